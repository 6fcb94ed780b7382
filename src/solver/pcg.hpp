// SPDX-License-Identifier: Apache-2.0
// Projected (filtered) preconditioned conjugate gradient with a block-Jacobi preconditioner.
#pragma once
#include <chrono>
#include <optional>
#include "solver/flexible_cg.hpp"
#include "solver/projected_system.hpp"

namespace mica {

struct PcgWorkspace {
  FlexibleCg<Vec3List> cg;
  Vec3List tmp, rhs;
  std::vector<Mat3> inv_diag;
  void resize(size_t n);  // allocates only when n changes
};

// z = M^-1 r for a symmetric positive definite approximation M of the projected system, written
// to every entry of z; the solver projects its result (z = S z) itself.
class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  virtual void apply(const Vec3List& r, Vec3List& z) = 0;
};

// Projected PCG as a LinearSolver: stops when ||P y - rhs|| <= tolerance ||rhs||, after
// max_iterations, or at the deadline (if one is set). Block-Jacobi preconditioned unless given
// another preconditioner, which may round (a single-precision factor): the search directions
// take Polak-Ribiere's beta (flexible_cg.hpp), which such a preconditioner does not stall.
class PcgSolver : public LinearSolver {
 public:
  using Clock = std::chrono::steady_clock;
  void configure(double tolerance, int32_t max_iterations, std::optional<Clock::time_point> deadline = {}) {
    tolerance_ = tolerance;
    max_iterations_ = max_iterations;
    deadline_ = deadline;
  }
  void set_preconditioner(Preconditioner* p) { preconditioner_ = p; }  // null: block Jacobi
  SolveReport solve(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v) override;
  SolveReport solve_homogeneous(const ProjectedSystem& sys, const Vec3List& f, Vec3List& y) override;
  void reserve(size_t n) { ws_.resize(n); }

 private:
  // P y = rhs from the warm start in y (its free part).
  SolveReport iterate(const ProjectedSystem& sys, Vec3List& y);
  PcgWorkspace ws_;
  double tolerance_ = 1e-8;
  int32_t max_iterations_ = 200;
  std::optional<Clock::time_point> deadline_;
  Preconditioner* preconditioner_ = nullptr;
};

}  // namespace mica
