// SPDX-License-Identifier: Apache-2.0
// The step runs only the stages the scene calls for, and leaving a stage out changes
// nothing: a scene without gravity or damping gives the same motion as one where both are
// present with zero values.
#include "test_util.hpp"

using namespace mica;

namespace {

struct Scene {
  World world;
  Id body;
};

// A block fixed at x = 0 and set spinning and stretching by its initial velocity.
void build(Scene& s, bool corotational) {
  BodySettings bs;
  bs.material = {5e4, 0.35, 1000};
  bs.model = corotational ? ElasticModel::Corotational : ElasticModel::Linear;
  s.body = s.world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.4, 0.2, 0.2), {6, 3, 3}, 6), bs, Vec3::Zero(),
                            Vec3::Zero());
  Body& b = s.world.body(s.body);
  std::vector<int32_t> root;
  for (int32_t i = 0; i < b.fem.node_count(); ++i) {
    const Vec3& p = b.fem.rest[i];
    if (p.x() < 1e-9) root.push_back(i);
    else b.v[i] = Vec3(0.5 * p.x(), -p.z(), p.y());
  }
  s.world.add_lpc(s.body, root, LpcSpec{});
}

WorldSettings settings(bool plan_all) {
  WorldSettings ws;
  ws.solver = SolverKind::Direct;  // the exact solver: one factorization per new system
  ws.gravity = Vec3::Zero();
  ws.plan_all_stages = plan_all;
  return ws;
}

}  // namespace

static void test_absent_effects_are_not_run_and_change_nothing(void**) {
  for (bool corot : {true, false}) {
    Scene lean{World(settings(false)), 0}, full{World(settings(true)), 0};
    build(lean, corot);
    build(full, corot);
    for (int k = 0; k < 40; ++k) {
      lean.world.step(0.01);
      full.world.step(0.01);
    }
    const WorldStats& ls = lean.world.stats();
    const WorldStats& fs = full.world.stats();
    assert_int_equal(ls.stages[size_t(Stage::Loads)].runs_total, 0);
    assert_int_equal(ls.stages[size_t(Stage::Damping)].runs_total, 0);
    assert_int_equal(fs.stages[size_t(Stage::Loads)].runs_total, 40);
    assert_int_equal(fs.stages[size_t(Stage::Damping)].runs_total, 40);
    assert_int_equal(ls.stages[size_t(Stage::Rotations)].runs_total, corot ? 40 : 0);
    assert_int_equal(ls.stages[size_t(Stage::Solve)].runs_total, 40);
    const Body& a = lean.world.body(lean.body);
    const Body& b = full.world.body(full.body);
    double moved = 0, diff = 0;
    for (size_t i = 0; i < a.x.size(); ++i) {
      moved = std::max(moved, (a.x[i] - a.fem.rest[i]).norm());
      diff = std::max(diff, (a.x[i] - b.x[i]).norm() + (a.v[i] - b.v[i]).norm());
    }
    assert_true(moved > 1e-3);  // the bodies really moved
    assert_le(diff, 1e-12);
  }
}

static void test_present_effects_enter_the_plan(void**) {
  Scene s{World(settings(false)), 0};
  build(s, true);
  Plan p = s.world.plan();
  assert_false(p.loads);
  assert_false(p.damping);
  assert_true(p.constraints && p.rotations && p.solve);
  s.world.set_gravity(Vec3(0, 0, -9.81));
  assert_true(s.world.plan().loads);
  s.world.set_gravity(Vec3::Zero());
  s.world.set_node_forces(s.body, {3}, {Vec3(0, 0, 1)});
  assert_true(s.world.plan().loads);
  s.world.set_node_forces(s.body, {3}, {Vec3::Zero()});
  assert_false(s.world.plan().loads);

  BodySettings damped;
  damped.rayleigh_beta = 0.01;
  s.world.add_body(make_box_grid(Vec3(1, 0, 0), Vec3(1.2, 0.2, 0.2), {1, 1, 1}, 5), damped, Vec3::Zero(),
                   Vec3::Zero());
  assert_true(s.world.plan().damping);
}

