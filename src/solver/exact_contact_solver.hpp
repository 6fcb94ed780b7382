// The exact reference for contact: each body's projected A factored by CHOLMOD, the Delassus
// matrix W = G A^-1 G^T formed column by column, and its complementarity problem solved to
// round-off. Costly (one solve per contact row), exact: what MICA is measured against.
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
  DirectSolver* direct;      // factored for this A and projection
  Vec3List* v;               // out
  Vec3List contact_impulse;  // out: G^T lambda per node, N s
};

// lambda: out, impulse per row (N s). Throws Error(Numerical) if the complementarity problem
// has no solution the pivoting can find.
SolveReport solve_exact_contact(std::vector<ExactBody>& bodies, const ContactRows& rows, std::vector<double>& lambda);

}  // namespace mica
