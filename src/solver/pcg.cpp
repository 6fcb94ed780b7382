// SPDX-License-Identifier: Apache-2.0
#include "solver/pcg.hpp"

#include <Eigen/LU>
#include <cmath>

#include "core/error.hpp"

namespace mica {

void PcgWorkspace::resize(size_t n) {
  for (Vec3List* v : {&r, &z, &z_last, &p, &q, &tmp, &rhs}) v->resize(n);
  inv_diag.resize(n);
}

namespace {
double dot(const Vec3List& a, const Vec3List& b) { return flat(a).dot(flat(b)); }
}  // namespace

SolveReport PcgSolver::solve(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v) {
  ws_.resize(b.size());
  sys.right_hand_side(b, ws_.rhs, ws_.tmp);
  // Unknown y = S (v - z): start from the warm start's free part.
  for (int32_t i : sys.projection.nodes) v[i] = sys.projection.S[i] * v[i];
  const SolveReport report = iterate(sys, v);
  for (int32_t i : sys.projection.nodes) v[i] += sys.projection.z[i];
  return report;
}

SolveReport PcgSolver::solve_homogeneous(const ProjectedSystem& sys, const Vec3List& f, Vec3List& y) {
  ws_.resize(f.size());
  ws_.rhs = f;
  for (int32_t i : sys.projection.nodes) ws_.rhs[i] = sys.projection.S[i] * f[i];
  for (Vec3& yi : y) yi.setZero();
  return iterate(sys, y);
}

SolveReport PcgSolver::iterate(const ProjectedSystem& sys, Vec3List& y) {
  PcgWorkspace& ws = ws_;
  const int32_t n = sys.pattern.rows;
  if (!preconditioner_)
    for (int32_t i = 0; i < n; ++i) ws.inv_diag[i] = sys.diagonal_block(i).inverse();
  sys.apply(y, ws.q, ws.tmp);
  for (int32_t i = 0; i < n; ++i) ws.r[i] = ws.rhs[i] - ws.q[i];

  SolveReport report;
  const double rhs_norm = std::sqrt(dot(ws.rhs, ws.rhs));
  if (!std::isfinite(rhs_norm)) fail(Errc::Numerical, "the right-hand side is not finite (loads or state overflow)");
  const double stop = tolerance_ * rhs_norm;
  double r_norm = std::sqrt(dot(ws.r, ws.r));
  if (rhs_norm == 0) {
    for (auto& yi : y) yi.setZero();
    r_norm = 0;
  }
  double rz = 0;
  while (r_norm > stop && report.iterations < max_iterations_) {
    if (deadline_ && report.iterations > 0 && Clock::now() >= *deadline_) {
      report.out_of_time = true;
      break;
    }
    if (preconditioner_) {
      preconditioner_->apply(ws.r, ws.z);
      for (int32_t i : sys.projection.nodes) ws.z[i] = sys.projection.S[i] * ws.z[i];
    } else {
      for (int32_t i = 0; i < n; ++i) ws.z[i] = ws.inv_diag[i] * ws.r[i];
    }
    const double rz_new = dot(ws.r, ws.z);
    if (report.iterations == 0) {
      ws.p = ws.z;
    } else {
      // Polak-Ribiere: (r_k.z_k - r_k.z_k-1) / r_k-1.z_k-1 (Notay 2000's flexible CG); the same
      // as Fletcher-Reeves' r_k.z_k / r_k-1.z_k-1 for a fixed linear preconditioner.
      const double beta = (rz_new - dot(ws.r, ws.z_last)) / rz;
      for (int32_t i = 0; i < n; ++i) ws.p[i] = ws.z[i] + beta * ws.p[i];
    }
    rz = rz_new;
    ws.z_last = ws.z;
    sys.apply(ws.p, ws.q, ws.tmp);
    const double pq = dot(ws.p, ws.q);
    if (!(pq > 0)) break;  // breakdown: the operator is not positive definite here
    const double alpha = rz / pq;
    for (int32_t i = 0; i < n; ++i) {
      y[i] += alpha * ws.p[i];
      ws.r[i] -= alpha * ws.q[i];
    }
    r_norm = std::sqrt(dot(ws.r, ws.r));
    ++report.iterations;
  }
  report.residual = rhs_norm > 0 ? r_norm / rhs_norm : 0;
  report.converged = r_norm <= stop;  // false for a NaN residual
  return report;
}

}  // namespace mica
