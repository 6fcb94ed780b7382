// SPDX-License-Identifier: Apache-2.0
#include "solver/supernodal_solve.hpp"

#include <algorithm>
#include <cmath>

#include "core/assert.hpp"
#include "solver/half_products.hpp"

namespace mica {

bool SupernodalSolve::bind(const cholmod_factor* L, Copy copy, const Multiply& multiply) {
  L_ = nullptr;
  values_single_.clear();
  values_half_.clear();
  factor_inverse_perm_.clear();  // a new factor ends a bridge
  bridge_copy_.clear();
  bridge_H_.resize(0, 0);
  bridge_LS_.resize(0, 0);
  if (!L || !L->is_super || !L->is_ll || L->xtype != CHOLMOD_REAL || L->dtype != CHOLMOD_DOUBLE ||
      L->itype != CHOLMOD_INT || !L->x)
    return false;
  super_ = static_cast<const int*>(L->super);
  pi_ = static_cast<const int*>(L->pi);
  px_ = static_cast<const int*>(L->px);
  s_ = static_cast<const int*>(L->s);
  const int* perm = static_cast<const int*>(L->Perm);
  values_ = static_cast<const double*>(L->x);
  const Eigen::Index n = Eigen::Index(L->n), below = Eigen::Index(L->maxesize > 0 ? L->maxesize : 1);
  w_.resize(n);
  t_.resize(below);
  w3_.setZero(n, 3);
  t3_.resize(below, 3);
  inverse_perm_.resize(size_t(n));
  for (Eigen::Index i = 0; i < n; ++i) inverse_perm_[size_t(perm[i])] = int32_t(i);
  L_ = L;
  if (copy == Copy::None) return true;
  // A copy is kept only where its precision holds: float's 6e-8 (half's 5e-4) grows with the
  // condition of the system (a nearly incompressible, very stiff body's is far too large), and a
  // preconditioner that far off misleads the solves.
  make_panels();
  w_single_.resize(n);
  w3_single_.setZero(n, 3);
  if (copy == Copy::Half && multiply && half_products_supported()) {
    make_copy(Copy::Half);
    const Probe half = probe_copy(multiply);
    if (half.difference <= kHalfAgreement && half.residual <= kHalfResidual) return true;
    values_half_.clear();
  }
  make_copy(Copy::Single);
  if (!(probe_copy(nullptr).difference <= kSingleAgreement)) values_single_.clear();
  return true;
}

void SupernodalSolve::release_double() {
  MICA_ASSERT(single(), "the double factor is released only where a copy serves the solves");
  values_ = nullptr;
  w_.resize(0);  // the double halves' workspaces
  t_.resize(0);
  w3_.resize(0, 3);
  t3_.resize(0, 3);
}

SupernodalSolve::Probe SupernodalSolve::probe_copy(const Multiply& multiply) const {
  const Eigen::Index n = Eigen::Index(L_->n);
  Eigen::VectorXd probe(n), in_double(n), in_copy(n), product(n);
  for (Eigen::Index i = 0; i < n; ++i) probe[i] = std::sin(0.7 * double(i)) + 0.5;
  solve(probe.data(), in_double.data());
  solve_single(probe.data(), in_copy.data());
  Probe out{(in_copy - in_double).norm() / in_double.norm(), 0};
  if (multiply) {
    multiply(in_copy.data(), product.data());
    out.residual = (probe - product).norm() / probe.norm();
  }
  return out;
}

void SupernodalSolve::solve(const double* b, double* x) const {
  forward(b, false);
  backward(x);
}

void SupernodalSolve::solve_single(const double* b, double* x) const {
  forward(b, true);
  backward(x);
}

namespace {

// A supernode k holds columns super[k] .. super[k+1) of L as a dense block (column-major, nr
// rows, leading dimension nr): its diagonal block on top, then the rows s[pi[k] + nc ..].
struct Supernode {
  Supernode(const double* values, const int* super, const int* pi, const int* px, const int* s, Eigen::Index k)
      : c0(super[k]), nc(super[k + 1] - c0), below(pi[k + 1] - pi[k] - nc), rows(s + pi[k] + nc),
        X(values + px[k], nc + below, nc, Eigen::OuterStride<>(nc + below)) {}
  Eigen::Index c0, nc, below;
  const int* rows;  // the rows below the diagonal block
  Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> X;
};

}  // namespace

int32_t SupernodalSolve::widest_supernode() const {
  int32_t widest = 0;
  for (int k = 0; L_ && k < int(L_->nsuper); ++k) widest = std::max(widest, int32_t(super_[k + 1] - super_[k]));
  return widest;
}

void SupernodalSolve::make_panels() {
  panels_.clear();
  first_panel_.assign(1, 0);
  copy_size_ = 0;
  int tallest = 1, below = 1;
  for (int k = 0; k < int(L_->nsuper); ++k) {
    const int c0 = super_[k], nc = super_[k + 1] - c0, nr = pi_[k + 1] - pi_[k];
    tallest = std::max(tallest, nr);
    below = std::max(below, nr - nc);
    for (int a = 0; a < nc; a += kInvertedWidth) {
      const int width = std::min(kInvertedWidth, nc - a), rows = nr - a, padded = (rows + 7) / 8 * 8;
      panels_.push_back({c0 + a, width, rows, nr, int64_t(px_[k]) + int64_t(a) * nr + a, pi_[k] + a, copy_size_, padded});
      copy_size_ += int64_t(padded) * width;
    }
    first_panel_.push_back(int32_t(panels_.size()));
  }
  // A panel's rows padded to a multiple of 8, and 8 more: backward_pass's zeros after its rows.
  y_single_.resize((tallest + 7) / 8 * 8 + 8);
  below_single_.resize(below);
}

void SupernodalSolve::make_copy(Copy kind) {
  // Each panel [D; E] of a supernode (D its lower-triangular diagonal block) becomes
  // [D^-1; E D^-1]: then its forward half is one product, y = [D^-1; E D^-1] x, and its backward
  // half x = D^-T x - (E D^-1)^T t another, with no triangular solve in either. A triangular solve
  // of a few columns runs at a fraction of a product's speed: it was a third of the pair's time on
  // the nidus, whose 1101 supernodes have ~7.5 columns. A wider supernode (a top separator, up to
  // 459 columns on the nidus) is a chain of panels of kInvertedWidth columns, each inverted alone:
  // a panel costs its rows times its width squared, where inverting all of D would cost more than
  // the factorization; and D's triangular solve, in Eigen, took 9 % of a nidus step.
  const bool half = kind == Copy::Half;
  const Eigen::Index tallest = y_single_.size();
  Eigen::MatrixXd Yd(half ? 0 : tallest, kInvertedWidth);
  Eigen::MatrixXf Yf(half ? tallest : 0, kInvertedWidth), Df(kInvertedWidth, kInvertedWidth);
  if (half) {
    values_half_.assign(size_t(copy_size_), 0);
    half_unscale_.assign(panels_.size(), 1.0f);
  } else {
    values_single_.assign(size_t(copy_size_), 0.0f);
  }
  for (size_t q = 0; q < panels_.size(); ++q) {
    const SupernodePanel& p = panels_[q];
    const int nc = p.width, nr = p.rows;
    const Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> X(values_ + p.at, nr, nc,
                                                                          Eigen::OuterStride<>(p.ld));
    if (!half) {  // Y = [I; E] D^-1 in double (Eigen's blocked triangular solve), then rounded
      auto y = Yd.topLeftCorner(nr, nc);
      y.topRows(nc).setIdentity();
      y.bottomRows(nr - nc) = X.bottomRows(nr - nc);
      X.topRows(nc).triangularView<Eigen::Lower>().solveInPlace<Eigen::OnTheRight>(y);
      Eigen::Map<Eigen::MatrixXf, 0, Eigen::OuterStride<>>(values_single_.data() + p.copy_at, nr, nc,
                                                           Eigen::OuterStride<>(p.copy_rows)) = y.cast<float>();
      continue;
    }
    // The half copy: the same in single (it is rounded to half after, and a background refresh has
    // to make it between two adoptions: 2.0 against 2.9 ms on the nidus), scaled by a power of two
    // that puts the largest entry in [2^14, 2^15).
    auto y = Yf.topLeftCorner(nr, nc);
    auto d = Df.topLeftCorner(nc, nc);
    d = X.topRows(nc).cast<float>();
    y.topRows(nc).setIdentity();
    y.bottomRows(nr - nc) = X.bottomRows(nr - nc).cast<float>();
    d.triangularView<Eigen::Lower>().solveInPlace<Eigen::OnTheRight>(y);
    const float largest = y.cwiseAbs().maxCoeff();
    int exponent = 0;
    std::frexp(largest, &exponent);  // largest < 2^exponent
    const int shift = largest > 0 ? 15 - exponent : 0;
    half_unscale_[q] = std::ldexp(1.0f, -shift);
    for (int j = 0; j < nc; ++j)
      to_half(y.col(j).data(), size_t(nr), std::ldexp(1.0f, shift), values_half_.data() + p.copy_at + int64_t(j) * p.copy_rows);
  }
}

// The copy, as the passes below read it: the single one, or the half one with its scales.
struct CopyView {
  const std::vector<SupernodePanel>& panels;
  const std::vector<int32_t>& first_panel;  // per supernode its first panel, and one past the last
  const int* s;
  const float* single;
  const uint16_t* half;  // null: the single copy
  const float* unscale;
};

namespace {

// y = B x, B panel q of the copy ([D^-1; E D^-1], zero above the diagonal); the half product
// also writes the padding's rows (zero).
void panel_product(const CopyView& c, size_t q, const float* x, float* y) {
  const SupernodePanel& p = c.panels[q];
  if (c.half) return half_product(c.half + p.copy_at, p.copy_rows, p.copy_rows, p.width, x, c.unscale[q], y);
  const float* B = c.single + p.copy_at;
  for (int i = 0; i < p.rows; ++i) y[i] = 0;
  for (int j = 0; j < p.width; ++j) {  // column j of the top block is zero above row j
    const float a = x[j];
    const float* col = B + size_t(j) * size_t(p.copy_rows);
    for (int i = j; i < p.rows; ++i) y[i] += col[i] * a;
  }
}

// x = B^T y, B as above; y has the padding's rows too (zero).
void panel_transposed_product(const CopyView& c, size_t q, const float* y, float* x) {
  const SupernodePanel& p = c.panels[q];
  if (c.half) return half_transposed_product(c.half + p.copy_at, p.copy_rows, p.copy_rows, p.width, y, c.unscale[q], x);
  const float* B = c.single + p.copy_at;
  for (int j = 0; j < p.width; ++j) {
    const float* col = B + size_t(j) * size_t(p.copy_rows);
    x[j] = Eigen::Map<const Eigen::VectorXf>(col + j, p.rows - j).dot(Eigen::Map<const Eigen::VectorXf>(y + j, p.rows - j));
  }
}

// Panel q's part of the forward half on w: y = B x, x its columns' entries of w (x is written
// only after the product).
void forward_panel(const CopyView& c, size_t q, float* w, float* y) {
  const SupernodePanel& p = c.panels[q];
  float* x = w + p.column;
  panel_product(c, q, x, y);
  for (int i = 0; i < p.width; ++i) x[i] = y[i];
  const int* rows = c.s + p.row_at;
  for (int i = p.width; i < p.rows; ++i) w[rows[i]] -= y[i];
}

// A panel's rows are its supernode's columns from its own on (contiguous in w), then the
// supernode's rows below its columns (scattered in w). A supernode of several panels sums its
// panels' parts of the rows below in `below` and scatters them once, where each panel would
// scatter them again: on the nidus, 33 k scattered rows a pass instead of 67 k.
void forward_pass(const CopyView& c, float* w, float* y, float* below) {
  for (size_t k = 0; k + 1 < c.first_panel.size(); ++k) {
    const size_t q0 = size_t(c.first_panel[k]), q1 = size_t(c.first_panel[k + 1]);
    if (q1 - q0 == 1) {
      forward_panel(c, q0, w, y);
      continue;
    }
    const SupernodePanel& last = c.panels[q1 - 1];
    const int nb = last.rows - last.width;
    std::fill(below, below + nb, 0.0f);
    for (size_t q = q0; q < q1; ++q) {
      const SupernodePanel& p = c.panels[q];
      float* x = w + p.column;
      panel_product(c, q, x, y);
      const int inside = p.rows - nb;  // the supernode's columns from this panel's on
      for (int i = 0; i < p.width; ++i) x[i] = y[i];
      for (int i = p.width; i < inside; ++i) x[i] -= y[i];
      for (int i = 0; i < nb; ++i) below[i] += y[inside + i];
    }
    const int* rows = c.s + last.row_at + last.width;
    for (int i = 0; i < nb; ++i) w[rows[i]] -= below[i];
  }
}

// x = B^T [x; -t], t the rows' solved entries of w. Each supernode gathers the rows below its
// columns once, into the end of y (then 8 zeros: the padding), where every panel's y ends.
void backward_pass(const CopyView& c, float* w, float* y, int size) {
  float* end = y + size - 8;
  for (size_t k = c.first_panel.size() - 1; k-- > 0;) {
    const size_t q0 = size_t(c.first_panel[k]), q1 = size_t(c.first_panel[k + 1]);
    const SupernodePanel& last = c.panels[q1 - 1];
    const int nb = last.rows - last.width;
    const int* rows = c.s + last.row_at + last.width;
    float* tail = end - nb;
    for (int i = 0; i < nb; ++i) tail[i] = -w[rows[i]];
    std::fill(end, end + 8, 0.0f);
    for (size_t q = q1; q-- > q0;) {
      const SupernodePanel& p = c.panels[q];
      float* x = w + p.column;
      const int inside = p.rows - nb;
      float* yp = tail - inside;
      for (int i = 0; i < p.width; ++i) yp[i] = x[i];
      for (int i = p.width; i < inside; ++i) yp[i] = -x[i];
      panel_transposed_product(c, q, yp, x);
    }
  }
}

}  // namespace

CopyView SupernodalSolve::copy_view() const {
  const bool half = !values_half_.empty();
  return {panels_, first_panel_, s_, values_single_.data(), half ? values_half_.data() : nullptr, half_unscale_.data()};
}

void SupernodalSolve::forward_single() const {
  forward_pass(copy_view(), w_single_.data(), y_single_.data(), below_single_.data());
}

void SupernodalSolve::backward_single() const {
  backward_pass(copy_view(), w_single_.data(), y_single_.data(), int(y_single_.size()));
}

void SupernodalSolve::forward_double() const {
  for (Eigen::Index k = 0; k < Eigen::Index(L_->nsuper); ++k) {  // L w' = w
    const Supernode sn(values_, super_, pi_, px_, s_, k);
    auto xk = w_.segment(sn.c0, sn.nc);
    sn.X.topRows(sn.nc).triangularView<Eigen::Lower>().solveInPlace(xk);
    if (sn.below == 0) continue;
    auto t = t_.head(sn.below);
    t.noalias() = sn.X.bottomRows(sn.below) * xk;
    for (Eigen::Index i = 0; i < sn.below; ++i) w_[sn.rows[i]] -= t[i];
  }
}

void SupernodalSolve::backward_double() const {
  for (Eigen::Index k = Eigen::Index(L_->nsuper) - 1; k >= 0; --k) {  // L^T w' = w
    const Supernode sn(values_, super_, pi_, px_, s_, k);
    auto xk = w_.segment(sn.c0, sn.nc);
    if (sn.below > 0) {
      auto t = t_.head(sn.below);
      for (Eigen::Index i = 0; i < sn.below; ++i) t[i] = w_[sn.rows[i]];
      xk.noalias() -= sn.X.bottomRows(sn.below).transpose() * t;
    }
    sn.X.topRows(sn.nc).triangularView<Eigen::Lower>().transpose().solveInPlace(xk);
  }
}

bool SupernodalSolve::bridge(const std::vector<int32_t>& factor_node,
                             const std::vector<std::pair<int32_t, int32_t>>& copy, const Eigen::MatrixXd& B,
                             const Eigen::MatrixXd& C) {
  MICA_ASSERT(bound(), "a bridge needs a factor");
  const Eigen::Index n = factor_rows(), m = 3 * Eigen::Index(copy.size());
  MICA_ASSERT(B.rows() == n && B.cols() == m && C.rows() == m && C.cols() == m, "B and C fit the factor and copies");
  if (!double_kept()) return false;
  // Everything new first (this may throw), then swapped in.
  std::vector<int32_t> base = bridged() ? factor_inverse_perm_ : inverse_perm_;  // the factor's own
  // H = L^-1 P B, in double, each column by the forward pass (w_ is the double halves' workspace).
  Eigen::MatrixXd H(n, m);
  w_.resize(n + m);
  for (Eigen::Index k = 0; k < m; ++k) {
    for (Eigen::Index r = 0; r < n; ++r) w_[base[size_t(r)]] = B(r, k);
    forward_double();
    H.col(k) = w_.head(n);
  }
  if (single()) w_single_.resize(n + m);
  // S = C - H^T H: positive definite as Q^T A Q is; its eigenvalues are kept above round-off's
  // reach (the factor's K and the B, C given agree to round-off, not exactly).
  Eigen::MatrixXd S = C - H.transpose() * H;
  S = 0.5 * (S + S.transpose()).eval();
  const double floor = 1e-12 * (m > 0 ? std::max(C.diagonal().maxCoeff(), 0.0) : 0.0) + 1e-300;  // m = 0: a resection
  Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success || !llt.matrixLLT().allFinite() ||
      (m > 0 && llt.matrixLLT().diagonal().array().square().minCoeff() < floor)) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
    S = eig.eigenvectors() * eig.eigenvalues().cwiseMax(floor).asDiagonal() * eig.eigenvectors().transpose();
    llt.compute(0.5 * (S + S.transpose()));
  }
  Eigen::MatrixXd LS = llt.matrixL();
  std::vector<int32_t> permuted(3 * factor_node.size());
  for (size_t i = 0; i < factor_node.size(); ++i) {
    const int32_t f = factor_node[i];
    MICA_ASSERT(f >= 0 && f < n / 3, "a bridged node maps past the factor");
    for (int c = 0; c < 3; ++c) permuted[3 * i + size_t(c)] = base[size_t(3 * f + c)];
  }
  std::vector<int32_t> start(factor_node.size() + 1, 0);
  for (const auto& [c, p] : copy) ++start[size_t(c) + 1], ++start[size_t(p) + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<std::pair<int32_t, double>> mode(size_t(start.back()));
  {
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (size_t k = 0; k < copy.size(); ++k) {
      mode[size_t(fill[size_t(copy[k].second)]++)] = {int32_t(k), M_SQRT1_2};
      mode[size_t(fill[size_t(copy[k].first)]++)] = {int32_t(k), -M_SQRT1_2};
    }
  }
  std::vector<std::pair<int32_t, int32_t>> copies(copy);
  Eigen::VectorXd t(m);
  // Nothing below throws.
  factor_inverse_perm_.swap(base);
  inverse_perm_.swap(permuted);
  bridge_copy_.swap(copies);
  bridge_H_.swap(H);
  bridge_LS_.swap(LS);
  bridge_t_.swap(t);
  mode_start_.swap(start);
  mode_.swap(mode);
  return true;
}

