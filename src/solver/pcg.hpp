// Projected (filtered) preconditioned conjugate gradient with a block-Jacobi preconditioner.
#pragma once
#include "solver/projected_system.hpp"

namespace mica {

struct PcgWorkspace {
  Vec3List r, z, p, q, tmp, rhs;
  std::vector<Mat3> inv_diag;
  void resize(size_t n);  // allocates only when n changes
};

// Solves the projected system for v (in: the warm start, out: the solution). Stops when
// ||P y - rhs|| <= tolerance ||rhs|| or after max_iterations.
SolveReport solve_pcg(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v, double tolerance,
                      int32_t max_iterations, PcgWorkspace& ws);

}  // namespace mica
