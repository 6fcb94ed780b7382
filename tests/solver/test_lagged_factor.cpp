// SPDX-License-Identifier: Apache-2.0
// The factored sweep with a factor refreshed in the background (LaggedFactor): results do not
// depend on when the worker finishes (lockstep adoption), a refreshed factor keeps a turning body
// to fewer iterations than the first step's, a changed constraint set refactors at once, and a
// solve that drags on refactors the current system; the half columns a refresh makes in the
// background are those the step would make.
#include <chrono>
#include <cstring>
#include <thread>

#include "solver/lagged_factor.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

struct Twist {
  std::unique_ptr<World> world;
  Id body = 0, tool = 0, top = 0;
  std::vector<int32_t> top_nodes;
  int64_t iterations = 0;
};

// A soft cube, base fixed, its top dragged sideways (the elements turn) while a sphere presses its
// side: rotations and contact in every step.
Twist make_twist(int32_t refactor, int32_t refactor_after = 100) {
  WorldSettings ws;
  ws.solver = SolverKind::Mica;
  ws.mica_sweep = MicaSweep::Factored;
  ws.refactor_interval = refactor;
  ws.refactor_after = refactor_after;
  ws.tolerance = 1e-8;
  ws.max_iterations = 100000;
  ws.gravity = Vec3::Zero();
  Twist t;
  t.world = std::make_unique<World>(ws);
  BodySettings bs;
  bs.material = {5e3, 0.3, 1000};
  t.body = t.world->add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {6, 6, 6}, 6), bs, Vec3::Zero(),
                             Vec3::Zero());
  std::vector<int32_t> base, top;
  const Body& b = t.world->body(t.body);
  for (int32_t i = 0; i < b.fem.node_count(); ++i) {
    if (b.fem.rest[i].y() < 1e-9) base.push_back(i);
    if (b.fem.rest[i].y() > 0.1 - 1e-9) top.push_back(i);
  }
  t.world->add_lpc(t.body, base, LpcSpec{});
  LpcSpec drag;
  drag.velocity = Vec3(0.3, 0, 0);
  t.top = t.world->add_lpc(t.body, top, drag);
  t.top_nodes = top;
  Tool sphere;
  sphere.radius = 0.02;
  sphere.margin = 0.001;
  sphere.position = Vec3(0.05, 0.05, 0.1 + 0.02 - 0.004);
  t.tool = t.world->add_tool(sphere);
  return t;
}

void step(Twist& t) {
  t.world->step(0.01);
  assert_true(t.world->stats().converged);
  t.iterations += t.world->stats().solver_iterations;
}

}  // namespace

// Two worlds, one stepped at once and one after a pause each step (its worker always finishes
// before the factor is due): identical results bit for bit, including across a constraint change.
static void test_results_do_not_depend_on_timing(void**) {
  Twist fast = make_twist(3), slow = make_twist(3);
  for (int k = 0; k < 24; ++k) {
    if (k == 12) {  // the top is held where it is: a new constraint set, refactored at once
      for (Twist* t : {&fast, &slow}) {
        t->world->remove_lpc(t->top);
        t->top = t->world->add_lpc(t->body, t->top_nodes, LpcSpec{});
      }
    }
    step(fast);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    step(slow);
    const Vec3List& a = fast.world->body(fast.body).v;
    const Vec3List& b = slow.world->body(slow.body).v;
    assert_int_equal(a.size(), b.size());
    assert_memory_equal(a.data(), b.data(), a.size() * sizeof(Vec3));
  }
  const int64_t n = fast.world->factorizations(fast.body);
  print_message("24 steps, refresh every 3 solves: %lld factorizations, %lld iterations\n", (long long)n,
                (long long)fast.iterations);
  assert_true(n >= 24 / 3);  // refreshed in the background (and once more at the constraint change)
  assert_int_equal(fast.iterations, slow.iterations);
}