template <class T>
void SupernodalSolve::bridge_gather(const double* b, const Mat3* turn, T* w) const {
  std::fill(w, w + factor_rows(), T(0));
  for (size_t i = 0; i < inverse_perm_.size() / 3; ++i) {
    const Eigen::Map<const Vec3> bi(b + 3 * i);
    const Vec3 v = turn ? Vec3(turn[i].transpose() * bi) : Vec3(bi);
    for (int c = 0; c < 3; ++c) w[inverse_perm_[3 * i + size_t(c)]] += T(v[c]);
  }
}

template <class T>
void SupernodalSolve::bridge_modes_forward(const double* b, const Mat3* turn, T* w) const {
  const auto turned = [&](int32_t i) {
    const Eigen::Map<const Vec3> bi(b + 3 * i);
    return turn ? Vec3(turn[i].transpose() * bi) : Vec3(bi);
  };
  const Eigen::Index n = factor_rows();
  Eigen::VectorXd& t = bridge_t_;
  for (size_t k = 0; k < bridge_copy_.size(); ++k) {
    const auto [c, p] = bridge_copy_[k];
    t.segment<3>(3 * Eigen::Index(k)) = M_SQRT1_2 * (turned(p) - turned(c));
  }
  for (Eigen::Index k = 0; k < t.size(); ++k) {  // t -= H^T w
    double d = 0;
    const double* h = bridge_H_.col(k).data();
    for (Eigen::Index r = 0; r < n; ++r) d += h[r] * double(w[r]);
    t[k] -= d;
  }
  bridge_LS_.triangularView<Eigen::Lower>().solveInPlace(t);
  for (Eigen::Index k = 0; k < t.size(); ++k) w[n + k] = T(t[k]);
}

