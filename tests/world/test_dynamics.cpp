// SPDX-License-Identifier: Apache-2.0
// Whole-body dynamics against analytic answers: a cantilever's static tip deflection
// (Euler-Bernoulli), energy that never grows without damping and decays with it, and the
// reactions of overlapping constraint groups that add up to the load they carry.
#include "test_util.hpp"

using namespace mica;

namespace {

std::vector<int32_t> nodes_where(const Body& b, double (*coord)(const Vec3&), double value) {
  std::vector<int32_t> found;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (std::fabs(coord(b.fem.rest[i]) - value) < 1e-9) found.push_back(i);
  return found;
}
double x_of(const Vec3& p) { return p.x(); }

double total_energy(const Body& b) {
  return kinetic_energy(b.fem, b.v) + elastic_energy(b.fem, b.x, b.settings.model);
}

}  // namespace

// Tip load P on a clamped beam: w = P L^3 / (3 E I). Linear tets are stiff in bending
// (locking), so the answer converges from below as the mesh is refined; shear adds ~1% at
// L/H = 10. Returns w / w_EB.
static double cantilever_ratio(int32_t nx, int32_t nyz) {
  const double L = 1.0, H = 0.1, E = 1e7, P = 1.0;
  WorldSettings ws;
  ws.solver = SolverKind::Direct;  // exact: the analytic answers hold to round-off
  ws.gravity = Vec3::Zero();
  World world(ws);
  BodySettings bs;
  bs.material = {E, 0.3, 100};
  bs.model = ElasticModel::Linear;
  const Id id = world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(L, H, H), {nx, nyz, nyz}, 5), bs, Vec3::Zero(),
                               Vec3::Zero());
  Body& beam = world.body(id);
  world.add_lpc(id, nodes_where(beam, x_of, 0.0), LpcSpec{});
  const auto tip = nodes_where(beam, x_of, L);
  world.set_node_forces(id, tip, Vec3List(tip.size(), Vec3(0, 0, -P / double(tip.size()))));
  // Large implicit steps are damped Newton iterations toward the static equilibrium.
  for (int k = 0; k < 30; ++k) world.step(1.0);
  double w = 0;
  for (int32_t i : tip) w -= beam.x[i].z() - beam.fem.rest[i].z();
  w /= double(tip.size());
  const double I = H * H * H * H / 12, w_eb = P * L * L * L / (3 * E * I);
  print_message("%dx%dx%d cells: tip deflection %.6g m, Euler-Bernoulli %.6g m, ratio %.4f\n", nx, nyz, nyz, w,
                w_eb, w / w_eb);
  // The linear body factored its matrix once for all 30 steps.
  assert_int_equal(world.factorizations(id), 1);
  return w / w_eb;
}

static void test_cantilever_matches_euler_bernoulli(void**) {
  const double coarse = cantilever_ratio(40, 4), fine = cantilever_ratio(80, 8);
  assert_near(fine, 1.0, 0.05);
  assert_true(coarse < fine);  // converging from below
}

// Backward Euler never creates energy: a plucked beam's energy is non-increasing without
// damping (linear model exactly; co-rotational within 1e-6), and Rayleigh damping takes
// it down much faster.
static double run_plucked_beam(bool corotational, double alpha, std::vector<double>& energy) {
  WorldSettings ws;
  ws.solver = SolverKind::Direct;  // exact: the analytic answers hold to round-off
  ws.gravity = Vec3::Zero();
  World world(ws);
  BodySettings bs;
  bs.material = {1e7, 0.3, 1000};  // first bending mode ~10 rad/s
  bs.model = corotational ? ElasticModel::Corotational : ElasticModel::Linear;
  bs.rayleigh_alpha = alpha;
  const Id id = world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(1, 0.1, 0.1), {20, 2, 2}, 6), bs, Vec3::Zero(),
                               Vec3::Zero());
  Body& beam = world.body(id);
  world.add_lpc(id, nodes_where(beam, x_of, 0.0), LpcSpec{});
  // Initial velocity growing along the beam: a pluck.
  for (int32_t i = 0; i < beam.fem.node_count(); ++i) beam.v[i] = Vec3(0, 0, 2.0 * beam.fem.rest[i].x());
  for (int32_t i : nodes_where(beam, x_of, 0.0)) beam.v[i].setZero();
  energy.push_back(total_energy(beam));
  for (int k = 0; k < 300; ++k) {
    world.step(0.005);
    energy.push_back(total_energy(beam));
    assert_true(flat(beam.x).allFinite());
  }
  return energy.back();
}

static void test_energy_never_grows_without_damping(void**) {
  for (bool corot : {false, true}) {
    std::vector<double> e;
    run_plucked_beam(corot, 0, e);
    const double slack = corot ? 1e-6 : 1e-12;
    for (size_t k = 1; k < e.size(); ++k) assert_le(e[k], e[k - 1] * (1 + slack));
    assert_true(e.back() > 0.05 * e.front());  // bounded, not collapsed: it still oscillates
  }
}

