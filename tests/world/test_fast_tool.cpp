// Fast tools: a tool pressed in at speed is made way for at its speed (its own approach is not
// penetration to recover slowly), and a tool driven through a thin slab in one step pushes the
// slab ahead instead of passing through it.
#include "test_util.hpp"

using namespace mica;

namespace {

WorldSettings settings() {
  WorldSettings ws;
  ws.solver = SolverKind::Mica;
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

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tool_pressed_at_speed_is_made_way_for),
      cmocka_unit_test(test_tool_through_thin_slab_in_one_step_pushes_it_ahead),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
