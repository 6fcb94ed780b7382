// Dense reference solvers for linear complementarity problems (LCP): given M (n x n) and q,
// find z with
//     z >= 0,   w = M z + q >= 0,   z_r w_r = 0 for every row r.
// Lemke's method is the exact reference (a finite pivoting method, lexicographic so that
// degenerate problems such as redundant contacts do not cycle); projected Gauss-Seidel is the
// iterative one, also for the box LCP of contacts with Coulomb friction. Meant for small
// problems (tens to a few hundred rows): everything is dense.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <string>
#include <vector>

namespace mica {

struct LcpSolution {
  Eigen::VectorXd z, w;  // the unknowns and w = M z + q, both of size n
  bool solved = false;   // false: ray termination, pivot or sweep limit, numerical breakdown
  int32_t pivots = 0;    // Lemke: pivots done (0 in the trivial case q >= 0); PGS: sweeps done
  std::string message;   // what happened, for a person to read
};

// Lemke's complementary pivoting with the covering vector of ones, lexicographic
// minimum-ratio rule. Solves every LCP whose M is positive semidefinite (or copositive-plus,
// or a P-matrix) when it has a solution; otherwise it ends on a ray and reports
// solved == false with a message. max_pivots == 0 means 50 n. The returned z is polished by
// one solve with the final basis. Throws Error(InvalidArgument) on mismatched sizes, a
// negative max_pivots or a non-finite entry.
LcpSolution solve_lcp_lemke(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, int32_t max_pivots = 0);

// Projected Gauss-Seidel from z = 0, for positive semidefinite M: sweeps the rows in order,
// z_r <- max(0, z_r - w_r / M_rr), skipping rows with M_rr <= 0 (they keep z_r = 0). Stops,
// solved, once complementarity_error(M, q, z) <= tol; else after max_sweeps.
LcpSolution solve_lcp_pgs(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, double tol, int32_t max_sweeps);

// Box LCP of frictional contact. Row r is a normal row when normal_index[r] < 0, with
//     z_r >= 0, w_r >= 0, z_r w_r = 0;
// otherwise a friction row bounded by its normal row n = normal_index[r] (itself a normal row):
//     -mu[r] z_n <= z_r <= mu[r] z_n, and
//     w_r = 0 when z_r is strictly inside the bounds, w_r >= 0 at the lower bound,
//     w_r <= 0 at the upper bound (when the bounds meet, z_r = 0 and w_r is free).
// mu is read on friction rows only (mu[r] >= 0). The bounds move with z_n, so this is not a
// plain LCP; PGS uses the current z_n for each friction row. Stops, solved, once
// box_lcp_error <= tol; else after max_sweeps. Rows with M_rr <= 0 are skipped.
LcpSolution solve_box_lcp_pgs(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                              const std::vector<int32_t>& normal_index, double tol, int32_t max_sweeps);

// Plain LCP: max over rows of max(-z_r, -w_r, |z_r w_r|) with w = M z + q; 0 for n = 0.
double complementarity_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z);

// Box LCP: max over rows of the natural residual |z_r - mid(lo_r, z_r - w_r, hi_r)|, with
// lo = 0, hi = +inf on normal rows and lo = -mu z_n, hi = mu z_n on friction rows; it is 0
// exactly when the conditions of solve_box_lcp_pgs hold.
double box_lcp_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                     const std::vector<int32_t>& normal_index, const Eigen::VectorXd& z);

}  // namespace mica
