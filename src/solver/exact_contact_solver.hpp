// Contact through the Delassus matrix: W = G A^-1 G^T formed column by column with each body's
// linear solver, and its complementarity problem solved to round-off (Lemke's pivoting without
// friction; with Coulomb friction block Gauss-Seidel over the contacts, frictional_contact.hpp). With CHOLMOD it is exact, the reference MICA is measured against; with projected
// PCG it is as exact as the PCG tolerance. Costly: one linear solve per contact row.
#pragma once
#include <chrono>
#include <optional>
#include <vector>

#include "solver/contact_rows.hpp"
#include "solver/direct_solver.hpp"

namespace mica {

struct ExactBody {
  const BlockPattern* pattern;
  const BlockValues* A;
  const Vec3List* b;
  const Projection* projection;
  LinearSolver* solver;      // ready for this A and projection (a DirectSolver: factored)
  Vec3List* v;               // out
  Vec3List contact_impulse;  // out: G^T lambda per node, N s
};

struct ExactContactSettings {
  // Friction: the impulse per row to start from (say the last step's, matched by row key);
  // null: zero. Frictionless contact is solved by pivoting, which needs none.
  const std::vector<double>* warm_start = nullptr;
  // Friction: the sweeps stop here, unconverged (out_of_time). The linear solves are not cut.
  std::optional<std::chrono::steady_clock::time_point> deadline;
};

// lambda: out, impulse per row (N s). Throws Error(Numerical) if the frictionless
// complementarity problem has no solution the pivoting can find, or an impulse is not finite;
// a frictional solve that stops short of its tolerance (sweep cap, deadline) is reported
// (converged false), not thrown. The report sums the linear solves' iterations and the
// frictional sweeps, and takes the worst of the linear residuals and the complementarity error
// (relative to the impulse scale with friction, frictional_contact.hpp).
// `diagonal` receives W_rr per row.
SolveReport solve_contact_delassus(std::vector<ExactBody>& bodies, const ContactRows& rows, std::vector<double>& lambda,
                                   std::vector<double>& diagonal, const ExactContactSettings& settings = {});

}  // namespace mica
