// SPDX-License-Identifier: Apache-2.0
// The triangular solve pair with CHOLMOD's supernodal LL^T factor, for one right-hand side,
// written out by hand, in double or from a copy of the factor in single or half precision.
// Why beside CHOLMOD, which factors: the factored sweep solves one right-hand side at a time,
// and a contact node's half columns are a forward solve of a sparse one (its three unit
// columns). CHOLMOD's sparse right-hand side (cholmod_solve2's Bset) works on simplicial factors
// only: it turns a supernodal factor simplicial, for good. For a dense one, cholmod_solve2 makes
// two BLAS-2 calls per supernode and triangle, where the velocity systems here have about a
// thousand supernodes of a few columns each (the nidus: 1101 of ~7.5), and the pair is bound by
// reading the factor from memory (8.6 MB on the nidus). The factored sweep's preconditioner
// needs no more than the copy's precision (its projection and residuals stay in double): a half
// or a quarter of the bytes to read. On the nidus a pair takes 0.419 ms with cholmod_solve2 and
// 0.137 ms by hand from the half copy (0.385 in double, 0.243 in single; bench_factor, no node
// held: docs/performance.md's factorization table); tests/solver/test_supernodal_solve.cpp
// holds them to cholmod_solve2.
#pragma once
#include <cholmod.h>

#include <Eigen/Dense>
#include <functional>
#include <vector>

#include "core/types.hpp"

namespace mica {

// The copies' unit of work: a run of at most SupernodalSolve::kInvertedWidth columns of one
// supernode with the supernode's rows from its first column down, [D; E] with D lower triangular.
// In the copies D is inverted: [D^-1; E D^-1].
struct SupernodePanel {
  int32_t column, width, rows, ld;  // its first (permuted) column, columns, rows, leading dimension
  int64_t at;                        // its first value, in L->x's layout
  int32_t row_at;                    // its first row's index in L->s
  // In the copies each panel is a block of its own, its rows padded with zeros to a multiple of 8
  // (the leading dimension): the half kernels then run on whole vectors of 8, with no scalar rows.
  int64_t copy_at;
  int32_t copy_rows;
};
struct CopyView;

class SupernodalSolve {
 public:
  // The copy of the factor the "single" solves read: none, single precision, or half precision
  // where the CPU has the instructions for it (half_products.hpp; single otherwise).
  enum class Copy : uint8_t { None, Single, Half };
  // Reads L's structure (pointers into it: L must outlive the binding and not change) and makes
  // the copy, kept when a solve with it agrees with the double one on a probe vector to
  // kSingleAgreement (single precision) or kHalfAgreement with a residual below kHalfResidual
  // (half; the single copy is tried when it does not).
  // single() says whether a copy was kept, half() whether it is the half one. False when L is not
  // a real supernodal LL^T with int indices; the solves must not be called then.
  // multiply(x, y): y = A x for the factored A (the half copy's residual; without it no half copy).
  using Multiply = std::function<void(const double* x, double* y)>;
  bool bind(const cholmod_factor* L, Copy copy, const Multiply& multiply = nullptr);
  static constexpr double kSingleAgreement = 1e-4;
  // Half precision's 5e-4 times the system's condition: on the nidus the probe agrees to 2.8e-4.
  static constexpr double kHalfAgreement = 1e-3;
  // And the half copy's residual must be below half the probe's size: a preconditioner that
  // overshoots the stiff directions (a nearly incompressible body's, 3e5 times the probe, where
  // the single copy's is 250) slows the conjugate gradients to hundreds of iterations. The
  // nidus's is 0.18, a 35k-tet cube's 0.011.
  static constexpr double kHalfResidual = 0.5;
  // The copies split each supernode into panels of up to this many columns and keep each panel
  // inverted, [D^-1; E D^-1]: both halves of the pair are then products, with no triangular solve
  // (make_copy says why). 16 rather than 64: a quarter of the inversion's work, the same pair
  // (0.231 against 0.251 ms on the nidus).
  static constexpr int kInvertedWidth = 16;
  // The most columns of any supernode (0 unbound).
  int32_t widest_supernode() const;
  void unbind() { L_ = nullptr; }
  bool bound() const { return L_ != nullptr; }
  int64_t rows() const { return bound() ? int64_t(L_->n) : 0; }  // of the factor (3 per node)
  bool single() const { return bound() && (!values_single_.empty() || !values_half_.empty()); }
  bool half() const { return bound() && !values_half_.empty(); }
  // Forgets L's values (bound, with a copy kept): the owner frees them, keeping L's structure, and
  // from then on every solve, the half columns included, reads the copy (DirectSolver::factorize
  // with keep_double false: the factored sweep's factor is a quarter of the memory).
  void release_double();
  bool double_kept() const { return bound() && values_ != nullptr; }
  // x = A^-1 b for the factored A = P^T L L^T P (with the copy once the double is released); b and
  // x may be the same array.
  void solve(const double* b, double* x) const;
  // The same with the copy (bind with Copy::Single or Copy::Half): relative error ~1e-7 (single)
  // or ~5e-4 (half) times A's condition number.
  void solve_single(const double* b, double* x) const;

