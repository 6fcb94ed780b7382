// SPDX-License-Identifier: Apache-2.0
// Random LCPs with fixed seeds, shared by test_lcp.cpp and test_lcp_oracle.cpp. No cmocka
// here: include this before "test_util.hpp".
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "solver/lcp.hpp"

namespace lcp_problems {

struct Problem {
  Eigen::MatrixXd M;
  Eigen::VectorXd q;
};

// Uniform in [lo, hi) from the raw 32-bit output, so the numbers are the same with every
// standard library (the std distributions are implementation-defined).
class Rng {
 public:
  explicit Rng(uint32_t seed) : g_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * (double(g_()) / 4294967296.0); }
  int32_t index(int32_t n) { return int32_t(g_() % uint32_t(n)); }
  Eigen::MatrixXd matrix(Eigen::Index rows, Eigen::Index cols) {
    Eigen::MatrixXd A(rows, cols);
    for (Eigen::Index j = 0; j < cols; ++j)
      for (Eigen::Index i = 0; i < rows; ++i) A(i, j) = uniform(-1, 1);
    return A;
  }
  Eigen::VectorXd vector(Eigen::Index n) { return matrix(n, 1).col(0); }

 private:
  std::mt19937 g_;
};

// M = A A^T + 0.1 I, symmetric positive definite: the LCP has exactly one solution.
inline Problem spd(int32_t n, uint32_t seed) {
  Rng rng(seed);
  const Eigen::MatrixXd A = rng.matrix(n, n);
  Problem p;
  p.M = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
  p.q = 2.0 * rng.vector(n);
  return p;
}

// Redundant contacts: n rows that copy rows of an SPD base problem of m < n rows (every base
// row at least once). M = P M0 P^T is positive semidefinite and singular. With same_q the
// copies have the same q too (exact ties everywhere, the most degenerate case); otherwise each
// copy gets its own q. Either way a solution exists: only the smallest q of a group matters.
struct Duplicated {
  Problem problem, base;
  std::vector<int32_t> source;  // base row of each row
};
inline Duplicated duplicated(int32_t m, int32_t n, uint32_t seed, bool same_q) {
  Duplicated d;
  d.base = spd(m, seed);
  Rng rng(seed + 7919u);
  for (int32_t i = 0; i < n; ++i) d.source.push_back(i < m ? i : rng.index(m));
  for (int32_t i = n - 1; i > 0; --i) std::swap(d.source[size_t(i)], d.source[size_t(rng.index(i + 1))]);
  d.problem.M.resize(n, n);
  d.problem.q.resize(n);
  for (int32_t i = 0; i < n; ++i) {
    d.problem.q(i) = same_q ? d.base.q(d.source[size_t(i)]) : 2.0 * rng.uniform(-1, 1);
    for (int32_t j = 0; j < n; ++j) d.problem.M(i, j) = d.base.M(d.source[size_t(i)], d.source[size_t(j)]);
  }
  return d;
}

// M = B B^T with B n x k, k < n: positive semidefinite of rank k. q = s - M x with x >= 0,
// s >= 0 and x_i s_i = 0, so (x, s) is a solution and the problem is feasible (a random q
// would often not be).
inline Problem low_rank(int32_t n, int32_t k, uint32_t seed) {
  Rng rng(seed);
  const Eigen::MatrixXd B = rng.matrix(n, k);
  Problem p;
  p.M = B * B.transpose();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), s = Eigen::VectorXd::Zero(n);
  for (int32_t i = 0; i < n; ++i) {
    const double r = rng.uniform(0, 1);
    if (r < 0.4) x(i) = rng.uniform(0.1, 1.0);
    else if (r < 0.8) s(i) = rng.uniform(0.1, 1.0);  // else both zero: a degenerate row
  }
  p.q = s - p.M * x;
  return p;
}

inline double inf_norm(const Eigen::VectorXd& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

// The worst row of complementarity, each term against its own scale: -z_r against
// max(1, |z|), -w_r against what w is summed from, max(1, |q|, |M| |z|), and |z_r w_r|
// against the product of the two.
inline double relative_complementarity(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z) {
  const double m = M.size() ? M.cwiseAbs().rowwise().sum().maxCoeff() : 0.0;
  const double z_scale = std::max(1.0, inf_norm(z));
  const double w_scale = std::max({1.0, inf_norm(q), m * inf_norm(z)});
  const Eigen::VectorXd w = M * z + q;
  double error = 0.0;
  for (Eigen::Index r = 0; r < z.size(); ++r)
    error = std::max({error, -z(r) / z_scale, -w(r) / w_scale, std::fabs(z(r) * w(r)) / (z_scale * w_scale)});
  return error;
}

// |a - b| relative to max(1, |b|), in the infinity norm.
inline double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return inf_norm(a - b) / std::max(1.0, inf_norm(b));
}

}  // namespace lcp_problems
