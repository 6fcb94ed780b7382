// SPDX-License-Identifier: Apache-2.0
// One velocity problem for the tests of every solver (VelocitySolver, velocity_solver.hpp), built
// without a World: a 0.1 m cube of n^3 cells x 6 tets (E = 2e4 Pa, nu = 0.3, rho = 1000), its
// bottom face fixed, a little sheared (so the co-rotational A is warped), moving up at 5 cm/s
// under gravity into a tilted ceiling that its top nodes touch (some inside, some just below);
// with friction the ceiling slides sideways. The step is h = 10 ms.
//   A = M + h^2 K(R),  b = M v0 + h (f_int + M g),  rows: one contact per top node.
// check_solution tests the conditions a solution must meet, whatever the solver.
#pragma once
#include "test_util.hpp"  // the core's headers (world.hpp), then cmocka

namespace mica_test {

using namespace mica;

struct SolverProblem {
  static constexpr double kH = 0.01;
  FemModel fem;
  Vec3List x;
  std::vector<Mat3> R;
  BlockValues A;
  Vec3List b, v, impulse, f_int;
  Projection projection;
  std::vector<Contact> contacts;
  ContactRows rows;
  std::vector<double> lambda;
  std::vector<TriangleStiffness> extra;  // what of A the solver is told is contact stiffness

  explicit SolverProblem(double friction = 0, int32_t cells = 3, bool contact = true,
                         const Material& material = Material{2e4, 0.3, 1000}) {
    const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {cells, cells, cells}, 6);
    fem = build_fem_model(mesh, material, MassKind::Consistent, "test body");
    const int32_t n = fem.node_count();
    x = fem.rest;
    for (Vec3& p : x) p += Vec3(0.08 * p.y() * p.y(), 0, 0.03 * p.y());  // sheared: R != I
    R.resize(fem.elements.size());
    compute_rotations(fem, x, R);
    A.resize(fem.pattern.block_count());
    f_int.resize(size_t(n));
    set_scaled_mass(fem, 1.0, A);
    assemble_elastic(fem, x, &R, kH * kH, &A, f_int);
    const size_t count = static_cast<size_t>(n);
    Vec3List v0(count, Vec3(0, 0.05, 0)), Mv(count), g(count, Vec3(0, -9.81, 0)), Mg(count);
    mass_multiply(fem, v0, Mv);
    mass_multiply(fem, g, Mg);
    b.resize(size_t(n));
    for (int32_t i = 0; i < n; ++i) b[i] = Mv[i] + kH * (f_int[i] + Mg[i]);
    projection.reset(n);
    for (int32_t i = 0; i < n; ++i)
      if (fem.rest[i].y() < 1e-9) projection.constrain(i, Mat3::Identity(), Vec3::Zero());
    v = v0;
    impulse.assign(size_t(n), Vec3::Zero());
    if (!contact) return;
    // The ceiling: normal n (pushing the body down), through the point c; a top node's gap is
    // its distance below it.
    const Vec3 normal = Vec3(0.1, -1, 0.05).normalized(), c(0.05, 0.1012, 0.05);
    for (int32_t i = 0; i < n; ++i) {
      if (fem.rest[i].y() < 0.1 - 1e-9) continue;
      Contact ct{uint64_t(1000 + i), node_point(0, i), BodyPoint{}, normal, x[i], normal.dot(x[i] - c),
                 friction, Vec3(0.03, 0, 0.01)};
      ct.tool = 0;
      contacts.push_back(ct);
    }
    rows.build(contacts, kH, 1.0);
    lambda.assign(rows.size(), 0.0);
  }

  SolverBody body(uint64_t key = 1) {
    SolverBody s;
    s.key = key;
    s.fem = &fem;
    s.A = &A;
    s.b = &b;
    s.projection = &projection;
    s.v = &v;
    s.contact_impulse = &impulse;
    s.rotation = &R;
    s.extra_stiffness = extra.empty() ? nullptr : &extra;
    s.system = SystemKey{kH, 0, 0};
    return s;
  }

  // Solves with `solver` from the warm start v0 (and lambda as it is); returns the report.
  SolveReport solve(VelocitySolver& solver, const SolveContext& ctx = {}) {
    std::vector<SolverBody> bodies{body()};
    return solver.solve(ctx, bodies, rows, lambda);
  }
};

