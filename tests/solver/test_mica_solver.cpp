// MICA against an exact reference: the projected system factored by CHOLMOD, the Delassus
// matrix W = G A^-1 G^T formed column by column, its LCP solved to 1e-13. Plus the physics
// of the forces a user feels.
#include "test_util.hpp"

using namespace mica;

namespace {

struct Scene {
  World world;
  Id body = 0, base = 0, tool = 0;
};

// A 0.1 m cube fixed at its bottom face (y = 0), optionally pressed by a sphere from above.
void build(Scene& s, bool with_tool, double depth) {
  BodySettings bs;
  bs.material = {2e4, 0.3, 1000};
  s.body = s.world.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {5, 5, 5}, 6), bs, Vec3::Zero(),
                            Vec3::Zero());
  const Body& b = s.world.body(s.body);
  std::vector<int32_t> bottom;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (b.fem.rest[i].y() < 1e-9) bottom.push_back(i);
  s.base = s.world.add_lpc(s.body, bottom, LpcSpec{});
  if (with_tool) {
    Tool t;
    t.radius = 0.03;
    t.margin = 0.002;  // nodes resolved to gap ~ 0 stay in the contact set: no chattering
    t.position = Vec3(0.05, 0.1 + 0.03 - depth, 0.05);
    s.tool = s.world.add_tool(t);
  }
}

WorldSettings mica_settings(double tol) {
  WorldSettings ws;
  ws.solver = SolverKind::Mica;
  ws.tolerance = tol;
  ws.max_iterations = 20000;
  return ws;
}

// The exact solution of the step MICA just took, from the same A, b, S, z and contacts.
void exact_reference(const World& w, Id id, Vec3List& v, std::vector<double>& lambda, double h) {
  const Body& b = w.body(id);
  const auto& contacts = w.contacts();
  const size_t n = b.x.size(), nc = contacts.size();
  const ProjectedSystem sys{b.fem.pattern, b.A, b.projection};
  DirectSolver direct;
  direct.analyze(b.fem.pattern);
  direct.factorize(sys);
  // Unconstrained-by-contact velocity v0 and the response columns A^-1 G_r^T (z = 0 for them).
  Vec3List v0(n);
  direct.solve(sys, b.b, v0);
  Projection no_prescribed = b.projection;
  for (auto& zi : no_prescribed.z) zi.setZero();
  const ProjectedSystem sys0{b.fem.pattern, b.A, no_prescribed};
  std::vector<Vec3List> columns(nc, Vec3List(n));
  for (size_t r = 0; r < nc; ++r) {
    Vec3List e(n, Vec3::Zero());
    e[contacts[r].node] = contacts[r].normal;
    direct.solve(sys0, e, columns[r]);
  }
  Eigen::MatrixXd W(nc, nc);
  Eigen::VectorXd q(nc);
  for (size_t r = 0; r < nc; ++r) {
    q[r] = contacts[r].normal.dot(v0[contacts[r].node]) + std::max(contacts[r].gap / h, -1.0);
    for (size_t s = 0; s < nc; ++s) W(r, s) = contacts[r].normal.dot(columns[s][contacts[r].node]);
  }
  // 0 <= lambda _|_ W lambda + q >= 0 by projected Gauss-Seidel on the exact W, to 1e-13.
  Eigen::VectorXd l = Eigen::VectorXd::Zero(nc);
  for (int it = 0; it < 200000; ++it) {
    double change = 0;
    for (size_t r = 0; r < nc; ++r) {
      if (W(r, r) <= 0) continue;
      const double next = std::max(0.0, l[r] - (W.row(r).dot(l) + q[r]) / W(r, r));
      change = std::max(change, std::fabs(next - l[r]));
      l[r] = next;
    }
    if (change <= 1e-13 * std::max(1e-12, l.cwiseAbs().maxCoeff())) break;
  }
  lambda.assign(l.data(), l.data() + nc);
  v = v0;
  for (size_t s = 0; s < nc; ++s)
    for (size_t i = 0; i < n; ++i) v[i] += columns[s][i] * l[s];
}

double max_diff(const Vec3List& a, const Vec3List& b) {
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, (a[i] - b[i]).norm());
  return d;
}

}  // namespace

static void test_mica_without_contact_matches_direct(void**) {
  Scene m{World(mica_settings(1e-12)), 0, 0, 0}, d{World(WorldSettings{}), 0, 0, 0};
  build(m, false, 0);
  build(d, false, 0);
  for (int k = 0; k < 5; ++k) {
    m.world.step(0.01);
    d.world.step(0.01);
  }
  assert_true(m.world.stats().converged);
  assert_le(max_diff(m.world.body(m.body).v, d.world.body(d.body).v), 1e-8);
}

