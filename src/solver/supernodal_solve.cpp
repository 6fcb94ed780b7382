// SPDX-License-Identifier: Apache-2.0
#include "solver/supernodal_solve.hpp"

#include <cmath>

namespace mica {

bool SupernodalSolve::bind(const cholmod_factor* L, bool single) {
  L_ = nullptr;
  values_single_.clear();
  if (!L || !L->is_super || !L->is_ll || L->xtype != CHOLMOD_REAL || L->dtype != CHOLMOD_DOUBLE ||
      L->itype != CHOLMOD_INT || !L->x)
    return false;
  super_ = static_cast<const int*>(L->super);
  pi_ = static_cast<const int*>(L->pi);
  px_ = static_cast<const int*>(L->px);
  s_ = static_cast<const int*>(L->s);
  perm_ = static_cast<const int*>(L->Perm);
  values_ = static_cast<const double*>(L->x);
  const Eigen::Index n = Eigen::Index(L->n), below = Eigen::Index(L->maxesize > 0 ? L->maxesize : 1);
  w_.resize(n);
  t_.resize(below);
  L_ = L;
  if (single) {
    values_single_.assign(values_, values_ + L->xsize);
    w_single_.resize(n);
    t_single_.resize(below);
    // Kept only where single precision holds: float's 6e-8 grows with the condition of the
    // system (a nearly incompressible, very stiff body's is far too large), and a preconditioner
    // that far off misleads the solves. Probed on one fixed vector, in double and in single.
    Eigen::VectorXd probe(n), in_double(n), in_single(n);
    for (Eigen::Index i = 0; i < n; ++i) probe[i] = std::sin(0.7 * double(i)) + 0.5;
    solve(probe.data(), in_double.data());
    solve_single(probe.data(), in_single.data());
    const double error = (in_single - in_double).norm(), size = in_double.norm();
    if (!(error <= kSingleAgreement * size)) values_single_.clear();
  }
  return true;
}

void SupernodalSolve::solve(const double* b, double* x) const { run(values_, w_, t_, b, x); }

void SupernodalSolve::solve_single(const double* b, double* x) const {
  run(values_single_.data(), w_single_, t_single_, b, x);
}

template <class T>
void SupernodalSolve::run(const T* values, Eigen::Matrix<T, Eigen::Dynamic, 1>& w,
                          Eigen::Matrix<T, Eigen::Dynamic, 1>& t_all, const double* b, double* x) const {
  using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
  using Block = Eigen::Map<const Matrix, 0, Eigen::OuterStride<>>;
  const Eigen::Index n = w.size(), nsuper = Eigen::Index(L_->nsuper);
  for (Eigen::Index i = 0; i < n; ++i) w[i] = T(b[perm_[i]]);
  // A supernode k holds columns super[k] .. super[k+1) of L as a dense block (column-major,
  // nr rows, leading dimension nr): its diagonal block on top, then the rows s[pi[k] + nc ..].
  auto block = [&](Eigen::Index k, Eigen::Index& c0, Eigen::Index& nc, Eigen::Index& nr) {
    c0 = super_[k];
    nc = super_[k + 1] - c0;
    nr = pi_[k + 1] - pi_[k];
    return Block(values + px_[k], nr, nc, Eigen::OuterStride<>(nr));
  };
  Eigen::Index c0, nc, nr;
  for (Eigen::Index k = 0; k < nsuper; ++k) {  // L w' = w
    const Block X = block(k, c0, nc, nr);
    auto xk = w.segment(c0, nc);
    X.topRows(nc).template triangularView<Eigen::Lower>().solveInPlace(xk);
    const Eigen::Index below = nr - nc;
    if (below == 0) continue;
    auto t = t_all.head(below);
    t.noalias() = X.bottomRows(below) * xk;
    const int* rows = s_ + pi_[k] + nc;
    for (Eigen::Index i = 0; i < below; ++i) w[rows[i]] -= t[i];
  }
  for (Eigen::Index k = nsuper - 1; k >= 0; --k) {  // L^T w' = w
    const Block X = block(k, c0, nc, nr);
    auto xk = w.segment(c0, nc);
    const Eigen::Index below = nr - nc;
    if (below > 0) {
      auto t = t_all.head(below);
      const int* rows = s_ + pi_[k] + nc;
      for (Eigen::Index i = 0; i < below; ++i) t[i] = w[rows[i]];
      xk.noalias() -= X.bottomRows(below).transpose() * t;
    }
    X.topRows(nc).template triangularView<Eigen::Lower>().transpose().solveInPlace(xk);
  }
  for (Eigen::Index i = 0; i < n; ++i) x[perm_[i]] = double(w[i]);
}

}  // namespace mica
