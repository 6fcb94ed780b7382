// Projected (filtered) preconditioned conjugate gradient with a block-Jacobi preconditioner.
#pragma once
#include "solver/projected_system.hpp"

namespace mica {

struct PcgWorkspace {
  Vec3List r, z, p, q, tmp, rhs;
  std::vector<Mat3> inv_diag;
  void resize(size_t n);  // allocates only when n changes
};

// Projected PCG as a LinearSolver: stops when ||P y - rhs|| <= tolerance ||rhs|| or after
// max_iterations.
class PcgSolver : public LinearSolver {
 public:
  void configure(double tolerance, int32_t max_iterations) {
    tolerance_ = tolerance;
    max_iterations_ = max_iterations;
  }
  SolveReport solve(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v) override;
  SolveReport solve_homogeneous(const ProjectedSystem& sys, const Vec3List& f, Vec3List& y) override;
  void reserve(size_t n) { ws_.resize(n); }

 private:
  // P y = rhs from the warm start in y (its free part).
  SolveReport iterate(const ProjectedSystem& sys, Vec3List& y);
  PcgWorkspace ws_;
  double tolerance_ = 1e-8;
  int32_t max_iterations_ = 200;
};

}  // namespace mica