  // A node's half columns L^-1 P E, E the three unit columns of DOFs first .. first + 2: nonzero
  // only on the supernodes of their path up the elimination tree (a few hundred of the nidus's
  // 8208 rows), kept as those segments. With them, A^-1 E = P^T L^-T H and E^T A^-1 E' = H^T H'.
  // With a copy, they are the copy's (its panels are the segments): the compliance H^T H' is then
  // that of the preconditioner whose halves they correct, and the double factor is not needed.
  struct HalfColumns {
    std::vector<int32_t> start, length;              // the segments' first permuted row, rows
    Eigen::Matrix<double, Eigen::Dynamic, 3> values;  // their rows, one segment after another
  };
  void half_columns(int32_t first, HalfColumns& out) const;
  // H^T H' (E^T A^-1 E').
  static Mat3 product(const HalfColumns& a, const HalfColumns& b);
  // The solve pair in halves, with what lies between them in the caller's hands (the factored
  // sweep's correction of its preconditioner, factored_mica.cpp): forward(b) keeps w = L^-1 P b;
  // dot(H) = H^T w; add(H, f): w += H f; clear(single): w = 0 instead of forward(); backward(x):
  // x = P^T L^-T w. With `single` and the copy, the halves run in single precision (w is kept in
  // single: dot sums in double, add rounds H f): x along E is then H^T w only to single's
  // precision, and a caller that needs it exact puts back the values it knows. b and x hold
  // 3-DOF nodes; with `turn`, b's node i is turned by turn_i^T on the way in and x's by turn_i on
  // the way out (the warped factor's Q, lagged_factor.hpp), in the same pass as the permutation.
  void forward(const double* b, bool single, const Mat3* turn = nullptr) const;
  Vec3 dot(const HalfColumns& h) const;
  void add(const HalfColumns& h, const Vec3& f) const;
  void clear(bool single) const {
    halves_single_ = (single || !values_) && this->single();
    if (halves_single_) w_single_.setZero();
    else w_.setZero();
  }
  void backward(double* x, const Mat3* turn = nullptr) const;

  // A bridge (LaggedFactor::remap): the factor of K serves the system of a body whose topology
  // changed since (a cut), until that system's own factor is ready. Node i of the new numbering
  // is served by the factor's node factor_node[i]; a cut node's copies share their node's. In the
  // basis Q = [T^T, V] (T^T y gives each node its factor node's value, the coarse part; V's columns
  // d_k = (e_p - e_c) / sqrt 2 move a copy c = copy[k].first against its node p = copy[k].second)
  // the new system is Q^T A Q = [K B; B^T C]: its coarse block is the factor's own (T A T^T = K
  // when A is the cut mesh's system as of the factor: LaggedFactor::remap), and B (3 rows per
  // factor node, in its order, 3 columns per copy) and C (3 per copy) are given. Its Cholesky
  // factor is [L 0; H^T L_S] with H = L^-1 P B (made here, with the double factor, which must be
  // kept) and L_S L_S^T = C - H^T H (the Schur complement: the copies' modes with everything else
  // free); the halves solve with it, A^-1 = Q (Q^T A Q)^-1 Q^T. So the bridged preconditioner is
  // as near the cut body's system as the factor was to the uncut one. Factor nodes no node maps
  // to (a resection) get no input. Every solve, half and half column follows the bridge; the
  // next bind() ends it. False (no bridge) when the double factor was not kept.
  bool bridge(const std::vector<int32_t>& factor_node, const std::vector<std::pair<int32_t, int32_t>>& copy,
              const Eigen::MatrixXd& B, const Eigen::MatrixXd& C);
  bool bridged() const { return !factor_inverse_perm_.empty(); }