// max |a - b| / max(max |b|, floor)
inline double relative_difference(const Vec3List& a, const Vec3List& b, double floor = 1e-300) {
  double d = 0, s = floor;
  for (size_t i = 0; i < a.size(); ++i) {
    d = std::max(d, (a[i] - b[i]).norm());
    s = std::max(s, b[i].norm());
  }
  return d / s;
}
inline double relative_difference(const std::vector<double>& a, const std::vector<double>& b, double floor = 1e-300) {
  double d = 0, s = floor;
  for (size_t i = 0; i < a.size(); ++i) {
    d = std::max(d, std::fabs(a[i] - b[i]));
    s = std::max(s, std::fabs(b[i]));
  }
  return d / s;
}

// The conditions of a solution, to `tol` relative to the sizes involved: momentum balance on
// the free directions S (A v - b - G^T lambda) = 0, the prescribed velocities (I - S) v = z, the
// contact impulse G^T lambda, and per contact the normal complementarity
// 0 <= lambda_n _|_ w_n >= 0 and Coulomb's law (the tangent impulse on the disk; sticking
// (w_t = 0) inside it, sliding against w_t on its rim). Returns the count of active contacts.
inline int check_solution(const SolverProblem& p, double tol) {
  const BlockPattern& pat = p.fem.pattern;
  const int32_t n = p.fem.node_count();
  Vec3List g(size_t(n), Vec3::Zero());
  p.rows.scatter(p.lambda, [&](int32_t) -> Vec3List& { return g; });
  double r = 0, scale = 0, impulse_error = 0, impulse_scale = 1e-300;
  for (int32_t i = 0; i < n; ++i) {
    Vec3 av = Vec3::Zero();
    for (int32_t k = pat.row_start[i]; k < pat.row_start[i + 1]; ++k) av += p.A[k] * p.v[pat.col[k]];
    const bool fixed = p.projection.is_constrained[i];
    const Mat3 S = fixed ? p.projection.S[i] : Mat3::Identity();
    r = std::max(r, (S * (av - p.b[i] - g[i])).norm());
    scale = std::max({scale, av.norm(), p.b[i].norm(), g[i].norm()});
    if (fixed) assert_le((p.v[i] - S * p.v[i] - p.projection.z[i]).norm(), 1e-12);
    impulse_error = std::max(impulse_error, (p.impulse[i] - g[i]).norm());
    impulse_scale = std::max(impulse_scale, g[i].norm());
  }
  assert_le(r, tol * scale);
  assert_le(impulse_error, 1e-12 * impulse_scale);
  // Row velocities w = G v + bias.
  std::vector<double> w(p.rows.size());
  double l_scale = 1e-300, w_scale = 1e-300;
  for (size_t q = 0; q < p.rows.size(); ++q) {
    w[q] = p.rows.bias[q];
    for (int32_t t = p.rows.start[q]; t < p.rows.start[q + 1]; ++t)
      w[q] += p.rows.terms[t].coef * p.rows.direction[q].dot(p.v[p.rows.terms[t].node]);
    l_scale = std::max(l_scale, std::fabs(p.lambda[q]));
    w_scale = std::max(w_scale, std::fabs(p.rows.bias[q]));
  }
  int active = 0;
  for (size_t q = 0; q < p.rows.size(); ++q) {
    if (p.rows.normal_of[q] >= 0) continue;
    assert_true(p.lambda[q] >= 0);
    assert_le(-w[q], tol * w_scale);                        // no penetration
    assert_le(std::min(p.lambda[q] / l_scale, std::fabs(w[q]) / w_scale), tol);  // complementarity
    active += p.lambda[q] > tol * l_scale;
    if (q + 2 >= p.rows.size() || !p.rows.first_tangent(q + 1)) continue;
    const double mu = p.rows.mu[q + 1], lt = std::hypot(p.lambda[q + 1], p.lambda[q + 2]);
    const double wt = std::hypot(w[q + 1], w[q + 2]);
    assert_le(lt, mu * p.lambda[q] * (1 + 1e-12) + 1e-300);
    if (!(p.lambda[q] > tol * l_scale)) continue;  // apart (to round-off): no friction to check
    if (lt < mu * p.lambda[q] * (1 - 1e-6)) {
      assert_le(wt, tol * w_scale);  // sticking
    } else if (wt > 1e-6 * w_scale) {  // sliding (not merely on the rim): the impulse opposes the slip
      const double cosine = (p.lambda[q + 1] * w[q + 1] + p.lambda[q + 2] * w[q + 2]) / (lt * wt);
      assert_le(cosine, -1 + 1e-4);
    }
  }
  return active;
}

}  // namespace mica_test