template <class T>
void SupernodalSolve::bridge_modes_backward(T* w) const {
  const Eigen::Index n = factor_rows();
  Eigen::VectorXd& z = bridge_t_;
  for (Eigen::Index k = 0; k < z.size(); ++k) z[k] = double(w[n + k]);
  bridge_LS_.triangularView<Eigen::Lower>().transpose().solveInPlace(z);
  for (Eigen::Index k = 0; k < z.size(); ++k) w[n + k] = T(z[k]);
  for (Eigen::Index k = 0; k < z.size(); ++k) {  // w -= H z
    const double* h = bridge_H_.col(k).data();
    const double zk = z[k];
    for (Eigen::Index r = 0; r < n; ++r) w[r] -= T(h[r] * zk);
  }
}

template <class T>
void SupernodalSolve::bridge_scatter(const T* w, const Mat3* turn, double* x) const {
  const T* z = w + factor_rows();
  for (size_t i = 0; i < inverse_perm_.size() / 3; ++i) {
    const int32_t* at = &inverse_perm_[3 * i];
    Vec3 v(static_cast<double>(w[at[0]]), static_cast<double>(w[at[1]]), static_cast<double>(w[at[2]]));
    for (int32_t m = mode_start_[i]; m < mode_start_[i + 1]; ++m) {
      const auto [k, sign] = mode_[size_t(m)];
      const T* zk = z + 3 * k;
      v += sign * Vec3(double(zk[0]), double(zk[1]), double(zk[2]));
    }
    Eigen::Map<Vec3>(x + 3 * i) = turn ? Vec3(turn[i] * v) : v;
  }
}

