// SPDX-License-Identifier: Apache-2.0
#include "solver/direct_solver.hpp"

#include <algorithm>
#include <cmath>

#include "core/assert.hpp"
#include "core/error.hpp"
#include "fem/block_matrix.hpp"

namespace mica {

namespace {
// CHOLMOD's last message on this thread: CHOLMOD prints nothing (a library writes nothing to the
// host's stdout), and a failed factorization's error carries the message instead.
thread_local std::string cholmod_message;

void keep_cholmod_message(int status, const char* file, int line, const char* message) {
  cholmod_message = std::string(status > 0 ? "CHOLMOD warning " : "CHOLMOD error ") + std::to_string(status) + ": " +
                    (message ? message : "") + " (" + (file ? file : "") + ":" + std::to_string(line) + ")";
}
}  // namespace

DirectSolver::DirectSolver() {
  cholmod_common& common = llt_.cholmod();
  common.print = 0;
  common.error_handler = keep_cholmod_message;
}

DirectSolver::~DirectSolver() {
  for (cholmod_dense** d : {&x_, &y_, &e_})
    if (*d) cholmod_free_dense(d, &llt_.cholmod());
}

void DirectSolver::solve_raw(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::MatrixXd& X) {
  if (B.cols() != 1 || !by_hand_.bound()) return solve_raw_cholmod(B, X);
  X.resize(B.rows(), 1);
  by_hand_.solve(B.data(), X.data());
}

void DirectSolver::solve_one(const Eigen::Ref<const Eigen::VectorXd>& b, Eigen::VectorXd& x, bool single) {
  x.resize(b.size());
  if (single && by_hand_.single()) {
    by_hand_.solve_single(b.data(), x.data());
  } else if (by_hand_.bound()) {
    by_hand_.solve(b.data(), x.data());
  } else {
    solve_raw_cholmod(b, y_flat_);
    x = y_flat_.col(0);
  }
}

void DirectSolver::solve_raw_cholmod(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::MatrixXd& X) {
  MICA_ASSERT(!by_hand_.bound() || by_hand_.double_kept(), "cholmod_solve2 needs the double factor");
  cholmod_dense b{};  // a view of B (CHOLMOD reads it only)
  b.nrow = size_t(B.rows());
  b.ncol = size_t(B.cols());
  b.nzmax = b.nrow * b.ncol;
  b.d = size_t(B.outerStride());
  b.x = const_cast<double*>(B.data());
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, llt_.factor(), &b, nullptr, &x_, nullptr, &y_, &e_, &llt_.cholmod()))
    fail(Errc::Numerical, "CHOLMOD could not solve with the factorization");
  X.resize(B.rows(), B.cols());
  X = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x_->x), B.rows(), B.cols());
}

namespace {
// Node i is held still: no velocity component of it is free.
bool held_still(const Projection& p, size_t i) { return p.is_constrained[i] && p.S[i].isZero(0); }
}  // namespace

void DirectSolver::build_lower(const BlockPattern& pattern, bool leave_out_held) {
  const int32_t n = 3 * pattern.rows;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(9 * pattern.block_count() / 2 + 3 * size_t(pattern.rows));
  for (int32_t i = 0; i < pattern.rows; ++i)
    for (int32_t k = pattern.row_start[i]; k < pattern.row_start[i + 1]; ++k) {
      const int32_t j = pattern.col[k];
      if (leave_out_held && j != i && (held_[size_t(i)] || held_[size_t(j)])) continue;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          if (3 * i + r >= 3 * j + c) entries.emplace_back(3 * i + r, 3 * j + c, 1.0);
    }
  lower_.resize(n, n);
  lower_.setFromTriplets(entries.begin(), entries.end());
  lower_.makeCompressed();
  // Where each stored scalar comes from: entry (3i + r, 3j + c) is element (r, c) of block (i, j).
  value_source_.resize(size_t(lower_.nonZeros()));
  for (int32_t col = 0; col < n; ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(lower_, col); it; ++it) {
      const int32_t row = int32_t(it.row());
      const int32_t k = pattern.find(row / 3, col / 3);
      value_source_[size_t(&it.valueRef() - lower_.valuePtr())] = 9 * k + 3 * (col % 3) + row % 3;
    }
}

void DirectSolver::Factor::analyze_given(const Eigen::SparseMatrix<double>& lower, std::vector<int>& perm) {
  cholmod_common& common = cholmod();
  if (m_cholmodFactor) cholmod_free_factor(&m_cholmodFactor, &common);
  cholmod_sparse A = Eigen::viewAsCholmod(lower.selfadjointView<Eigen::Lower>());
  const int nmethods = common.nmethods, ordering = common.method[0].ordering;
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_GIVEN;
  m_cholmodFactor = cholmod_analyze_p(&A, perm.data(), nullptr, 0, &common);
  common.nmethods = nmethods;
  common.method[0].ordering = ordering;
  if (!m_cholmodFactor) fail(Errc::Internal, "CHOLMOD could not analyse the system with its own ordering");
  this->m_isInitialized = true;
  this->m_info = Eigen::Success;
  m_analysisIsOk = true;
  m_factorizationIsOk = false;
}

