// SPDX-License-Identifier: Apache-2.0
// WorldSettings::threads: a world stepped on 2 (or 3) threads against the same world on one,
// side by side. MICA's sweep runs in colour order on more than one thread (its iterates differ,
// its fixed point does not), so velocities and impulses agree within the solver tolerance; the
// direct and PCG solvers see only the parallel assembly (round-off). Above one thread the
// count does not matter: 2 and 3 threads agree bit for bit. Labelled `threads`: CI runs
// it under ThreadSanitizer.
#include "test_util.hpp"

using namespace mica;

namespace {

struct SceneSpec {
  SolverKind solver = SolverKind::Mica;
  bool tool = false;
  double friction = 0;
  bool grasp = false;      // drag the x = 0.1 face
  bool slide_top = false;  // top face held in its plane
  bool second_body = false;  // a soft block resting on the cube (contact between bodies)
  Vec3 gravity = Vec3::Zero();
};

struct Scene {
  World world;
  Id body = 0, tool = 0, other = 0;
};

WorldSettings settings(const SceneSpec& spec, int32_t threads) {
  WorldSettings ws;
  ws.solver = spec.solver;
  ws.mica_sweep = MicaSweep::GaussSeidel;  // MICA: the colour-ordered Gauss-Seidel sweep is what threads change
  ws.tolerance = 1e-10;
  ws.max_iterations = 100000;
  ws.gravity = spec.gravity;
  ws.threads = threads;
  return ws;
}

std::vector<int32_t> nodes_where(const Body& b, bool (*pred)(const Vec3&)) {
  std::vector<int32_t> found;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (pred(b.fem.rest[i])) found.push_back(i);
  return found;
}

// A 0.1 m cube (5^3 cells x 6 tets) fixed at its bottom face.
void build(Scene& s, const SceneSpec& spec) {
  BodySettings bs;
  bs.material = {2e4, 0.3, 1000};
  bs.rayleigh_alpha = 1;
  s.body = s.world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {5, 5, 5}, 6), bs, Vec3::Zero(),
                            Vec3::Zero());
  const Body& b = s.world.body(s.body);
  s.world.add_lpc(s.body, nodes_where(b, [](const Vec3& p) { return p.y() < 1e-9; }), LpcSpec{});
  if (spec.grasp) {
    LpcSpec drag;
    drag.velocity = Vec3(0, 0.02, 0.05);
    s.world.add_lpc(s.body, nodes_where(b, [](const Vec3& p) { return p.x() > 0.1 - 1e-9 && p.y() > 1e-9; }), drag);
  }
  if (spec.slide_top) {
    LpcSpec plane;
    plane.kind = LpcKind::Plane;
    plane.directions[0] = Vec3(1, 1, 0).normalized();
    s.world.add_lpc(s.body, nodes_where(b, [](const Vec3& p) { return p.y() > 0.1 - 1e-9 && p.x() < 0.1 - 1e-9; }),
                    plane);
  }
  if (spec.tool) {
    Tool t;
    t.radius = 0.03;
    t.margin = 0.002;
    t.friction = spec.friction;
    t.position = Vec3(0.05, 0.1 + 0.03 - 0.003, 0.05);
    s.tool = s.world.add_tool(t);
  }
  if (spec.second_body) {
    BodySettings soft;
    soft.material = {2e4, 0.3, 1000};
    // Off the lower body's grid: a node right above an edge of its surface is a tie between two
    // triangles that round-off decides, and the two worlds would build different contact sets.
    s.other = s.world.add_body(make_box_grid(Vec3(0.0213, 0.1005, 0.0161), Vec3(0.0813, 0.1305, 0.0761), {3, 2, 3}, 6),
                               soft, Vec3::Zero(), Vec3::Zero());
    LpcSpec push;
    push.velocity = Vec3(0, -0.1, 0);
    s.world.add_lpc(s.other, nodes_where(s.world.body(s.other), [](const Vec3& p) { return p.y() > 0.1305 - 1e-9; }),
                    push);
  }
}

double max_norm(const Vec3List& a) {
  double m = 0;
  for (const Vec3& v : a) m = std::max(m, v.norm());
  return m;
}

double relative_difference(const Vec3List& a, const Vec3List& b) {
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, (a[i] - b[i]).norm());
  return d / std::max(max_norm(b), 1e-12);
}

