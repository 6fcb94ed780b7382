// SPDX-License-Identifier: Apache-2.0
// Dense reference solvers for linear complementarity problems (LCP): given M (n x n) and q,
// find z with
//     z >= 0,   w = M z + q >= 0,   z_r w_r = 0 for every row r.
// Lemke's method is the exact reference (a finite pivoting method, lexicographic so that
// degenerate problems such as redundant contacts do not cycle); projected Gauss-Seidel is the
// iterative one. Meant for small problems (tens to a few hundred rows): everything is dense.
// Contact with Coulomb friction is not an LCP; its residual is here (cone_error), its solver in
// frictional_contact.hpp.
#pragma once
#include <Eigen/Dense>
#include <cstdint>
#include <string>
#include <vector>

namespace mica {

struct LcpSolution {
  Eigen::VectorXd z, w;  // the unknowns and w = M z + q, both of size n
  bool solved = false;   // false: ray termination, pivot or sweep limit, numerical breakdown
  bool ray = false;      // Lemke ended on a ray: for a copositive-plus M (positive semidefinite) the LCP has no solution
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

// Plain LCP: max over rows of max(-z_r, -w_r, |z_r w_r|) with w = M z + q; 0 for n = 0.
double complementarity_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z);

// Frictional contact with the isotropic Coulomb cone (friction_cone.hpp). Row r is a normal row
// when normal_index[r] < 0; otherwise a friction row of the contact whose normal row is
// n = normal_index[r] (itself a normal row); a contact has at most two friction rows, its
// tangents, which carry the same mu (mu is read on friction rows only, mu >= 0). With w = M z + q
// the conditions are, per contact c:
//     0 <= z_n  _|_  w_n >= 0,   |z_t| <= mu z_n,   and w_t = -beta z_t with beta >= 0 when
//     |z_t| = mu z_n > 0, w_t = 0 when |z_t| < mu z_n (z_t: the pair of tangent impulses).
// Returns the largest natural residual |z_c - P_c(z_c - rho_c w_c)| (2-norm over the contact's
// rows), P_c the cone projection with the disk's radius mu max(z_n, 0) from z itself and
// rho_c = 1 / the largest diagonal entry of M on the contact's rows (so the residual is an
// impulse, N s for a Delassus matrix); it is 0 exactly when the conditions hold (for any
// rho_c > 0). Throws Error(InvalidArgument) on mismatched sizes, a non-finite entry, a friction
// row that does not name a normal row, a third friction row, unequal mu on one contact, or a
// non-positive diagonal entry.
double cone_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                  const std::vector<int32_t>& normal_index, const Eigen::VectorXd& z);

// The contacts of such a problem: per contact its normal row, its friction rows (-1: absent) and mu.
// Validated as cone_error says (which throws on what this throws on).
struct ConeContact {
  int32_t normal;
  int32_t tangent[2];
  double mu;
};
std::vector<ConeContact> cone_contacts(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                       const std::vector<int32_t>& normal_index, const char* who);
// The same into contacts, with contact_of as scratch (no allocation once both have the capacity).
void cone_contacts(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                   const std::vector<int32_t>& normal_index, const char* who, std::vector<ConeContact>& contacts,
                   std::vector<int32_t>& contact_of);
// cone_error on validated contacts; w = M z + q given.
double cone_error(const Eigen::MatrixXd& M, const std::vector<ConeContact>& contacts, const Eigen::VectorXd& z,
                  const Eigen::VectorXd& w);

}  // namespace mica