void DirectSolver::analyze(const BlockPattern& pattern, const Projection* projection) {
  by_hand_.unbind();  // it points into the factor a new analysis replaces
  held_.assign(size_t(pattern.rows), 0);
  if (projection && projection->active())
    for (int32_t i : projection->nodes) held_[size_t(i)] = held_still(*projection, size_t(i));
  projected_.resize(pattern.block_count());
  cholmod_common& common = llt_.cholmod();
  common.postorder = 1;
  // The fill-reducing ordering, once (a solver serves one body's pattern), of the whole pattern
  // with no node held: AMD or nested dissection (CHOLMOD's NESDIS over METIS), whichever fills
  // less. CHOLMOD's default tries METIS only after AMD filled a lot, and kept AMD on the nidus,
  // where NESDIS has 10.5 % fewer nonzeros in L and 27 % fewer flops (bench_factor); on a
  // 35k-tet cube the memory after the first step fell 5073 -> 4775 B per tet (bench_nidus
  // --scaling). NESDIS takes ~20 ms on the nidus, so a new held set (a grasp) is analysed with
  // this ordering given (~5 ms), and a pattern marked FillOrdering::Amd (a body just cut, whose
  // next step must factor) skips it and is ordered as held, in one analysis (~6 ms, from ~26):
  // with the cut's other savings, bench_incision's cut p99 fell from 45-49 to 31-33 ms. All of
  // it is deterministic: a restored state factors the same bits.
  const bool any_held = std::find(held_.begin(), held_.end(), 1) != held_.end();
  const bool amd_alone = pattern.fill_ordering == FillOrdering::Amd;
  bool analysed_as_held = false;
  if (ordering_.size() != size_t(3 * pattern.rows)) {
    // AMD alone orders the pattern as it is held now: one analysis, not two.
    const bool held_now = amd_alone && any_held;
    build_lower(pattern, held_now);
    common.nmethods = amd_alone ? 1 : 2;
    common.method[0].ordering = CHOLMOD_AMD;
    common.method[1].ordering = CHOLMOD_NESDIS;
    llt_.analyzePattern(lower_);
    const cholmod_factor* L = llt_.factor();
    if (!L) fail(Errc::Internal, "CHOLMOD could not analyse the system");
    ordering_.assign(static_cast<const int*>(L->Perm), static_cast<const int*>(L->Perm) + L->n);
    ordering_method_ = L->ordering;
    analysed_as_held = held_now || !any_held;
  }
  if (!analysed_as_held) {
    build_lower(pattern, true);
    llt_.analyze_given(lower_, ordering_);
  }
  nonzeros_ = common.lnz;
  flops_ = common.fl;
  analyzed_ = true;
}

int64_t DirectSolver::factor_entries() const {
  const cholmod_factor* L = analyzed_ ? llt_.factor() : nullptr;
  return L ? int64_t(L->is_super ? L->xsize : L->nzmax) : 0;
}

int DirectSolver::ordering() const { return analyzed_ ? ordering_method_ : 0; }

void DirectSolver::factorize(const ProjectedSystem& sys) {
  const BlockPattern& p = sys.pattern;
  bool same_held = analyzed_ && held_.size() == size_t(p.rows);
  for (size_t i = 0; same_held && i < held_.size(); ++i)
    same_held = held_[i] == (sys.projection.active() && held_still(sys.projection, i));
  if (!same_held) analyze(p, &sys.projection);
  for (int32_t i = 0; i < p.rows; ++i)
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) projected_[k] = sys.block(i, k);
  const double* source = projected_[0].data();
  double* values = lower_.valuePtr();
  for (size_t q = 0; q < value_source_.size(); ++q) values[q] = source[value_source_[q]];
  by_hand_.unbind();
  cholmod_message.clear();
  llt_.factorize(lower_);
  ++factorizations_;
  if (llt_.info() != Eigen::Success)
    fail(Errc::Numerical, "the system matrix is not positive definite (" +
                              (cholmod_message.empty() ? std::string("CHOLMOD factorization failed") : cholmod_message) +
                              ")");
  // The half copy's probe multiplies by the factored system itself (the blocks just copied).
  auto multiply = [&](const double* x, double* y) {
    const size_t n = size_t(p.rows);
    Vec3List xs(n), ys(n);
    for (size_t i = 0; i < n; ++i) xs[i] = Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    block_multiply(p, projected_, xs, ys);
    for (size_t i = 0; i < n; ++i)
      for (int r = 0; r < 3; ++r) y[3 * i + size_t(r)] = ys[i][r];
  };
  by_hand_.bind(llt_.factor(), copy_, multiply);  // false (cholmod_solve2 then) for a factor of another kind
  if (keep_double_ || !by_hand_.single()) return;
  // Back to CHOLMOD's symbolic supernodal factor: the values go, the structure the copy's panels
  // point into stays.
  if (!cholmod_change_factor(CHOLMOD_PATTERN, true, true, true, true, llt_.factor(), &llt_.cholmod()))
    fail(Errc::Internal, "CHOLMOD could not free the double factor");
  by_hand_.release_double();
}

SolveReport DirectSolver::solve(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v) {
  const size_t n = b.size();
  rhs_.resize(n);
  tmp_.resize(n);
  check_.resize(n);
  sys.right_hand_side(b, rhs_, tmp_);
  solve_raw(flat(rhs_), y_flat_);
  flat(v) = y_flat_.col(0);
  // The residual of the projected system, reported like the iterative solvers'.
  sys.apply(v, check_, tmp_);
  const double rhs_norm = flat(rhs_).norm();
  SolveReport report;
  report.iterations = 1;
  report.residual = rhs_norm > 0 ? (flat(check_) - flat(rhs_)).norm() / rhs_norm : 0;
  report.converged = std::isfinite(report.residual);
  for (int32_t i : sys.projection.nodes) v[i] += sys.projection.z[i];
  return report;
}

SolveReport DirectSolver::solve_homogeneous(const ProjectedSystem& sys, const Vec3List& f, Vec3List& y) {
  rhs_ = f;
  for (int32_t i : sys.projection.nodes) rhs_[i] = sys.projection.S[i] * f[i];
  solve_raw(flat(rhs_), y_flat_);
  flat(y) = y_flat_.col(0);
  SolveReport report;
  report.iterations = 1;
  return report;
}

}  // namespace mica
