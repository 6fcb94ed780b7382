// SPDX-License-Identifier: Apache-2.0
// Fast tools: a tool pressed in at speed is made way for at its speed (its own approach is not
// penetration to recover slowly), and a tool driven through a thin slab in one step pushes the
// slab ahead instead of passing through it; a tool turned about itself feels what it did.
#include "test_util.hpp"

using namespace mica;

namespace {

WorldSettings settings() {
  WorldSettings ws;
  ws.solver = SolverKind::Mica;
  ws.mica_sweep = MicaSweep::GaussSeidel;  // the paper's sweep
  ws.tolerance = 1e-8;
  ws.max_iterations = 20000;
  ws.gravity = Vec3::Zero();
  return ws;
}

Id add_sphere(World& w, const Vec3& at, double radius) {
  Tool t;
  t.radius = radius;
  t.margin = 1e-3;
  t.position = at;
  return w.add_tool(t);
}

// The deepest surface node inside the sphere.
double penetration(const Body& b, const Tool& t) {
  double deepest = 0;
  for (int32_t i : b.surface_node_list) deepest = std::max(deepest, t.radius - (b.x[i] - t.position).norm());
  return deepest;
}

std::vector<int32_t> nodes_where(const Body& b, bool (*pred)(const Vec3&)) {
  std::vector<int32_t> found;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (pred(b.fem.rest[i])) found.push_back(i);
  return found;
}

}  // namespace

// A 1 cm sphere pressed 2 cm into a soft block at 2 m/s, 2 mm a step: every step ends with the
// surface on the sphere. (With the tool's approach clamped to max_recovery_speed, 1 m/s, the
// nodes fell 1 mm further behind every step.)
static void test_tool_pressed_at_speed_is_made_way_for(void**) {
  World w(settings());
  BodySettings soft;
  soft.material = {1e4, 0.3, 1000};
  const Id block = w.add_body(make_box_grid(Vec3(-0.05, -0.05, -0.05), Vec3(0.05, 0, 0.05), {10, 5, 10}, 5), soft,
                              Vec3::Zero(), Vec3::Zero());
  w.add_lpc(block, nodes_where(w.body(block), [](const Vec3& p) { return p.y() < -0.05 + 1e-9; }), LpcSpec{});
  const double r = 0.01, h = 1e-3, speed = 2.0;
  const Vec3 start(0.002, r + 0.0005, 0.003);
  const Id tool = add_sphere(w, start, r);
  double worst = 0;
  for (int k = 1; k <= 10; ++k) {
    w.set_tool_pose(tool, start - Vec3(0, speed * h * k, 0), Eigen::Quaterniond::Identity());
    w.step(h);
    assert_true(w.stats().converged);
    worst = std::max(worst, penetration(w.body(block), w.tool(tool)));
  }
  print_message("pressed 2 cm at %g m/s: deepest node %.3g m inside the sphere\n", speed, worst);
  assert_true(w.tool(tool).force.y() > 0);
  assert_le(worst, 1e-5);
}

// The stress scenario h at h = 10 ms: the sphere is moved 4.2 cm down in one step, from 2 mm above
// a 4 mm slab (rim fixed) to 2.6 cm below it, then held. The slab is pushed ahead of it: no node
// that was under it ends behind its centre in its shadow, none is inside it.
static void test_tool_through_thin_slab_in_one_step_pushes_it_ahead(void**) {
  World w(settings());
  BodySettings soft;
  soft.material = {1e4, 0.3, 1000};
  const Id slab = w.add_body(make_box_grid(Vec3(-0.05, -0.004, -0.05), Vec3(0.05, 0, 0.05), {10, 1, 10}, 5), soft,
                             Vec3::Zero(), Vec3::Zero());
  const Body& b = w.body(slab);
  w.add_lpc(slab, nodes_where(b, [](const Vec3& p) { return std::fabs(p.x()) > 0.05 - 1e-9 || std::fabs(p.z()) > 0.05 - 1e-9; }),
            LpcSpec{});
  const double r = 0.01, h = 0.01;
  const Vec3 start(0.003, 0.002 + r, 0.002), end = start - Vec3(0, 0.042, 0);
  const Id tool = add_sphere(w, start, r);
  w.set_tool_pose(tool, end, Eigen::Quaterniond::Identity());
  double lowest_under = HUGE_VAL;
  for (int k = 0; k < 5; ++k) {
    w.step(h);
    assert_true(w.stats().converged);
    for (int32_t i : b.surface_node_list) {
      const Vec3 d = b.x[i] - end;
      if (std::hypot(d.x(), d.z()) < r) {
        if (d.y() > 0) fail_msg("step %d: node %d is behind the sphere, %.3g m above its centre", k, i, d.y());
        lowest_under = std::min(lowest_under, d.y());
      }
    }
    assert_le(penetration(b, w.tool(tool)), 1e-3 * r);
  }
  print_message("nodes in the sphere's shadow are %.3g m or more below its centre\n", -lowest_under);
  assert_true(w.tool(tool).force.y() > 0);  // the stretched slab pulls the sphere back up
}