static void test_sphere_press_matches_exact_reference(void**) {
  const double h = 0.01;
  WorldSettings ws = mica_settings(1e-10);
  ws.gravity = Vec3::Zero();  // the press alone: the cube does not sag away from the sphere
  Scene s{World(ws), 0, 0, 0};
  build(s, true, 0.004);
  s.world.step(h);
  assert_true(s.world.stats().converged);
  const auto& contacts = s.world.contacts();
  assert_true(contacts.size() >= 4);
  Vec3List v_ref;
  std::vector<double> l_ref;
  exact_reference(s.world, s.body, v_ref, l_ref, h);
  const Vec3List& v = s.world.body(s.body).v;
  double vmax = 0, lmax = 0, ldiff = 0;
  for (const Vec3& vi : v_ref) vmax = std::max(vmax, vi.norm());
  for (size_t r = 0; r < l_ref.size(); ++r) {
    lmax = std::max(lmax, l_ref[r]);
    ldiff = std::max(ldiff, std::fabs(l_ref[r] - s.world.impulses()[r]));
  }
  print_message("%zu contacts, max |v - v_ref| / max|v| = %.3g, max |l - l_ref| / max l = %.3g, %d iterations\n",
                contacts.size(), max_diff(v, v_ref) / vmax, ldiff / lmax, s.world.stats().solver_iterations);
  assert_true(lmax > 0);
  assert_le(max_diff(v, v_ref), 1e-6 * vmax);
  assert_le(ldiff, 1e-6 * lmax);
  // Complementarity of the result: no contact point moves into the sphere beyond its gap.
  for (size_t r = 0; r < contacts.size(); ++r)
    assert_true(contacts[r].normal.dot(v[contacts[r].node]) * h + contacts[r].gap > -1e-9);
}

// Pressed and settled: the tool's force, the support reaction and the weight balance, and
// the tool is pushed up (away from the tissue) by a force of the right size.
static void test_static_equilibrium_of_forces(void**) {
  WorldSettings ws = mica_settings(1e-10);
  ws.gravity = Vec3(0, -9.81, 0);
  Scene s{World(ws), 0, 0, 0};
  build(s, true, 0.015);  // deeper than the cube's own sag (rho g L / E * L ~ 5 mm)
  s.world.body(s.body).settings.rayleigh_alpha = 20;  // settle quickly
  int iterations = 0;
  for (int k = 0; k < 200; ++k) {
    s.world.step(0.01);
    iterations += s.world.stats().solver_iterations;
  }
  print_message("%.0f MICA iterations per step on average\n", iterations / 200.0);
  const Vec3 tool = s.world.tool(s.tool).force;
  const Vec3 support = s.world.lpc(s.base).reaction;  // on the holder of the base
  const double weight = s.world.body(s.body).fem.total_mass() * 9.81;
  print_message("tool force (%.4f, %.4f, %.4f) N, base reaction (%.4f, %.4f, %.4f) N, weight %.4f N\n", tool.x(),
                tool.y(), tool.z(), support.x(), support.y(), support.z(), weight);
  assert_true(tool.y() > 0.1);  // the tissue pushes the tool up
  // On the body: -tool force (from the tool) - support (from the base) + weight = 0.
  const Vec3 net = -tool - support + Vec3(0, -weight, 0);
  assert_le(net.norm(), 1e-3 * (weight + tool.norm()));
}

// Grasp the top face and lift it: the user's hand is pulled down.
static void test_lifting_a_grasp_pulls_down(void**) {
  WorldSettings ws = mica_settings(1e-10);
  Scene s{World(ws), 0, 0, 0};
  build(s, false, 0);
  const Body& b = s.world.body(s.body);
  std::vector<int32_t> top;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (b.fem.rest[i].y() > 0.1 - 1e-9) top.push_back(i);
  LpcSpec lift;
  lift.velocity = Vec3(0, 0.05, 0);  // m/s upward
  const Id grasp = s.world.add_lpc(s.body, top, lift);
  for (int k = 0; k < 20; ++k) s.world.step(0.01);
  const Vec3 felt = s.world.lpc(grasp).reaction;
  print_message("stretching by 1 cm: the hand feels (%.4f, %.4f, %.4f) N\n", felt.x(), felt.y(), felt.z());
  assert_true(felt.y() < 0);
  // Of the size of the stretched column's elastic force: E A (dL / L) = 2e4 * 0.01 * 0.1 = 20 N, within a factor 2.
  assert_true(-felt.y() > 10 && -felt.y() < 40);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_mica_without_contact_matches_direct),
      cmocka_unit_test(test_sphere_press_matches_exact_reference),
      cmocka_unit_test(test_static_equilibrium_of_forces),
      cmocka_unit_test(test_lifting_a_grasp_pulls_down),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
