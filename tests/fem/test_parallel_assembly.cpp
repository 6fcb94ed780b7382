// SPDX-License-Identifier: Apache-2.0
// The step's parallel loops against the serial ones: the pool itself (every thread runs, the
// barrier orders), rotations bit for bit, assembly by element colours equal up to round-off
// (the sums run in colour order) and the same for every thread count above one; none of it
// allocates once warm.
#include "core/thread_pool.hpp"
#include "fem/element_colouring.hpp"
#include "fem/fem_model.hpp"
#include "haptics/alloc_counter.hpp"
#include "solver/mica_solver.hpp"
#include "solver/node_colouring.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// A 6x5x4 box (x 6 tets) deformed by a smooth map plus noise: every element rotated differently.
struct Deformed {
  TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(0.12, 0.1, 0.08), {6, 5, 4}, 6);
  FemModel model = build_fem_model(mesh, Material{2e4, 0.35, 1000}, MassKind::Consistent, "box");
  Vec3List x;
  Deformed() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> noise(-2e-3, 2e-3);
    for (const Vec3& p : model.rest) {
      const double a = 3 * p.x();
      x.push_back(Eigen::AngleAxisd(a, Vec3(0.3, 1, 0.2).normalized()) * p + Vec3(noise(rng), noise(rng), noise(rng)));
    }
  }
};

double max_diff(const BlockValues& a, const BlockValues& b) {
  double d = 0;
  for (size_t k = 0; k < a.size(); ++k) d = std::max(d, (a[k] - b[k]).cwiseAbs().maxCoeff());
  return d;
}
double max_diff(const Vec3List& a, const Vec3List& b) {
  double d = 0;
  for (size_t k = 0; k < a.size(); ++k) d = std::max(d, (a[k] - b[k]).cwiseAbs().maxCoeff());
  return d;
}

}  // namespace

// Phases in order: every item of phase p reads all of phase p - 1, which must be complete.
static void test_pool_phases_run_in_order(void**) {
  for (int32_t threads : {1, 2, 3, 4}) {
    ThreadPool pool(threads);
    assert_int_equal(pool.size(), threads);
    const int32_t phases = 6, width = 37;  // uneven: the last chunk of a phase is short
    std::vector<int32_t> start;
    for (int32_t p = 0; p <= phases; ++p) start.push_back(p * width);
    for (int32_t grain : {1, 5, 16, 100}) {
      for (int round = 0; round < 50; ++round) {
        std::vector<int64_t> value(size_t(phases * width), -1);
        std::vector<int> chunks_seen(size_t(ThreadPool::chunk_count(start.data(), phases, grain)), 0);
        auto f = [&](int32_t p, int32_t first, int32_t last, int32_t chunk) {
          ++chunks_seen[chunk];
          for (int32_t i = first; i < last; ++i) {
            int64_t sum = round;
            if (p > 0)
              for (int32_t j = start[p - 1]; j < start[p]; ++j) sum += value[j];
            value[i] = sum + 1;
          }
        };
        pool.phased_for(start.data(), phases, grain, f);
        int64_t expected = round + 1;  // phase 0
        for (int32_t p = 0; p < phases; ++p) {
          for (int32_t i = start[p]; i < start[p + 1]; ++i) assert_int_equal(value[i], expected);
          expected = round + width * expected + 1;
        }
        for (int c : chunks_seen) assert_int_equal(c, 1);
      }
    }
    // parallel_for covers [0, n) exactly once.
    std::vector<int> hits(1001, 0);
    parallel_for(&pool, 1001, 10, [&](int32_t first, int32_t last) {
      for (int32_t i = first; i < last; ++i) ++hits[i];
    });
    for (int h : hits) assert_int_equal(h, 1);
  }
  assert_true(ThreadPool::resolve(0) >= 1);
  assert_int_equal(ThreadPool::resolve(3), 3);
}

static void test_pool_sleeps_and_wakes(void**) {
  // Loops spaced by more than the spin time: the workers go to sleep, wake up (or come late,
  // and the caller does the work).
  ThreadPool pool(3);
  std::atomic<int> count{0};
  const int32_t start[2] = {0, 64};
  for (int k = 0; k < 5; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    auto f = [&](int32_t, int32_t first, int32_t last, int32_t) { count.fetch_add(last - first); };
    pool.phased_for(start, 1, 4, f);
  }
  assert_int_equal(count.load(), 5 * 64);
}

static void test_parallel_rotations_are_the_serial_ones(void**) {
  const Deformed d;
  std::vector<Mat3> serial(d.model.elements.size()), parallel(d.model.elements.size());
  compute_rotations(d.model, d.x, serial);
  ThreadPool pool(2);
  compute_rotations(d.model, d.x, parallel, &pool);
  for (size_t e = 0; e < serial.size(); ++e) assert_true(serial[e] == parallel[e]);  // bit for bit
}

