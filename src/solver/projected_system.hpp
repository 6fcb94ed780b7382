// SPDX-License-Identifier: Apache-2.0
// The velocity system of one body under projection constraints.
// With v = y + z, y = S y, the constrained problem S (A v - b) = 0, (I - S) v = z becomes
// the symmetric positive definite system (S A S + I - S) y = S (b - A z).
#pragma once
#include "fem/block_matrix.hpp"
#include "solver/projection.hpp"

namespace mica {

// What every solve reports, a linear solve of one body or a velocity solve of the step
// (velocity_solver.hpp); MICA's loops also fill the terms of their stopping test.
struct SolveReport {
  int32_t iterations = 0;
  int32_t solves = 0;   // velocity solves: the factored sweep's rounds (0: the solver counts none, the world counts 1)
  double residual = 0;  // ||P y - r|| / ||r|| of the projected system (0 when r = 0); a velocity solve: its worst measure
  bool converged = true;
  bool out_of_time = false;  // stopped at the time budget (converged is then false)
  double velocity_change = 0;    // MICA: last change of v, relative to its scale (mica_solver.hpp)
  double impulse_change = 0;     // MICA: last change of lambda, relative to its scale
  double paper_change = 0;       // MICA: last 2-norm of the change of (v, lambda), the paper's test
  double momentum_residual = 0;  // MICA: last true residual, relative (NaN if never checked)
};

struct ProjectedSystem {
  const BlockPattern& pattern;
  const BlockValues& A;
  const Projection& projection;  // inactive: S = I, z = 0

  // out = (S A S + I - S) y; tmp is scratch of the same size.
  void apply(const Vec3List& y, Vec3List& out, Vec3List& tmp) const;
  // rhs = S (b - A z); tmp is scratch.
  void right_hand_side(const Vec3List& b, Vec3List& rhs, Vec3List& tmp) const;
  // The projected diagonal block S_i A_ii S_i + I - S_i.
  Mat3 diagonal_block(int32_t i) const;
  // The projected block (i, j) stored at index k.
  Mat3 block(int32_t i, int32_t k) const;
};

// A method for the velocity solve of one body's projected system.
class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  // v = y + z with (S A S + I - S) y = S (b - A z); v holds a warm start on entry.
  virtual SolveReport solve(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v) = 0;
  // y = (S A S + I - S)^-1 S f: the response to a force f with no prescribed velocity.
  virtual SolveReport solve_homogeneous(const ProjectedSystem& sys, const Vec3List& f, Vec3List& y) = 0;
};

}  // namespace mica