// Steps the scene on `threads` and on one thread side by side; checks velocities, positions and
// impulses every step, relative to their size.
void compare_threads(const SceneSpec& spec, int32_t threads, int steps, double rel_tol) {
  const double h = 0.01;
  Scene many{World(settings(spec, threads))}, one{World(settings(spec, 1))};
  assert_int_equal(many.world.thread_count(), threads);
  assert_int_equal(one.world.thread_count(), 1);
  build(many, spec);
  build(one, spec);
  double worst_v = 0, worst_x = 0, worst_l = 0;
  int active = 0;
  int64_t iterations_many = 0, iterations_one = 0;
  for (int k = 0; k < steps; ++k) {
    if (spec.tool) {
      const Vec3 p = one.world.tool(one.tool).position + h * Vec3(0.05, -0.2, 0);
      many.world.set_tool_pose(many.tool, p, Eigen::Quaterniond::Identity());
      one.world.set_tool_pose(one.tool, p, Eigen::Quaterniond::Identity());
    }
    many.world.step(h);
    one.world.step(h);
    assert_true(many.world.stats().converged);
    assert_true(one.world.stats().converged);
    iterations_many += many.world.stats().solver_iterations;
    iterations_one += one.world.stats().solver_iterations;
    for (Id id : {many.body, many.other}) {
      if (!id) continue;
      worst_v = std::max(worst_v, relative_difference(many.world.body(id).v, one.world.body(id).v));
      Vec3List um = many.world.body(id).x, uo = one.world.body(id).x;
      for (size_t i = 0; i < um.size(); ++i) {
        um[i] -= many.world.body(id).fem.rest[i];
        uo[i] -= one.world.body(id).fem.rest[i];
      }
      worst_x = std::max(worst_x, relative_difference(um, uo));
    }
    const auto& lm = many.world.impulses();
    const auto& lo = one.world.impulses();
    assert_int_equal(lm.size(), lo.size());
    double lmax = 0, ldiff = 0;
    for (size_t r = 0; r < lm.size(); ++r) {
      lmax = std::max(lmax, std::fabs(lo[r]));
      ldiff = std::max(ldiff, std::fabs(lm[r] - lo[r]));
      active += (one.world.contact_rows().normal_of[r] < 0 && lo[r] > 0);
    }
    if (lmax > 0) worst_l = std::max(worst_l, ldiff / lmax);
  }
  print_message("%d threads vs 1, %d steps: worst relative difference in v %.3g, in u %.3g, in lambda %.3g; "
                "%d active contact-steps; iterations %lld vs %lld\n",
                threads, steps, worst_v, worst_x, worst_l, active, (long long)iterations_many,
                (long long)iterations_one);
  if (spec.tool || spec.second_body) assert_true(active > 0);
  assert_le(worst_v, rel_tol);
  assert_le(worst_x, rel_tol);
  assert_le(worst_l, rel_tol);
}

}  // namespace

static void test_thread_count_setting(void**) {
  WorldSettings ws;
  assert_int_equal(ws.threads, 1);  // the serial path unless the host asks
  assert_int_equal(World(ws).thread_count(), 1);
  ws.threads = 0;
  assert_true(World(ws).thread_count() >= 1);
  ws.threads = 3;
  assert_int_equal(World(ws).thread_count(), 3);
  for (int32_t bad : {-1, kMaxThreads + 1}) {
    ws.threads = bad;
    bool refused = false;
    try {
      World w(ws);
    } catch (const Error& e) {
      refused = e.code() == Errc::InvalidArgument;
    }
    assert_true(refused);
  }
}

static void test_sphere_press_with_friction_on_two_threads(void**) {
  SceneSpec spec;
  spec.tool = true;
  spec.friction = 0.3;
  compare_threads(spec, 2, 10, 1e-6);
}

static void test_grasp_and_plane_constraints_on_two_threads(void**) {
  SceneSpec spec;
  spec.grasp = true;
  spec.slide_top = true;
  spec.gravity = Vec3(0, -9.81, 0);
  compare_threads(spec, 2, 10, 1e-6);
}

static void test_two_bodies_in_contact_on_two_threads(void**) {
  SceneSpec spec;
  spec.second_body = true;
  spec.gravity = Vec3(0, -9.81, 0);
  compare_threads(spec, 2, 8, 1e-6);
}

static void test_press_and_grasp_on_three_threads(void**) {
  SceneSpec spec;
  spec.tool = true;
  spec.grasp = true;
  compare_threads(spec, 3, 6, 1e-6);
}

// Chunks are cut independently of the thread count and summed in order: 2 and 3 threads give
// the same bits (and so does a rerun: no dependence on which thread took which chunk).
static void test_two_and_three_threads_agree_bit_for_bit(void**) {
  SceneSpec spec;
  spec.tool = true;
  spec.friction = 0.3;
  spec.grasp = true;
  spec.gravity = Vec3(0, -9.81, 0);
  Scene a{World(settings(spec, 2))}, b{World(settings(spec, 3))}, c{World(settings(spec, 2))};
  for (Scene* s : {&a, &b, &c}) build(*s, spec);
  for (int k = 0; k < 6; ++k) {
    for (Scene* s : {&a, &b, &c}) {
      const Vec3 p = s->world.tool(s->tool).position + 0.01 * Vec3(0.05, -0.2, 0);
      s->world.set_tool_pose(s->tool, p, Eigen::Quaterniond::Identity());
      s->world.step(0.01);
    }
    for (Scene* s : {&b, &c}) {
      assert_int_equal(s->world.stats().solver_iterations, a.world.stats().solver_iterations);
      assert_true(s->world.body(s->body).x == a.world.body(a.body).x);
      assert_true(s->world.body(s->body).v == a.world.body(a.body).v);
      assert_true(s->world.impulses() == a.world.impulses());
    }
  }
}

static void test_direct_and_pcg_see_only_round_off(void**) {
  for (SolverKind solver : {SolverKind::Direct, SolverKind::Pcg}) {
    SceneSpec spec;
    spec.solver = solver;
    spec.tool = true;
    spec.grasp = true;
    compare_threads(spec, 2, 5, 1e-7);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_thread_count_setting),
      cmocka_unit_test(test_sphere_press_with_friction_on_two_threads),
      cmocka_unit_test(test_grasp_and_plane_constraints_on_two_threads),
      cmocka_unit_test(test_two_bodies_in_contact_on_two_threads),
      cmocka_unit_test(test_press_and_grasp_on_three_threads),
      cmocka_unit_test(test_two_and_three_threads_agree_bit_for_bit),
      cmocka_unit_test(test_direct_and_pcg_see_only_round_off),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