// A tool turned about itself in one step, as a Touch whose reading flips does: a sphere turned
// about its centre, and a capsule about its own axis, look the same, so the force of that step
// is the force of a twin world's tool that did not turn (a sphere's bit for bit; a turned
// capsule's ends move by an ulp, which the solver's tolerance of 1e-8 carries to 1e-7 of the force). (The contacts were swept
// along each node's arc: a sphere turned 90 deg pushed 5.5 N sideways, 150 deg pulled 10.5 N
// into the tissue, 170 deg 57 N.)
static void test_tool_turned_about_itself_feels_the_same(void**) {
  struct Case {
    const char* name;
    ToolShape shape;
    Vec3 axis;  // of the turn, in the tool's frame
  };
  const Case cases[] = {{"sphere", ToolShape::Sphere, Vec3(1, 0, 0)},
                        {"sphere", ToolShape::Sphere, Vec3(0.3, 0.9, -0.2).normalized()},
                        {"capsule", ToolShape::Capsule, Vec3::UnitZ()}};
  for (const Case& c : cases)
    for (double degrees : {30.0, 90.0, 150.0, 170.0, 180.0}) {
      World still(settings()), turned(settings());
      Id tools[2];
      int k = 0;
      for (World* w : {&still, &turned}) {
        BodySettings soft;
        soft.material = {1e4, 0.3, 1000};
        const Id block = w->add_body(make_box_grid(Vec3(-0.05, -0.05, -0.05), Vec3(0.05, 0, 0.05), {8, 4, 8}, 5), soft,
                                     Vec3::Zero(), Vec3::Zero());
        w->add_lpc(block, nodes_where(w->body(block), [](const Vec3& p) { return p.y() < -0.05 + 1e-9; }), LpcSpec{});
        Tool t;
        t.shape = c.shape;
        t.radius = 0.008;
        t.half_length = 0.01;
        t.margin = 1e-3;
        t.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()));  // a capsule lies along x
        t.position = Vec3(0.002, t.radius + 0.001, 0.003);
        t.previous_position = t.position;
        t.previous_orientation = t.orientation;
        tools[k] = w->add_tool(t);
        for (int step = 1; step <= 10; ++step) {  // pressed 3 mm and held
          w->set_tool_pose(tools[k], t.position - Vec3(0, 0.0004 * step, 0), t.orientation);
          w->step(0.01);
        }
        ++k;
      }
      const Tool& before = turned.tool(tools[1]);
      const Eigen::Quaterniond spun = before.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(degrees * M_PI / 180, c.axis));
      turned.set_tool_pose(tools[1], before.position, spun);
      still.step(0.01);
      turned.step(0.01);
      const Vec3 f0 = still.tool(tools[0]).force, f1 = turned.tool(tools[1]).force;
      if (!((f1 - f0).norm() <= 1e-6 * f0.norm()))
        fail_msg("%s turned %.0f deg: force (%.4g, %.4g, %.4g) N, unturned (%.4g, %.4g, %.4g) N", c.name, degrees, f1.x(),
                 f1.y(), f1.z(), f0.x(), f0.y(), f0.z());
      assert_true(f0.y() > 0.1);
    }
  print_message("a sphere turned 30-180 deg about its centre and a capsule about its axis: the unturned force\n");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tool_pressed_at_speed_is_made_way_for),
      cmocka_unit_test(test_tool_through_thin_slab_in_one_step_pushes_it_ahead),
      cmocka_unit_test(test_tool_turned_about_itself_feels_the_same),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