static void test_damping_decays_energy(void**) {
  std::vector<double> undamped, damped;
  const double alpha = 2.0, T = 300 * 0.005;
  run_plucked_beam(true, 0, undamped);
  run_plucked_beam(true, alpha, damped);
  // Mass damping C = alpha M takes every underdamped mode's energy down like exp(-alpha t),
  // on top of what backward Euler itself dissipates (the undamped run).
  const double decay = (damped.back() / damped.front()) / (undamped.back() / undamped.front());
  print_message("energy decay %.4g, exp(-alpha T) = %.4g\n", decay, std::exp(-alpha * T));
  assert_true(decay > 0.5 * std::exp(-alpha * T) && decay < 2.0 * std::exp(-alpha * T));
  for (size_t k = 1; k < damped.size(); ++k) assert_le(damped[k], damped[k - 1] * (1 + 1e-6));
}

// An unconstrained body falls rigidly: backward Euler gives v_n = g n h and a drop of
// g h^2 n (n + 1) / 2, which tends to g t^2 / 2 as h -> 0 (relative gap 1/n).
static void test_free_fall(void**) {
  for (bool corot : {true, false}) {
    WorldSettings ws;
    ws.solver = SolverKind::Direct;  // exact: the analytic answers hold to round-off
    ws.gravity = Vec3(0, 0, -9.81);
    World world(ws);
    BodySettings bs;
    bs.model = corot ? ElasticModel::Corotational : ElasticModel::Linear;
    const Id id = world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.2, 0.1, 0.1), {4, 2, 2}, 5), bs, Vec3::Zero(),
                                 Vec3::Zero());
    const int n = 100;
    const double h = 0.001, g = 9.81, t = n * h;
    for (int k = 0; k < n; ++k) world.step(h);
    const Body& b = world.body(id);
    const double drop_be = g * h * h * n * (n + 1) / 2;
    for (size_t i = 0; i < b.x.size(); ++i) {
      assert_near(b.fem.rest[i].z() - b.x[i].z(), drop_be, 1e-9 * drop_be);
      assert_near(b.v[i].z(), -g * t, 1e-9 * g * t);
      assert_near(b.x[i].x(), b.fem.rest[i].x(), 1e-12);
    }
    assert_near(drop_be / (0.5 * g * t * t), 1.0, 1.01 / n);
  }
}

// A clamped beam held at its root by overlapping constraint groups (the whole face fixed, its
// lower half fixed again, its upper half held along x only) under a tip load P at rest: the
// groups' reactions add up to what holds the beam, P (each node's reaction counted once, shared
// among the groups that hold it), and to the reaction of a twin held by one group over the face.
// (0.4 gave every group the node's whole reaction: the sum was off by the shared nodes' part.)
static void test_overlapping_constraint_reactions_add_up(void**) {
  const double L = 0.4, H = 0.1;
  const Vec3 P(0, -3, 1);
  Vec3 sums[2];
  for (int twin = 0; twin < 2; ++twin) {
    WorldSettings ws;
    ws.solver = SolverKind::Direct;  // exact: the analytic answers hold to round-off
    ws.gravity = Vec3::Zero();
    World world(ws);
    BodySettings bs;
    bs.material = {1e6, 0.3, 100};
    const Id id = world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(L, H, H), {8, 2, 2}, 5), bs, Vec3::Zero(),
                                 Vec3::Zero());
    const Body& beam = world.body(id);
    const std::vector<int32_t> root = nodes_where(beam, x_of, 0.0);
    std::vector<Id> groups{world.add_lpc(id, root, LpcSpec{})};
    if (twin == 0) {
      std::vector<int32_t> lower, upper;
      for (int32_t i : root) (beam.fem.rest[i].y() < H / 2 + 1e-9 ? lower : upper).push_back(i);
      groups.push_back(world.add_lpc(id, lower, LpcSpec{}));
      LpcSpec along_x;
      along_x.kind = LpcKind::Plane;  // one direction held
      along_x.directions[0] = Vec3::UnitX();
      groups.push_back(world.add_lpc(id, upper, along_x));
    }
    const auto tip = nodes_where(beam, x_of, L);
    world.set_node_forces(id, tip, Vec3List(tip.size(), P / double(tip.size())));
    for (int k = 0; k < 40; ++k) world.step(1.0);  // large implicit steps: damped toward rest
    sums[twin].setZero();
    for (Id g : groups) sums[twin] += world.lpc(g).reaction;
    print_message("%zu groups: reactions sum to (%.6f, %.6f, %.6f) N; the tip load (%.1f, %.1f, %.1f) N\n",
                  groups.size(), sums[twin].x(), sums[twin].y(), sums[twin].z(), P.x(), P.y(), P.z());
    assert_true((sums[twin] - P).norm() <= 1e-6 * P.norm());
  }
  assert_true((sums[0] - sums[1]).norm() <= 1e-9 * P.norm());
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_free_fall),
      cmocka_unit_test(test_cantilever_matches_euler_bernoulli),
      cmocka_unit_test(test_energy_never_grows_without_damping),
      cmocka_unit_test(test_damping_decays_energy),
      cmocka_unit_test(test_overlapping_constraint_reactions_add_up),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
