// SPDX-License-Identifier: Apache-2.0
#include "solver/lcp.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.hpp"
#include "solver/friction_cone.hpp"

namespace mica {

namespace {

void check_problem(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const char* who) {
  if (M.rows() != M.cols() || M.rows() != q.size())
    fail(Errc::InvalidArgument, std::string(who) + ": M is " + std::to_string(M.rows()) + " x " +
                                    std::to_string(M.cols()) + " and q has " + std::to_string(q.size()) +
                                    " entries; need n x n and n");
  if (!M.allFinite() || !q.allFinite())
    fail(Errc::InvalidArgument, std::string(who) + ": M or q has a non-finite entry");
}

// |x - y| small next to both: ties of the minimum-ratio test.
bool near_relative(double x, double y) {
  return std::fabs(x - y) <= 1e-11 * std::max(std::fabs(x), std::fabs(y));
}

// The Lemke tableau B^-1 [I  -M  -e  q] of w - M z - e z0 = q. Variables are numbered as its
// columns: w_i = i, z_i = n + i, z0 = 2n; column 2n + 1 holds the values of the basic ones.
// The first n columns are B^-1 itself, which the lexicographic rule reads.
class LemkeTableau {
 public:
  LemkeTableau(const Eigen::MatrixXd& M, const Eigen::VectorXd& q)
      : n_(int32_t(q.size())), T_(Eigen::MatrixXd::Zero(n_, 2 * n_ + 2)), basic_(size_t(n_)) {
    T_.leftCols(n_).setIdentity();
    T_.middleCols(n_, n_) = -M;
    T_.col(z0()).setConstant(-1.0);
    T_.col(rhs()) = q;
    for (int32_t i = 0; i < n_; ++i) basic_[size_t(i)] = i;
    for (int32_t j = 0; j < n_; ++j) column_scale_.push_back(std::max(1.0, M.col(j).cwiseAbs().maxCoeff()));
  }

  int32_t z0() const { return 2 * n_; }
  int32_t rhs() const { return 2 * n_ + 1; }
  int32_t basic(int32_t row) const { return basic_[size_t(row)]; }
  double value(int32_t row) const { return T_(row, rhs()); }
  // w_i <-> z_i.
  int32_t complement(int32_t var) const { return var < n_ ? var + n_ : var - n_; }

  // Makes `var` basic in `row` (Gauss-Jordan) and returns the variable that left.
  int32_t pivot(int32_t row, int32_t var) {
    const double pivot_entry = T_(row, var);  // a copy: /= takes its argument by reference
    T_.row(row) /= pivot_entry;
    const Eigen::RowVectorXd pivot_row = T_.row(row);
    Eigen::VectorXd factors = T_.col(var);
    factors(row) = 0.0;
    T_.noalias() -= factors * pivot_row;
    T_.col(var).setZero();
    T_(row, var) = 1.0;
    // Degenerate basic values come out as +-1e-17 instead of 0: make them exact zeros so
    // that ratio ties are seen as ties, and the basis stays feasible.
    const double scale = T_.col(rhs()).cwiseAbs().maxCoeff();
    for (int32_t i = 0; i < n_; ++i)
      if (std::fabs(T_(i, rhs())) <= 1e-13 * scale) T_(i, rhs()) = 0.0;
    const int32_t left = basic_[size_t(row)];
    basic_[size_t(row)] = var;
    return left;
  }

  // The row that leaves when `var` enters: minimum ratio value / column entry over positive
  // entries, ties broken lexicographically on the rows of B^-1 (scaled likewise), except that
  // z0 leaves whenever it is among the ties (that ends the method). -1: no positive entry, a ray.
  int32_t leaving_row(int32_t var) const {
    const auto column = T_.col(var);
    const double original_scale = var < n_ ? 1.0 : column_scale_[size_t(var - n_)];
    const double pivot_tol = 1e-11 * std::max(original_scale, column.cwiseAbs().maxCoeff());

    double best_ratio = std::numeric_limits<double>::infinity();
    for (int32_t i = 0; i < n_; ++i)
      if (column(i) > pivot_tol) best_ratio = std::min(best_ratio, value(i) / column(i));
    if (!std::isfinite(best_ratio)) return -1;

    std::vector<int32_t> ties;
    for (int32_t i = 0; i < n_; ++i)
      if (column(i) > pivot_tol && near_relative(value(i) / column(i), best_ratio)) ties.push_back(i);
    for (int32_t i : ties)
      if (basic(i) == z0()) return i;
    if (ties.size() == 1) return ties[0];
    return lexicographic_minimum(ties, var);
  }