static void test_static_bodies_are_not_integrated(void**) {
  World world(WorldSettings{});
  BodySettings fixed;
  fixed.is_static = true;
  world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}, 5), fixed, Vec3::Zero(), Vec3::Zero());
  assert_false(world.plan().solve);
  world.step(0.01);
  assert_int_equal(world.stats().stages[size_t(Stage::Solve)].runs_total, 0);
  assert_int_equal(world.stats().stages[size_t(Stage::Elements)].runs_total, 0);
}

static void test_linear_body_factors_once_corotational_every_step(void**) {
  for (bool corot : {false, true}) {
    Scene s{World(settings(false)), 0};
    build(s, corot);
    for (int k = 0; k < 10; ++k) s.world.step(0.01);
    assert_int_equal(s.world.factorizations(s.body), corot ? 10 : 1);
    s.world.step(0.02);  // a new time step changes A: the linear body factors again
    assert_int_equal(s.world.factorizations(s.body), corot ? 11 : 2);
  }
}

// Removing the only tool drops the Collide stage; what the tool left behind must go with it: no
// step may touch the removed tool (a use-after-free under AddressSanitizer), and no solver may keep
// subtracting the last contact impulse in a constraint's reaction. The three solvers agree while
// the tool presses (tight tolerance, frictionless), so they must agree after it is gone too.
static void test_removed_tool_leaves_nothing_behind(void**) {
  std::vector<Vec3> during, after;
  for (SolverKind solver : {SolverKind::Direct, SolverKind::Mica, SolverKind::Pcg}) {
    WorldSettings ws;
    ws.gravity = Vec3::Zero();
    ws.solver = solver;
    ws.mica_sweep = MicaSweep::GaussSeidel;  // MICA: the paper's sweep
    ws.tolerance = 1e-12;
    ws.max_iterations = 100000;
    World w(ws);
    BodySettings bs;
    bs.material = {2e4, 0.3, 1000};
    const Id b = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {4, 4, 4}, 6), bs, Vec3::Zero(),
                            Vec3::Zero());
    std::vector<int32_t> bottom, top;
    for (int32_t i = 0; i < w.body(b).fem.node_count(); ++i) {
      const double y = w.body(b).fem.rest[i].y();
      if (y < 1e-9) bottom.push_back(i);
      if (y > 0.1 - 1e-9) top.push_back(i);
    }
    w.add_lpc(b, bottom, LpcSpec{});
    LpcSpec slide;
    slide.kind = LpcKind::Plane;
    slide.directions[0] = Vec3(1, 1, 0).normalized();  // held along a tilted direction: contact rows stay servable
    const Id top_lpc = w.add_lpc(b, top, slide);
    Tool t;
    t.radius = 0.03;
    t.margin = 2e-3;
    t.position = Vec3(0.05, 0.126, 0.05);
    const Id tool = w.add_tool(t);
    for (int k = 0; k < 5; ++k) w.step(0.01);
    during.push_back(w.lpc(top_lpc).reaction);
    w.remove_tool(tool);
    for (int k = 0; k < 3; ++k) w.step(0.01);
    after.push_back(w.lpc(top_lpc).reaction);
  }
  assert_true(during[0].norm() > 0.1);  // the sphere did load the held face
  for (size_t k = 1; k < during.size(); ++k) {
    assert_true((during[k] - during[0]).norm() < 1e-6 * during[0].norm());
    assert_true((after[k] - after[0]).norm() < 1e-6 * during[0].norm());
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_absent_effects_are_not_run_and_change_nothing),
      cmocka_unit_test(test_present_effects_enter_the_plan),
      cmocka_unit_test(test_static_bodies_are_not_integrated),
      cmocka_unit_test(test_linear_body_factors_once_corotational_every_step),
      cmocka_unit_test(test_removed_tool_leaves_nothing_behind),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
