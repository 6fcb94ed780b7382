// SPDX-License-Identifier: Apache-2.0
// Contact with isotropic Coulomb friction on a dense Delassus matrix M (rows as in lcp.hpp's
// cone_error: per contact a normal row and up to two tangent rows):
//     w = M z + q;  0 <= z_n _|_ w_n >= 0;  |z_t| <= mu z_n;  sliding opposes w_t.
// Nonlinear (the disk's radius moves with z_n) and not an LCP. Solved by nonsmooth block
// Gauss-Seidel over the contacts: each contact's 3x3 problem is solved exactly with the others
// held (solve_contact_coulomb), sweep after sweep, with Newton steps on cone_error's natural map
// between batches of sweeps, until cone_error is below the tolerance. Meant for tens to a few
// hundred rows: everything is dense, O(rows^2) per sweep, O(rows^3) per Newton step.
#pragma once
#include <chrono>
#include <optional>

#include "solver/lcp.hpp"

namespace mica {

// Problems with more rows than this are solved by the sweeps alone (no Newton steps).
constexpr Eigen::Index kMaxNewtonRows = 300;

struct FrictionalSettings {
  // Solved when cone_error <= tolerance * the impulse scale: the largest of |z| and, per
  // contact, the impulse -q_n / M_nn its normal row alone asks for.
  double tolerance = 1e-10;
  int32_t max_sweeps = 5000;  // block Gauss-Seidel sweeps, then as many damped ones; a stall stops sooner (.cpp)
  Eigen::Index max_newton_rows = kMaxNewtonRows;  // Newton steps only on problems of at most this many rows
  std::optional<std::chrono::steady_clock::time_point> deadline;  // stop (unsolved) once past it
};

struct FrictionalSolution {
  Eigen::VectorXd z, w;  // the impulses and w = M z + q
  bool solved = false;
  bool out_of_time = false;  // stopped at the deadline
  int32_t sweeps = 0;        // all sweeps done, damped ones included
  int32_t newton_steps = 0;  // Newton steps tried on the natural map (see .cpp)
  double error = 0;          // cone_error at z
  double scale = 0;          // the impulse scale the tolerance is relative to
  std::string message;       // what happened, for a person to read
};

// What a solve works in: kept by a caller that solves again and again (the solver loop), a solve
// allocates nothing once the workspace and the solution have served a problem of as many rows
// and contacts (an Eigen vector or matrix of another size is allocated afresh).
struct FrictionalWorkspace {
  // One contact's rows and its 3x3 block of M; an absent tangent row is a decoupled row with the
  // normal's diagonal (its impulse stays zero).
  struct Block {
    int32_t row[3];  // normal, tangent, tangent (-1: absent)
    Eigen::Matrix3d W;
    double mu;
  };
  std::vector<ConeContact> contacts;
  std::vector<int32_t> contact_of;
  std::vector<Block> blocks;
  Eigen::VectorXd F, F_trial, dz, z_trial, w_trial, cod_work, cod_y;
  Eigen::MatrixXd J;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
};

// z0: the warm start, projected onto the cones (empty: zero). Throws Error(InvalidArgument) as
// cone_error does, or if z0 has the wrong size or a non-finite entry. Allocates only before
// the sweeps.
FrictionalSolution solve_frictional_contact(const Eigen::MatrixXd& M, const Eigen::VectorXd& q,
                                            const Eigen::VectorXd& mu, const std::vector<int32_t>& normal_index,
                                            const Eigen::VectorXd& z0, const FrictionalSettings& settings);
// The same into s, in ws (see FrictionalWorkspace).
void solve_frictional_contact(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                              const std::vector<int32_t>& normal_index, const Eigen::VectorXd& z0,
                              const FrictionalSettings& settings, FrictionalWorkspace& ws, FrictionalSolution& s);

}  // namespace mica
