// SPDX-License-Identifier: Apache-2.0
// MICA: Modified Iterative Constraint Anticipation (Arikatla, Ortiz, De, Enquobahrie 2016).
// One loop resolves projection constraints and contact together:
//
//   A v = b + G^T lambda,   (I - S) v = z,   0 <= lambda_n  _|_  G_n v + gap / h >= 0,
//   |lambda_t| <= mu lambda_n (isotropic Coulomb friction: a contact's two tangent impulses on a disk)
//
// Each iteration anticipates the contact velocities from the current v with the filtered
// block-diagonal inverse Dt^-1 = S (S D S + I - S)^-1 S, updates lambda by projected
// Gauss-Seidel on B = G Dt^-1 G^T, then sweeps v by modified block Gauss-Seidel with the
// contact impulses on the right-hand side. At a fixed point v and lambda solve the
// complementarity problem above exactly.
#pragma once
#include <array>
#include <vector>

#include "solver/velocity_solver.hpp"

namespace mica {

// The stopping test (SolverSettings::tolerance): stop when the change of v between iterations
// is below tolerance * max(|v|, |Dt^-1 b|, 1 um/s RMS per node), the change of lambda below
// tolerance * max(|lambda|, the first anticipated impulse), and the true momentum residual
// |S (b + G^T lambda - A v)| of every body below tolerance times the size of the terms it
// balances (per node the largest of |b|, |G^T lambda|, |A v|): the forces a user feels are
// accurate to the tolerance. Gauss-Seidel that stagnates (stiff bodies, long steps) changes
// little per sweep far from the solution, so small changes alone prove nothing. With a pool
// (SolveContext) and every body coloured (SolverBody::colours) the MBGS sweep runs colour by
// colour, a colour's nodes on the pool's threads; else the paper's sweep in node order.
class MicaSolver : public VelocitySolver {
 public:
  explicit MicaSolver(const SolverSettings& settings = {}) : settings_(settings) {}
  SolveReport solve(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                    std::vector<double>& lambda) override;
  // B_rr of the last solve, per row: the compliance each row sees (its diagonal of G Dt^-1 G^T).
  const std::vector<double>& row_diagonal() const override { return diag_; }

 private:
  void coloured_sweep(std::vector<SolverBody>& bodies, ThreadPool& pool, double& dv2, double& v2);
  double anticipated_velocity(const std::vector<SolverBody>& bodies, const ContactRows& rows, size_t r) const;
  void update_tangents(const ContactRows& rows, size_t r, std::vector<double>& lambda);

  SolverSettings settings_;
  std::vector<std::vector<Mat3>> inv_diag_;  // per body, per node: Dt_i^-1
  std::vector<Vec3> g_;                      // per row term: coef Dt^-1 d
  std::vector<double> diag_, c_;             // per row: B_rr, anticipated velocity
  std::vector<double> pair_step_;            // per first tangent row: the tangent pair's step length
  std::vector<std::vector<Vec3>> u_;         // per body, per node: Dt^-1 G^T lambda
  std::vector<double> lambda_old_;
  std::vector<std::array<double, 2>> block_sums_;  // coloured sweep: |dv|^2 and |v|^2 per block, in sweep order
};

}  // namespace mica