static void test_parallel_assembly_matches_serial(void**) {
  const Deformed d;
  const size_t ne = d.model.elements.size(), nn = d.x.size(), nb = d.model.pattern.block_count();
  std::vector<Mat3> R(ne);
  compute_rotations(d.model, d.x, R);
  const Colouring colours = colour_elements(d.mesh.tets, d.model.node_count(), 16);
  assert_true(is_valid_element_colouring(d.mesh.tets, d.model.node_count(), colours));
  assert_true(colours.colours() > 1 && colours.blocks() > colours.colours());
  const double k_scale = 1e-4 + 1e-5;
  BlockValues A1(nb), A2(nb), A3(nb);
  Vec3List f1(nn), f2(nn), f3(nn);
  set_scaled_mass(d.model, 1.0, A1);
  assemble_elastic(d.model, d.x, &R, k_scale, &A1, f1);
  ThreadPool two(2), three(3);
  set_scaled_mass(d.model, 1.0, A2, &two);
  assemble_elastic(d.model, d.x, &R, k_scale, &A2, f2, &colours, &two);
  set_scaled_mass(d.model, 1.0, A3, &three);
  assemble_elastic(d.model, d.x, &R, k_scale, &A3, f3, &colours, &three);
  double a_scale = 0, f_scale = 0;
  for (const Mat3& a : A1) a_scale = std::max(a_scale, a.cwiseAbs().maxCoeff());
  for (const Vec3& f : f1) f_scale = std::max(f_scale, f.cwiseAbs().maxCoeff());
  print_message("A: max |serial - parallel| %.3g of %.3g; f_int: %.3g of %.3g\n", max_diff(A1, A2), a_scale,
                max_diff(f1, f2), f_scale);
  assert_le(max_diff(A1, A2), 1e-13 * a_scale);
  assert_le(max_diff(f1, f2), 1e-12 * f_scale);
  // The order is the colouring's: 2 and 3 threads agree bit for bit.
  assert_true(max_diff(A2, A3) == 0);
  assert_true(max_diff(f2, f3) == 0);
  // Forces only (a linear body keeping its matrix), linear model (no rotations).
  Vec3List g1(nn), g2(nn);
  assemble_elastic(d.model, d.x, nullptr, k_scale, nullptr, g1);
  assemble_elastic(d.model, d.x, nullptr, k_scale, nullptr, g2, &colours, &two);
  assert_le(max_diff(g1, g2), 1e-12 * f_scale);
}

// The step's parallel pieces, warm: rotations, assembly and the coloured MBGS sweep make no
// heap allocation on the stepping thread (nor does the pool hand any work that allocates).
static void test_parallel_step_pieces_do_not_allocate(void**) {
  const Deformed d;
  const FemModel& m = d.model;
  std::vector<Mat3> R(m.elements.size());
  BlockValues A(m.pattern.block_count());
  Vec3List f(d.x.size()), b(d.x.size(), Vec3(0, -1e-3, 0)), v(d.x.size(), Vec3::Zero());
  const Colouring elements = colour_elements(d.mesh.tets, m.node_count(), 16);
  const Colouring nodes = colour_nodes(m.pattern, 8);
  assert_true(is_valid_node_colouring(m.pattern, nodes));
  Projection projection;
  projection.reset(m.node_count());
  ContactRows rows;
  std::vector<double> lambda;
  SolverSettings ss;
  ss.max_iterations = 20;
  MicaSolver solver(ss);
  Vec3List impulse(d.x.size(), Vec3::Zero());
  std::vector<SolverBody> bodies(1);
  bodies[0].fem = &m;
  bodies[0].A = &A;
  bodies[0].b = &b;
  bodies[0].projection = &projection;
  bodies[0].v = &v;
  bodies[0].contact_impulse = &impulse;
  bodies[0].colours = &nodes;
  ThreadPool pool(2);
  SolveContext ctx;
  ctx.pool = &pool;
  auto step = [&] {
    compute_rotations(m, d.x, R, &pool);
    set_scaled_mass(m, 1.0, A, &pool);
    assemble_elastic(m, d.x, &R, 1e-4, &A, f, &elements, &pool);
    solver.solve(ctx, bodies, rows, lambda);
  };
  step();  // the first solve sizes the solver's buffers
  mica_test::start_counting_allocations();
  for (int k = 0; k < 3; ++k) step();
  assert_int_equal(mica_test::stop_counting_allocations(), 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_pool_phases_run_in_order),
      cmocka_unit_test(test_pool_sleeps_and_wakes),
      cmocka_unit_test(test_parallel_rotations_are_the_serial_ones),
      cmocka_unit_test(test_parallel_assembly_matches_serial),
      cmocka_unit_test(test_parallel_step_pieces_do_not_allocate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