void SupernodalSolve::half_columns(int32_t first, HalfColumns& out) const {
  if (single()) half_columns_copy(first, out);
  else half_columns_double(first, out);
  if (!bridged()) return;
  // A bridged node's column of [L 0; H^T L_S]^-1 Q^T: the factor's, then in the modes' rows
  // L_S^-1 (V^T e - H^T h), h the factor's part.
  const size_t node = size_t(first / 3);
  const Eigen::Index m = bridge_LS_.rows(), n = factor_rows();
  Eigen::MatrixXd t = Eigen::MatrixXd::Zero(m, 3);
  for (int32_t q = mode_start_[node]; q < mode_start_[node + 1]; ++q) {
    const auto [k, sign] = mode_[size_t(q)];
    t.middleRows(3 * Eigen::Index(k), 3) += sign * Mat3::Identity();
  }
  Eigen::Index at = 0;
  for (size_t q = 0; q < out.start.size(); ++q) {
    t.noalias() -= bridge_H_.middleRows(out.start[q], out.length[q]).transpose() * out.values.middleRows(at, out.length[q]);
    at += out.length[q];
  }
  bridge_LS_.triangularView<Eigen::Lower>().solveInPlace(t);
  out.values.conservativeResize(at + m, 3);
  out.values.bottomRows(m) = t;
  out.start.push_back(int32_t(n));
  out.length.push_back(int32_t(m));
}