// The refreshed factor follows the turning elements: fewer iterations than the first step's
// factor warped by the node rotations, on the same steps.
static void test_refresh_saves_iterations(void**) {
  Twist frozen = make_twist(0), refreshed = make_twist(2);
  for (int k = 0; k < 20; ++k) {
    step(frozen);
    step(refreshed);
  }
  print_message("20 steps: %lld iterations with the first step's factor, %lld refreshed every 2 solves\n",
                (long long)frozen.iterations, (long long)refreshed.iterations);
  assert_int_equal(frozen.world->factorizations(frozen.body), 1);
  assert_true(refreshed.iterations < frozen.iterations);
}

// A solve that drags on refactors the current system and then ends within a few iterations.
static void test_long_solve_refactors(void**) {
  // (The step's own solves take up to 7 iterations here: refactoring after 5 is a solve dragging on.)
  constexpr int32_t kAfter = 5;
  Twist never = make_twist(0, 0), soon = make_twist(0, kAfter);
  int32_t worst = 0;
  for (int k = 0; k < 20; ++k) {
    step(never);
    step(soon);
    worst = std::max(worst, soon.world->stats().solver_iterations);
    const Vec3List& a = never.world->body(never.body).v;
    const Vec3List& b = soon.world->body(soon.body).v;
    double diff = 0, size = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      diff = std::max(diff, (a[i] - b[i]).norm());
      size = std::max(size, a[i].norm());
    }
    assert_true(diff <= 1e-6 * size);  // both converged to 1e-8 on the same step
  }
  const int64_t n = soon.world->factorizations(soon.body);
  print_message("20 steps: %lld iterations never refactoring, %lld refactoring after %d (%lld factorizations, "
                "at most %d iterations in a step)\n",
                (long long)never.iterations, (long long)soon.iterations, kAfter, (long long)n, worst);
  assert_int_equal(never.world->factorizations(never.body), 1);
  assert_true(n > 1);
  assert_true(soon.iterations < never.iterations);
}

// A step undone (begin, update, rollback) leaves the factor as it was, down to what a saved state
// holds: here the step adopts the refreshed factor and stages the next refresh in the slot it
// freed (before the fix, that slot's copy of its system was overwritten, and a state saved after
// the undone step held another system than the one its factor was made from).
static void test_rollback_leaves_the_saved_factor(void**) {
  Twist t = make_twist(1);
  for (int k = 0; k < 3; ++k) step(t);
  const Body& b = t.world->body(t.body);
  const LaggedFactor::Key key{SystemKey{0.01, 0, 0}, 0};
  LaggedFactor factor;
  factor.update(b.fem, key, b.A, b.projection, &b.rotations(), nullptr, 1);  // factors now, then refreshes every step
  step(t);
  factor.update(b.fem, key, b.A, b.projection, &b.rotations(), nullptr, 1);  // launches a refresh
  step(t);
  ByteWriter before;
  factor.save(before);
  BlockValues other = b.A;
  for (Mat3& block : other) block *= 1.5;  // another system, to tell the copies apart
  factor.begin();
  factor.update(b.fem, key, other, b.projection, &b.rotations(), nullptr, 1);  // adopts, and stages the next refresh
  factor.rollback();
  ByteWriter after;
  factor.save(after);
  assert_true(before.bytes() == after.bytes());
}

