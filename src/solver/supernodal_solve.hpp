// SPDX-License-Identifier: Apache-2.0
// The triangular solve pair with CHOLMOD's supernodal LL^T factor, for one right-hand side,
// written out by hand, in double or, from a single-precision copy of the factor, in single.
// cholmod_solve2 makes two BLAS-2 calls per supernode and triangle; the velocity systems here
// have about a thousand supernodes of a few columns each (the nidus: 1078 of ~7.6), and the
// pair is bound by reading the factor from memory (9.4 MB on the nidus). The factored sweep's
// preconditioner needs no more than single precision (its projection and residuals stay in
// double): half the bytes to read. bench_factor prints all three; tests/solver/
// test_supernodal_solve.cpp holds them to cholmod_solve2.
#pragma once
#include <cholmod.h>

#include <Eigen/Dense>
#include <vector>

namespace mica {

class SupernodalSolve {
 public:
  // Reads L's structure (pointers into it: L must outlive the binding and not change) and, with
  // `single`, copies its values to single precision, kept when a solve with the copy agrees with
  // the double one to kSingleAgreement on a probe vector (single() says whether it was). False
  // when L is not a real supernodal LL^T with int indices; the solves must not be called then.
  bool bind(const cholmod_factor* L, bool single);
  static constexpr double kSingleAgreement = 1e-4;
  void unbind() { L_ = nullptr; }
  bool bound() const { return L_ != nullptr; }
  bool single() const { return bound() && !values_single_.empty(); }
  // x = A^-1 b for the factored A = P^T L L^T P; b and x may be the same array.
  void solve(const double* b, double* x) const;
  // The same with the single-precision copy (bind(L, true)): relative error ~1e-7 times A's
  // condition number.
  void solve_single(const double* b, double* x) const;

 private:
  template <class T>
  void run(const T* values, Eigen::Matrix<T, Eigen::Dynamic, 1>& w, Eigen::Matrix<T, Eigen::Dynamic, 1>& t,
           const double* b, double* x) const;

  const cholmod_factor* L_ = nullptr;
  const int *super_ = nullptr, *pi_ = nullptr, *px_ = nullptr, *s_ = nullptr, *perm_ = nullptr;
  const double* values_ = nullptr;
  std::vector<float> values_single_;
  // The permuted vector, and a supernode's rows below its columns (grown, never shrunk).
  mutable Eigen::VectorXd w_, t_;
  mutable Eigen::VectorXf w_single_, t_single_;
};

}  // namespace mica