void SupernodalSolve::half_columns_copy(int32_t first, HalfColumns& out) const {
  // The copy's forward half of the three unit columns, panel by panel, skipping the panels they
  // have not reached; those they reach are the segments.
  out.start.clear();
  out.length.clear();
  const CopyView c = copy_view();
  float* w[3] = {w3_single_.col(0).data(), w3_single_.col(1).data(), w3_single_.col(2).data()};
  for (int k = 0; k < 3; ++k) w[k][inverse_perm_[size_t(first + k)]] = 1;
  Eigen::Index total = 0;
  for (size_t q = 0; q < panels_.size(); ++q) {
    const SupernodePanel& p = panels_[q];
    bool reached = false;
    for (int k = 0; k < 3 && !reached; ++k)
      for (int j = 0; j < p.width && !reached; ++j) reached = w[k][p.column + j] != 0;
    if (!reached) continue;
    for (int k = 0; k < 3; ++k) forward_panel(c, q, w[k], y_single_.data());
    out.start.push_back(p.column);
    out.length.push_back(p.width);
    total += p.width;
  }
  out.values.resize(total, 3);
  Eigen::Index at = 0;
  for (size_t q = 0; q < out.start.size(); ++q) {
    auto segment = w3_single_.middleRows(out.start[q], out.length[q]);
    out.values.middleRows(at, out.length[q]) = segment.cast<double>();
    segment.setZero();  // every row it touched lies in a segment
    at += out.length[q];
  }
}