 private:
  // Among rows tied on the ratio, the lexicographically smallest B^-1 row / column entry.
  // Rows of B^-1 are independent, so exactly one wins in exact arithmetic; entries closer
  // than round-off (relative to the largest in that column among the ties) count as equal.
  int32_t lexicographic_minimum(const std::vector<int32_t>& ties, int32_t var) const {
    int32_t best = ties[0];
    for (size_t t = 1; t < ties.size(); ++t) {
      const int32_t row = ties[t];
      for (int32_t k = 0; k < n_; ++k) {
        const double x = T_(row, k) / T_(row, var), y = T_(best, k) / T_(best, var);
        double scale = 0.0;
        for (int32_t i : ties) scale = std::max(scale, std::fabs(T_(i, k) / T_(i, var)));
        if (std::fabs(x - y) <= 1e-11 * scale) continue;
        if (x < y) best = row;
        break;
      }
    }
    return best;
  }

  int32_t n_;
  Eigen::MatrixXd T_;
  std::vector<int32_t> basic_;
  std::vector<double> column_scale_;  // max |M(:, j)|, at least 1: sets the pivot tolerance
};

double infinity_norm(const Eigen::VectorXd& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

// Complementarity row by row, each term against the size of what it is computed from:
// z against max(1, |z|), w against max(1, |q|, |M| |z|), z w against both; round-off makes
// it a few eps.
double relative_complementarity_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z) {
  const double m = M.size() ? M.cwiseAbs().rowwise().sum().maxCoeff() : 0.0;
  const double z_scale = std::max(1.0, infinity_norm(z));
  const double w_scale = std::max({1.0, infinity_norm(q), m * infinity_norm(z)});
  const Eigen::VectorXd w = M * z + q;
  double error = 0.0;
  for (Eigen::Index r = 0; r < z.size(); ++r)
    error = std::max({error, -z(r) / z_scale, -w(r) / w_scale, std::fabs(z(r) * w(r)) / (z_scale * w_scale)});
  return error;
}

// With the final complementary basis, w_i = 0 wherever z_i is basic, so z on that set solves
// M_ZZ z_Z = -q_Z (M_ZZ is invertible because the basis is). One solve with the original M
// removes the round-off the pivots accumulated; kept only when it does not make things worse.
Eigen::VectorXd polish(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z,
                       const std::vector<int32_t>& basic_z) {
  const Eigen::Index k = Eigen::Index(basic_z.size());
  if (k == 0) return z;
  Eigen::MatrixXd Mzz(k, k);
  Eigen::VectorXd rhs(k);
  for (Eigen::Index a = 0; a < k; ++a) {
    rhs(a) = -q(basic_z[size_t(a)]);
    for (Eigen::Index b = 0; b < k; ++b) Mzz(a, b) = M(basic_z[size_t(a)], basic_z[size_t(b)]);
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(Mzz);
  if (!lu.isInvertible()) return z;
  const Eigen::VectorXd sub = lu.solve(rhs);
  if (!sub.allFinite()) return z;
  Eigen::VectorXd polished = Eigen::VectorXd::Zero(z.size());
  for (Eigen::Index a = 0; a < k; ++a) polished(basic_z[size_t(a)]) = std::max(0.0, sub(a));
  return complementarity_error(M, q, polished) <= complementarity_error(M, q, z) ? polished : z;
}

std::string sweep_message(bool solved, int32_t sweeps, const char* what, double error) {
  char text[160];
  std::snprintf(text, sizeof text, "%s after %d sweeps, %s %.3g", solved ? "converged" : "sweep limit reached",
                int(sweeps), what, error);
  return text;
}

}  // namespace

double complementarity_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z) {
  const Eigen::VectorXd w = M * z + q;
  double error = 0.0;
  for (Eigen::Index r = 0; r < z.size(); ++r) error = std::max({error, -z(r), -w(r), std::fabs(z(r) * w(r))});
  return error;
}

LcpSolution solve_lcp_lemke(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, int32_t max_pivots) {
  check_problem(M, q, "solve_lcp_lemke");
  if (max_pivots < 0) fail(Errc::InvalidArgument, "solve_lcp_lemke: max_pivots must be >= 0");
  const int32_t n = int32_t(q.size());
  if (max_pivots == 0) max_pivots = std::max(50 * n, 1);

  LcpSolution s;
  s.z = Eigen::VectorXd::Zero(n);
  s.w = q;
  if (n == 0 || q.minCoeff() >= 0.0) {
    s.solved = true;
    s.message = "trivial solution: q >= 0, so z = 0";
    return s;
  }

  LemkeTableau tableau(M, q);
  // First pivot: z0 enters at the row of the most negative q; among equal minima the last
  // index is the lexicographic minimum of the rows [q_i, e_i].
  int32_t first = 0;
  for (int32_t i = 1; i < n; ++i)
    if (q(i) <= q(first)) first = i;
  int32_t entering = tableau.complement(tableau.pivot(first, tableau.z0()));
  s.pivots = 1;

  while (true) {
    if (s.pivots >= max_pivots) {
      s.message = "pivot limit reached: " + std::to_string(s.pivots) + " pivots without a solution";
      break;
    }
    const int32_t row = tableau.leaving_row(entering);
    if (row < 0) {
      s.ray = true;
      const std::string name = (entering < n ? "w_" : "z_") + std::to_string(entering % n);
      s.message = "ray termination after " + std::to_string(s.pivots) + " pivots (" + name +
                  " can grow without bound): the LCP has no solution, or M is not in a class Lemke's "
                  "method is guaranteed to solve (copositive-plus, P-matrix)";
      break;
    }
    const int32_t left = tableau.pivot(row, entering);
    ++s.pivots;
    if (left == tableau.z0()) {
      s.solved = true;
      break;
    }
    entering = tableau.complement(left);
  }
  if (!s.solved) return s;  // z = 0, w = q: the method has no meaningful partial answer

  std::vector<int32_t> basic_z;
  for (int32_t row = 0; row < n; ++row) {
    const int32_t var = tableau.basic(row);
    if (var >= n && var < 2 * n) {
      s.z(var - n) = std::max(0.0, tableau.value(row));
      basic_z.push_back(var - n);
    }
  }
  std::sort(basic_z.begin(), basic_z.end());
  s.z = polish(M, q, s.z, basic_z);
  s.w = M * s.z + q;

  // A sanity bound far above round-off: only a numerically broken pivot sequence fails it.
  const double error = relative_complementarity_error(M, q, s.z);
  if (!(error <= 1e-8)) {
    s.solved = false;
    char text[160];
    std::snprintf(text, sizeof text, "numerical breakdown: relative complementarity error %.3g after %d pivots", error,
                  int(s.pivots));
    s.message = text;
    return s;
  }
  s.message = "solved by Lemke's method in " + std::to_string(s.pivots) + " pivots";
  return s;
}

LcpSolution solve_lcp_pgs(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, double tol, int32_t max_sweeps) {
  check_problem(M, q, "solve_lcp_pgs");
  if (!(tol >= 0.0) || max_sweeps < 0) fail(Errc::InvalidArgument, "solve_lcp_pgs: need tol >= 0 and max_sweeps >= 0");
  const Eigen::Index n = q.size();
  const Eigen::MatrixXd Mt = M.transpose();  // rows of M as contiguous columns

  LcpSolution s;
  s.z = Eigen::VectorXd::Zero(n);
  double error = complementarity_error(M, q, s.z);
  while (error > tol && s.pivots < max_sweeps) {
    for (Eigen::Index r = 0; r < n; ++r) {
      const double d = M(r, r);
      if (!(d > 0.0)) continue;
      const double w_r = Mt.col(r).dot(s.z) + q(r);
      s.z(r) = std::max(0.0, s.z(r) - w_r / d);
    }
    ++s.pivots;
    error = complementarity_error(M, q, s.z);
  }
  s.w = M * s.z + q;
  s.solved = error <= tol;
  s.message = sweep_message(s.solved, s.pivots, "complementarity error", error);
  return s;
}

std::vector<ConeContact> cone_contacts(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                                       const std::vector<int32_t>& normal_index, const char* who) {
  std::vector<ConeContact> contacts;
  std::vector<int32_t> contact_of;
  cone_contacts(M, q, mu, normal_index, who, contacts, contact_of);
  return contacts;
}

void cone_contacts(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                   const std::vector<int32_t>& normal_index, const char* who, std::vector<ConeContact>& contacts,
                   std::vector<int32_t>& contact_of) {
  check_problem(M, q, who);
  const Eigen::Index n = q.size();
  if (mu.size() != n || Eigen::Index(normal_index.size()) != n)
    fail(Errc::InvalidArgument, std::string(who) + ": mu and normal_index need one entry per row");
  contacts.clear();
  contact_of.assign(size_t(n), -1);
  for (Eigen::Index r = 0; r < n; ++r) {
    if (!(M(r, r) > 0))
      fail(Errc::InvalidArgument, std::string(who) + ": row " + std::to_string(r) + " has no positive diagonal");
    if (normal_index[size_t(r)] >= 0) continue;
    contact_of[size_t(r)] = int32_t(contacts.size());
    contacts.push_back({int32_t(r), {-1, -1}, 0.0});
  }
  for (Eigen::Index r = 0; r < n; ++r) {
    const int32_t nr = normal_index[size_t(r)];
    if (nr < 0) continue;
    if (nr >= n || normal_index[size_t(nr)] >= 0)
      fail(Errc::InvalidArgument, std::string(who) + ": friction row " + std::to_string(r) +
                                      " must name a normal row, not " + std::to_string(nr));
    if (!(mu(r) >= 0.0) || !std::isfinite(mu(r)))
      fail(Errc::InvalidArgument, std::string(who) + ": mu of row " + std::to_string(r) + " must be finite and >= 0");
    ConeContact& c = contacts[size_t(contact_of[size_t(nr)])];
    if (c.tangent[1] >= 0)
      fail(Errc::InvalidArgument, std::string(who) + ": normal row " + std::to_string(nr) + " has a third friction row");
    if (c.tangent[0] >= 0 && mu(r) != c.mu)
      fail(Errc::InvalidArgument, std::string(who) + ": the friction rows of normal row " + std::to_string(nr) +
                                      " have different mu");
    c.tangent[c.tangent[0] >= 0 ? 1 : 0] = int32_t(r);
    c.mu = mu(r);
  }
}

double cone_error(const Eigen::MatrixXd& M, const std::vector<ConeContact>& contacts, const Eigen::VectorXd& z,
                  const Eigen::VectorXd& w) {
  double error = 0.0;
  for (const ConeContact& c : contacts) {
    double rho_inv = M(c.normal, c.normal);
    for (int32_t t : c.tangent)
      if (t >= 0) rho_inv = std::max(rho_inv, M(t, t));
    const double rho = 1.0 / rho_inv;
    double n = z(c.normal) - rho * w(c.normal);
    double t[2] = {0, 0};
    for (int k = 0; k < 2; ++k)
      if (c.tangent[k] >= 0) t[k] = z(c.tangent[k]) - rho * w(c.tangent[k]);
    n = std::max(n, 0.0);
    project_onto_disk(c.mu * std::max(z(c.normal), 0.0), t[0], t[1]);  // the disk of z, not of the step
    double e2 = std::pow(z(c.normal) - n, 2);
    for (int k = 0; k < 2; ++k)
      if (c.tangent[k] >= 0) e2 += std::pow(z(c.tangent[k]) - t[k], 2);
    if (!(std::sqrt(e2) <= error)) error = std::sqrt(e2);  // a NaN shows
  }
  return error;
}

double cone_error(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                  const std::vector<int32_t>& normal_index, const Eigen::VectorXd& z) {
  const std::vector<ConeContact> contacts = cone_contacts(M, q, mu, normal_index, "cone_error");
  if (z.size() != q.size()) fail(Errc::InvalidArgument, "cone_error: z needs one entry per row");
  return cone_error(M, contacts, z, M * z + q);
}

}  // namespace mica
