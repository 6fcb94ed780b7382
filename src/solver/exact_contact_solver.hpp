// Contact through the Delassus matrix: W = G A^-1 G^T formed column by column with each body's
// linear solver, and its complementarity problem solved to round-off (Lemke; box PGS with
// friction). With CHOLMOD it is exact, the reference MICA is measured against; with projected
// PCG it is as exact as the PCG tolerance. Costly: one linear solve per contact row.
#pragma once
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

// lambda: out, impulse per row (N s). Throws Error(Numerical) if the complementarity problem
// has no solution the pivoting can find. The report sums the linear solves' iterations and
// takes the worst of their residuals and the complementarity error.
// `diagonal` receives W_rr per row.
SolveReport solve_contact_delassus(std::vector<ExactBody>& bodies, const ContactRows& rows, std::vector<double>& lambda,
                                   std::vector<double>& diagonal);

}  // namespace mica
