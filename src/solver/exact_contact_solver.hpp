// SPDX-License-Identifier: Apache-2.0
// Contact through the Delassus matrix: W = G A^-1 G^T formed column by column with each body's
// linear solver, and its complementarity problem solved to round-off (Lemke's pivoting without
// friction; with Coulomb friction block Gauss-Seidel over the contacts, frictional_contact.hpp).
// With CHOLMOD it is exact, the reference MICA is measured against; with projected PCG it is as
// exact as the PCG tolerance. Costly: one linear solve per contact row.
#pragma once
#include <vector>

#include "solver/direct_solver.hpp"
#include "solver/pcg.hpp"
#include "solver/velocity_solver.hpp"

namespace mica {

// How each body's linear systems are solved.
enum class LinearMethod {
  Direct,  // CHOLMOD, factored when A or the constraint set changed (a linear body keeps its factor)
  Pcg,     // projected block-Jacobi PCG to SolverSettings::tolerance, warm-started, stopped at the deadline
};

// Throws Error(Numerical) if the frictionless complementarity problem has no solution the
// pivoting can find, or an impulse is not finite; a frictional solve that stops short of its
// tolerance (sweep cap, deadline: the linear solves are not cut) is reported (converged false),
// not thrown. The report sums the linear solves' iterations and the frictional sweeps, and
// takes the worst of the linear residuals and the complementarity error (relative to the
// impulse scale with friction, frictional_contact.hpp). The impulses lambda hold on entry are
// the sweeps' warm start (frictionless contact is solved by pivoting, which needs none).
// What the exact solver keeps per body.
struct ExactBodyCache {
  DirectSolver direct;
  PcgSolver pcg;
  uint64_t matrix_version = 0, constraint_version = 0;  // of the factored system
  bool factored = false;
  int64_t factorizations() const { return direct.factorizations(); }
};

class ExactContactSolver : public CachingVelocitySolver<ExactBodyCache> {
 public:
  explicit ExactContactSolver(LinearMethod method, const SolverSettings& settings = {})
      : method_(method), settings_(settings) {}
  SolveReport solve(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                    std::vector<double>& lambda) override;
  // W_rr per row of the last solve.
  const std::vector<double>& row_diagonal() const override { return diagonal_; }

 private:
  // The body's linear solver, ready for its A and projection.
  LinearSolver& linear_solver(const SolveContext& ctx, const SolverBody& body);

  LinearMethod method_;
  SolverSettings settings_;
  std::vector<LinearSolver*> solvers_;  // per body of the solve
  std::vector<double> diagonal_, warm_;
};

}  // namespace mica