void SupernodalSolve::half_columns_double(int32_t first, HalfColumns& out) const {
  out.start.clear();
  out.length.clear();
  double* w[3] = {w3_.col(0).data(), w3_.col(1).data(), w3_.col(2).data()};
  double* t[3] = {t3_.col(0).data(), t3_.col(1).data(), t3_.col(2).data()};
  for (int c = 0; c < 3; ++c) w[c][inverse_perm_[size_t(first + c)]] = 1;
  // The forward solve of the unit columns, in double, skipping the supernodes they have not
  // reached (zero there: nothing to pass on); those they reach are the segments. Written out for
  // three columns: Eigen's general products cost more in packing than in arithmetic at these sizes.
  Eigen::Index total = 0;
  for (int k = 0; k < int(L_->nsuper); ++k) {
    const int c0 = super_[k], nc = super_[k + 1] - c0, nr = pi_[k + 1] - pi_[k];
    bool reached = false;
    for (int c = 0; c < 3 && !reached; ++c)
      for (int j = 0; j < nc && !reached; ++j) reached = w[c][c0 + j] != 0;
    if (!reached) continue;
    const double* X = values_ + px_[k];  // [D; E], column-major, leading dimension nr
    const int* rows = s_ + pi_[k];
    for (int c = 0; c < 3; ++c) {  // D x = x
      double* x = w[c] + c0;
      for (int j = 0; j < nc; ++j) {
        const double* col = X + size_t(j) * size_t(nr);
        x[j] /= col[j];
        for (int i = j + 1; i < nc; ++i) x[i] -= col[i] * x[j];
      }
    }
    out.start.push_back(c0);
    out.length.push_back(nc);
    total += nc;
    const int below = nr - nc;
    if (below == 0) continue;
    for (int c = 0; c < 3; ++c) std::fill(t[c], t[c] + below, 0.0);
    for (int j = 0; j < nc; ++j) {  // t = E x, E read once for the three columns
      const double* e = X + size_t(j) * size_t(nr) + nc;
      const double a0 = w[0][c0 + j], a1 = w[1][c0 + j], a2 = w[2][c0 + j];
      for (int i = 0; i < below; ++i) {
        t[0][i] += e[i] * a0;
        t[1][i] += e[i] * a1;
        t[2][i] += e[i] * a2;
      }
    }
    for (int c = 0; c < 3; ++c)
      for (int i = 0; i < below; ++i) w[c][rows[nc + i]] -= t[c][i];
  }
  out.values.resize(total, 3);
  Eigen::Index at = 0;
  for (size_t q = 0; q < out.start.size(); ++q) {
    out.values.middleRows(at, out.length[q]) = w3_.middleRows(out.start[q], out.length[q]);
    w3_.middleRows(out.start[q], out.length[q]).setZero();  // every row it touched lies in a segment
    at += out.length[q];
  }
}

