// Contact between bodies: a cube dropped on a static slab comes to rest carrying its weight,
// and two deformable bodies pressed together agree with the exact reference.
#include "test_util.hpp"

using namespace mica;

namespace {

WorldSettings settings(SolverKind solver) {
  WorldSettings ws;
  ws.solver = solver;
  ws.tolerance = 1e-10;
  ws.max_iterations = 100000;
  ws.gravity = Vec3(0, -9.81, 0);
  return ws;
}

std::vector<int32_t> nodes_where(const Body& b, int axis, double value) {
  std::vector<int32_t> found;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (std::fabs(b.fem.rest[i][axis] - value) < 1e-9) found.push_back(i);
  return found;
}

}  // namespace

static void test_cube_rests_on_a_static_slab(void**) {
  World world(settings(SolverKind::Mica));
  BodySettings slab;
  slab.is_static = true;
  world.add_body(make_box_grid(Vec3(-0.1, -0.05, -0.1), Vec3(0.2, 0, 0.2), {6, 1, 6}, 5), slab, Vec3::Zero(),
                 Vec3::Zero());
  BodySettings soft;
  soft.material = {5e4, 0.3, 1000};
  soft.rayleigh_alpha = 10;
  const Id cube = world.add_body(make_box_grid(Vec3(0, 0.01, 0), Vec3(0.1, 0.11, 0.1), {4, 4, 4}, 6), soft,
                                 Vec3::Zero(), Vec3::Zero());
  const Body& b = world.body(cube);
  double lowest = HUGE_VAL;
  for (int k = 0; k < 150; ++k) {
    world.step(0.01);
    assert_true(flat(b.x).allFinite());
    for (const Vec3& p : b.x) lowest = std::min(lowest, p.y());
  }
  // Resting: it never sank through (penetration bounded by a millimetre), it stopped, and the
  // slab carries its weight: the contact impulses over a step are m g h.
  assert_true(lowest > -1e-3);
  double vmax = 0;
  for (const Vec3& v : b.v) vmax = std::max(vmax, v.norm());
  assert_le(vmax, 1e-3);
  Vec3 support = Vec3::Zero();
  for (const Vec3& f : b.contact_impulse) support += f / 0.01;
  const double weight = b.fem.total_mass() * 9.81;
  print_message("slab carries %.4f N of a %.4f N weight; lowest point %.3g m; max speed %.2g m/s\n", support.y(),
                weight, lowest, vmax);
  assert_near(support.y(), weight, 1e-3 * weight);
}

// A soft cube on a fixed base, a second soft cube pushed down onto it by a grasp on its top
// face: MICA and the exact reference each take the step from the same state. (Run apart, they
// would drift: a node right above an edge is a tie between two triangles, and round-off picks
// either, so the two worlds would solve equally valid but different problems.)
static void test_two_bodies_pressed_together_match_reference(void**) {
  double worst_v = 0, worst_f = 0;
  World mica(settings(SolverKind::Mica)), exact(settings(SolverKind::Direct));
  Id upper[2], lowers[2];
  World* worlds[2] = {&mica, &exact};
  for (int w = 0; w < 2; ++w) {
    World& world = *worlds[w];
    BodySettings soft;
    soft.material = {2e4, 0.3, 1000};
    const Id lower = world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.05, 0.1), {4, 2, 4}, 6), soft,
                                    Vec3::Zero(), Vec3::Zero());
    world.add_lpc(lower, nodes_where(world.body(lower), 1, 0.0), LpcSpec{});
    lowers[w] = lower;
    upper[w] = world.add_body(make_box_grid(Vec3(0.02, 0.0505, 0.02), Vec3(0.08, 0.0905, 0.08), {3, 2, 3}, 6), soft,
                              Vec3::Zero(), Vec3::Zero());
    LpcSpec push;
    push.velocity = Vec3(0, -0.2, 0);
    world.add_lpc(upper[w], nodes_where(world.body(upper[w]), 1, 0.0905), push);
  }
  int contacts = 0;
  for (int k = 0; k < 10; ++k) {
    for (const Id* ids : {upper, lowers}) {
      exact.body(ids[1]).x = mica.body(ids[0]).x;
      exact.body(ids[1]).v = mica.body(ids[0]).v;
    }
    mica.step(0.01);
    exact.step(0.01);
    assert_true(mica.stats().converged);
    const Body& a = mica.body(upper[0]);
    const Body& e = exact.body(upper[1]);
    double vmax = 0, dv = 0;
    for (size_t i = 0; i < a.v.size(); ++i) {
      vmax = std::max(vmax, e.v[i].norm());
      dv = std::max(dv, (a.v[i] - e.v[i]).norm());
    }
    worst_v = std::max(worst_v, dv / vmax);
    double fmax = 0, df = 0;
    for (size_t i = 0; i < a.contact_impulse.size(); ++i) {
      fmax = std::max(fmax, e.contact_impulse[i].norm());
      df = std::max(df, (a.contact_impulse[i] - e.contact_impulse[i]).norm());
    }
    if (fmax > 0) worst_f = std::max(worst_f, df / fmax);
    for (double l : mica.impulses()) contacts += l > 0;
  }
  print_message("two bodies: %d active contact-steps, worst relative difference in v %.3g, in impulses %.3g\n",
                contacts, worst_v, worst_f);
  assert_true(contacts > 10);
  assert_le(worst_v, 1e-6);
  assert_le(worst_f, 1e-5);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_cube_rests_on_a_static_slab),
      cmocka_unit_test(test_two_bodies_pressed_together_match_reference),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
