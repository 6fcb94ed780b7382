// SPDX-License-Identifier: Apache-2.0
#include "solver/pcg.hpp"

#include <Eigen/LU>
#include <cmath>

#include "core/error.hpp"

namespace mica {

void PcgWorkspace::resize(size_t n) {
  for (Vec3List* v : {&cg.r, &cg.z, &cg.z_last, &cg.p, &cg.q, &tmp, &rhs}) v->resize(n);
  inv_diag.resize(n);
}

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
  FlexibleCg<Vec3List>& cg = ws.cg;
  const int32_t n = sys.pattern.rows;
  if (!preconditioner_)
    for (int32_t i = 0; i < n; ++i) ws.inv_diag[i] = sys.diagonal_block(i).inverse();
  sys.apply(y, cg.q, ws.tmp);
  for (int32_t i = 0; i < n; ++i) cg.r[i] = ws.rhs[i] - cg.q[i];

  SolveReport report;
  const double rhs_norm = std::sqrt(dot(ws.rhs, ws.rhs));
  if (!std::isfinite(rhs_norm)) fail(Errc::Numerical, "the right-hand side is not finite (loads or state overflow)");
  const double stop = tolerance_ * rhs_norm;
  double r_norm = std::sqrt(dot(cg.r, cg.r));
  if (rhs_norm == 0) {
    for (auto& yi : y) yi.setZero();
    r_norm = 0;
  }
  cg.start();
  const auto apply = [&](const Vec3List& p, Vec3List& q) { sys.apply(p, q, ws.tmp); };
  while (r_norm > stop && report.iterations < max_iterations_) {
    if (deadline_ && report.iterations > 0 && Clock::now() >= *deadline_) {
      report.out_of_time = true;
      break;
    }
    if (preconditioner_) {
      preconditioner_->apply(cg.r, cg.z);
      for (int32_t i : sys.projection.nodes) cg.z[i] = sys.projection.S[i] * cg.z[i];
    } else {
      for (int32_t i = 0; i < n; ++i) cg.z[i] = ws.inv_diag[i] * cg.r[i];
    }
    if (!cg.step(y, apply)) break;  // breakdown: the operator is not positive definite here
    r_norm = std::sqrt(dot(cg.r, cg.r));
    ++report.iterations;
  }
  report.residual = rhs_norm > 0 ? r_norm / rhs_norm : 0;
  report.converged = r_norm <= stop;  // false for a NaN residual
  return report;
}

}  // namespace mica