 private:
  // The panels of L's supernodes (kInvertedWidth).
  void make_panels();
  // The single- or half-precision copy, its panels inverted; a half panel is scaled by a power of
  // two that puts its largest entry at half's top binade (half's range is 6e-5..65504).
  void make_copy(Copy kind);
  // How the copy's solve x = solve_single(b) of a fixed vector b fares: its relative difference
  // from the double solve, and (with multiply) its relative residual |b - A x| / |b|.
  struct Probe {
    double difference, residual;
  };
  Probe probe_copy(const Multiply& multiply) const;
  // The halves on the permuted vector: w_ with L in double, w_single_ with the copy.
  void forward_double() const;
  void backward_double() const;
  CopyView copy_view() const;  // the copy, as the passes read it
  void forward_single() const;
  void backward_single() const;
  void half_columns_double(int32_t first, HalfColumns& out) const;
  void half_columns_copy(int32_t first, HalfColumns& out) const;

  const cholmod_factor* L_ = nullptr;
  const int *super_ = nullptr, *pi_ = nullptr, *px_ = nullptr, *s_ = nullptr;
  const double* values_ = nullptr;
  std::vector<SupernodePanel> panels_;
  std::vector<int32_t> first_panel_;  // per supernode its first panel, and one past the last
  int64_t copy_size_ = 0;  // the copies' entries (the panels', padded)
  std::vector<float> values_single_;
  // The half copy (empty: the single copy alone), in place of the single one once kept: a
  // panel's value = stored half * its unscale.
  std::vector<uint16_t> values_half_;
  std::vector<float> half_unscale_;
  std::vector<int32_t> inverse_perm_;  // a DOF's permuted row
  // The permuted vector, and a supernode's rows below its columns (grown, never shrunk).
  mutable Eigen::VectorXd w_, t_;
  mutable Eigen::VectorXf w_single_;
  mutable Eigen::VectorXf y_single_;      // a panel's rows (the single halves')
  mutable Eigen::VectorXf below_single_;  // a supernode's rows below its columns (the forward half's)
  mutable Eigen::Matrix<double, Eigen::Dynamic, 3> w3_, t3_;  // half_columns' (w3_ zero between calls)
  mutable Eigen::Matrix<float, Eigen::Dynamic, 3> w3_single_;  // the copy's half columns' (zero between calls)
  mutable bool halves_single_ = false;                       // forward() left w in w_single_
  // The bridge (bridge()): the factor's own inverse_perm_ (empty: none), the copies' modes, H
  // (rows permuted as w's), L_S, and each node's modes (k, and the sign of its part in d_k).
  std::vector<int32_t> factor_inverse_perm_;
  std::vector<std::pair<int32_t, int32_t>> bridge_copy_;
  Eigen::MatrixXd bridge_H_, bridge_LS_;
  mutable Eigen::VectorXd bridge_t_;  // a mode vector's scratch
  std::vector<int32_t> mode_start_;
  std::vector<std::pair<int32_t, double>> mode_;
  Eigen::Index factor_rows() const { return Eigen::Index(L_->n); }
  // The bridged halves around the factor's: T b into w's factor rows; after the forward pass, the
  // modes' rows L_S^-1 (V^T b - H^T w); before the backward pass, z = L_S^-T (modes' rows) and
  // w -= H z; after it, x = T^T w + V z.
  template <class T>
  void bridge_gather(const double* b, const Mat3* turn, T* w) const;
  template <class T>
  void bridge_modes_forward(const double* b, const Mat3* turn, T* w) const;
  template <class T>
  void bridge_modes_backward(T* w) const;
  template <class T>
  void bridge_scatter(const T* w, const Mat3* turn, double* x) const;
};

}  // namespace mica