// The half columns a background refresh makes (after its factorization, on the worker) are the
// same bits as those the stepping thread makes after adoption: two factors updated alike, one
// with the worker's columns turned off, the other given time to make them all (each launch
// follows an adoption here, before the solve makes its columns: the nodes of the factor
// replaced are asked for too, else the worker would be asked for none).
static void test_background_columns_are_the_same_bits(void**) {
  Twist t = make_twist(1);
  step(t);
  const Body& b = t.world->body(t.body);
  const LaggedFactor::Key key{SystemKey{0.01, 0, 0}, 0};
  LaggedFactor worker, stepper;
  stepper.set_background_columns(false);
  std::vector<Mat3> node_rotation;
  for (int k = 0; k < 6; ++k) {
    compute_node_rotations(b.fem, b.rotations(), node_rotation);
    for (LaggedFactor* f : {&worker, &stepper}) {
      f->update(b.fem, key, b.A, b.projection, &node_rotation, nullptr, 1);  // refreshes every solve
      f->prepare_columns(t.top_nodes);
    }
    worker.wait_for_worker();  // it makes all its columns
    step(t);
  }
  print_message("6 solves: %lld factorizations each, %lld columns taken from the worker\n",
                (long long)worker.factorizations(), (long long)worker.columns_from_worker());
  assert_int_equal(worker.factorizations(), stepper.factorizations());
  // Factored at once, then each later solve adopts a refresh with all the nodes' columns.
  assert_int_equal(worker.columns_from_worker(), 4 * int64_t(t.top_nodes.size()));
  assert_int_equal(stepper.columns_from_worker(), 0);
  for (int32_t node : t.top_nodes) {
    const SupernodalSolve::HalfColumns &a = worker.columns(node), &s = stepper.columns(node);
    assert_true(a.start == s.start && a.length == s.length);
    assert_int_equal(a.values.size(), s.values.size());
    assert_memory_equal(a.values.data(), s.values.data(), size_t(a.values.size()) * sizeof(double));
  }
}

// A state saved by the first 0.6 builds ends with dense cached columns (count, then per node its
// index, 3n and 3n x 3 doubles) where a state now ends with the count 0: it still loads (the
// columns read past, the factor the same: it saves the same bytes again), and one whose columns
// do not fit the body is refused as corrupt.
static void test_loads_a_state_with_dense_columns(void**) {
  Twist t = make_twist(1);
  step(t);
  const Body& b = t.world->body(t.body);
  std::vector<Mat3> node_rotation;
  compute_node_rotations(b.fem, b.rotations(), node_rotation);
  LaggedFactor factor;
  factor.update(b.fem, LaggedFactor::Key{SystemKey{0.01, 0, 0}, 0}, b.A, b.projection, &node_rotation, nullptr, 0);
  ByteWriter now;
  factor.save(now);
  const int64_t n = b.fem.node_count();
  auto with_columns = [&](int64_t rows) {
    ByteWriter old;
    // Up to the count: a state of 0.8 ends there (since 0.9 the factor's element
    // rotations, none here, its double and pattern flags and the bridge's follow).
    ByteWriter since_09;
    since_09.put_vector(std::vector<Mat3>{});
    since_09.put(uint8_t(0));  // the double factor not kept
    since_09.put(uint8_t(0));
    since_09.put(uint8_t(0));
    old.put_bytes(now.bytes().data(), now.bytes().size() - sizeof(uint64_t) - since_09.bytes().size());
    old.put(uint64_t(1));
    old.put(int32_t(2));
    old.put(rows);
    const std::vector<double> columns(size_t(rows) * 3, 0.25);
    old.put_bytes(columns.data(), columns.size() * sizeof(double));
    return old.bytes();
  };
  const std::vector<uint8_t> fits = with_columns(3 * n), corrupt = with_columns(3 * n - 3);
  LaggedFactor loaded;
  ByteReader in(fits.data(), fits.size());
  loaded.load(in, b.fem);
  assert_int_equal(in.remaining(), 0);
  ByteWriter again;
  loaded.save(again);
  assert_true(again.bytes() == now.bytes());
  LaggedFactor refused;
  ByteReader bad(corrupt.data(), corrupt.size());
  try {
    refused.load(bad, b.fem);
    fail_msg("a state whose columns do not fit its body was loaded");
  } catch (const Error& e) {
    assert_true(e.code() == Errc::Parse);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rollback_leaves_the_saved_factor),
      cmocka_unit_test(test_results_do_not_depend_on_timing),
      cmocka_unit_test(test_refresh_saves_iterations),
      cmocka_unit_test(test_long_solve_refactors),
      cmocka_unit_test(test_loads_a_state_with_dense_columns),
      cmocka_unit_test(test_background_columns_are_the_same_bits),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