Mat3 SupernodalSolve::product(const HalfColumns& a, const HalfColumns& b) {
  // Both paths run up the same tree: their common supernodes are the same segments, in order.
  Mat3 p = Mat3::Zero();
  Eigen::Index ia = 0, ib = 0;
  for (size_t qa = 0, qb = 0; qa < a.start.size() && qb < b.start.size();) {
    if (a.start[qa] < b.start[qb]) {
      ia += a.length[qa++];
    } else if (b.start[qb] < a.start[qa]) {
      ib += b.length[qb++];
    } else {
      // Nine dot products down the segment's columns, summed side by side row by row: nine
      // independent sums keep the adder busy where one sum at a time waits on each addition
      // (Eigen's general product packs more than it computes at these sizes).
      const Eigen::Index rows = a.length[qa], lda = a.values.rows(), ldb = b.values.rows();
      const double *a0 = a.values.data() + ia, *a1 = a0 + lda, *a2 = a1 + lda;
      const double *b0 = b.values.data() + ib, *b1 = b0 + ldb, *b2 = b1 + ldb;
      double s00 = 0, s01 = 0, s02 = 0, s10 = 0, s11 = 0, s12 = 0, s20 = 0, s21 = 0, s22 = 0;
      for (Eigen::Index r = 0; r < rows; ++r) {
        const double x0 = a0[r], x1 = a1[r], x2 = a2[r], y0 = b0[r], y1 = b1[r], y2 = b2[r];
        s00 += x0 * y0;
        s01 += x0 * y1;
        s02 += x0 * y2;
        s10 += x1 * y0;
        s11 += x1 * y1;
        s12 += x1 * y2;
        s20 += x2 * y0;
        s21 += x2 * y1;
        s22 += x2 * y2;
      }
      p(0, 0) += s00;
      p(0, 1) += s01;
      p(0, 2) += s02;
      p(1, 0) += s10;
      p(1, 1) += s11;
      p(1, 2) += s12;
      p(2, 0) += s20;
      p(2, 1) += s21;
      p(2, 2) += s22;
      ia += a.length[qa++];
      ib += b.length[qb++];
    }
  }
  return p;
}

namespace {

// b's node i turned by turn_i^T (none: as it is), into the permuted w.
template <class T>
void gather(const double* b, const Mat3* turn, const std::vector<int32_t>& permuted, T* w) {
  for (size_t i = 0; i < permuted.size() / 3; ++i) {
    const Eigen::Map<const Vec3> bi(b + 3 * i);
    const Vec3 v = turn ? Vec3(turn[i].transpose() * bi) : Vec3(bi);
    for (int c = 0; c < 3; ++c) w[permuted[3 * i + size_t(c)]] = T(v[c]);
  }
}

// The permuted w back into x, node i turned by turn_i.
template <class T>
void scatter(const T* w, const Mat3* turn, const std::vector<int32_t>& permuted, double* x) {
  for (size_t i = 0; i < permuted.size() / 3; ++i) {
    const Vec3 v(static_cast<double>(w[permuted[3 * i]]), static_cast<double>(w[permuted[3 * i + 1]]),
                 static_cast<double>(w[permuted[3 * i + 2]]));
    Eigen::Map<Vec3>(x + 3 * i) = turn ? Vec3(turn[i] * v) : v;
  }
}

}  // namespace

void SupernodalSolve::forward(const double* b, bool single, const Mat3* turn) const {
  halves_single_ = (single || !values_) && this->single();
  if (!halves_single_) {
    if (!bridged()) {
      gather(b, turn, inverse_perm_, w_.data());
      return forward_double();
    }
    bridge_gather(b, turn, w_.data());
    forward_double();
    return bridge_modes_forward(b, turn, w_.data());
  }
  if (!bridged()) {
    gather(b, turn, inverse_perm_, w_single_.data());
    return forward_single();
  }
  bridge_gather(b, turn, w_single_.data());
  forward_single();
  bridge_modes_forward(b, turn, w_single_.data());
}

Vec3 SupernodalSolve::dot(const HalfColumns& h) const {
  Vec3 d = Vec3::Zero();
  Eigen::Index at = 0;
  for (size_t q = 0; q < h.start.size(); ++q) {
    const auto H = h.values.middleRows(at, h.length[q]);
    if (halves_single_) {  // by hand: a product with a cast would make a temporary
      const float* w = w_single_.data() + h.start[q];
      const double *h0 = H.col(0).data(), *h1 = H.col(1).data(), *h2 = H.col(2).data();
      // Two rows at a time into six sums: one sum per column would wait on each addition.
      double d0 = 0, d1 = 0, d2 = 0, e0 = 0, e1 = 0, e2 = 0;
      const Eigen::Index n = h.length[q];
      Eigen::Index r = 0;
      for (; r + 1 < n; r += 2) {
        const double u = w[r], v = w[r + 1];
        d0 += h0[r] * u;
        d1 += h1[r] * u;
        d2 += h2[r] * u;
        e0 += h0[r + 1] * v;
        e1 += h1[r + 1] * v;
        e2 += h2[r + 1] * v;
      }
      if (r < n) {
        d0 += h0[r] * double(w[r]);
        d1 += h1[r] * double(w[r]);
        d2 += h2[r] * double(w[r]);
      }
      d += Vec3(d0 + e0, d1 + e1, d2 + e2);
    } else {
      d.noalias() += H.transpose() * w_.segment(h.start[q], h.length[q]);
    }
    at += h.length[q];
  }
  return d;
}

void SupernodalSolve::add(const HalfColumns& h, const Vec3& f) const {
  Eigen::Index at = 0;
  for (size_t q = 0; q < h.start.size(); ++q) {
    const auto H = h.values.middleRows(at, h.length[q]);
    if (halves_single_) {
      float* w = w_single_.data() + h.start[q];
      const double *h0 = H.col(0).data(), *h1 = H.col(1).data(), *h2 = H.col(2).data();
      for (Eigen::Index r = 0; r < h.length[q]; ++r) w[r] += float(h0[r] * f[0] + h1[r] * f[1] + h2[r] * f[2]);
    } else {
      w_.segment(h.start[q], h.length[q]).noalias() += H * f;
    }
    at += h.length[q];
  }
}

void SupernodalSolve::backward(double* x, const Mat3* turn) const {
  if (halves_single_) {
    if (!bridged()) {
      backward_single();
      return scatter(w_single_.data(), turn, inverse_perm_, x);
    }
    bridge_modes_backward(w_single_.data());
    backward_single();
    return bridge_scatter(w_single_.data(), turn, x);
  }
  if (!bridged()) {
    backward_double();
    return scatter(w_.data(), turn, inverse_perm_, x);
  }
  bridge_modes_backward(w_.data());
  backward_double();
  bridge_scatter(w_.data(), turn, x);
}

}  // namespace mica
