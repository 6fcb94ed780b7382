// SPDX-License-Identifier: Apache-2.0
// The exact velocity solve: sparse Cholesky (CHOLMOD, supernodal) of the projected system.
// The symbolic analysis is done once per pattern; the numeric factorization whenever the
// caller says the matrix or the constraints changed (a linear body factors once).
#pragma once
#include <Eigen/CholmodSupport>
#include <Eigen/SparseCore>
#include <memory>

#include "solver/projected_system.hpp"
#include "solver/supernodal_solve.hpp"

namespace mica {

class DirectSolver : public LinearSolver {
 public:
  DirectSolver();
  ~DirectSolver() override;
  DirectSolver(const DirectSolver&) = delete;  // owns CHOLMOD workspaces
  DirectSolver& operator=(const DirectSolver&) = delete;
  // Builds the scalar lower-triangular pattern from the block pattern and analyses it. The nodes
  // `projection` holds still (S_i = 0: their rows of S A S + I - S are the identity's) keep only
  // their diagonal blocks, so the factor neither stores nor solves through their couplings, which
  // are zero. factorize() analyses again when its system holds other nodes still.
  void analyze(const BlockPattern& pattern, const Projection* projection = nullptr);
  bool analyzed() const { return analyzed_; }
  // Numeric factorization of S A S + I - S. Throws Error(Numerical) if not positive definite.
  void factorize(const ProjectedSystem& sys);
  // Both solves use the last factorization.
  SolveReport solve(const ProjectedSystem& sys, const Vec3List& b, Vec3List& v) override;
  SolveReport solve_homogeneous(const ProjectedSystem& sys, const Vec3List& f, Vec3List& y) override;
  // X = (S A S + I - S)^-1 B for any right-hand sides (no projection applied to B): one by the
  // hand-written supernodal solve, several through cholmod_solve2 with workspaces kept between
  // calls. No allocation once X has its size and the workspaces have grown to the widest B.
  void solve_raw(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::MatrixXd& X);
  // The same through cholmod_solve2 only (the reference the hand-written solve is tested against).
  void solve_raw_cholmod(const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::MatrixXd& X);
  // Set before factorize: each factorization also keeps this copy of the factor for the
  // preconditioner's solves (supernodal_solve.hpp). Without keep_double, a factorization whose
  // copy was kept then frees the double factor's values (CHOLMOD keeps its structure, and the
  // next factorization fills it again): every solve reads the copy, in a quarter (half copy) or a
  // half (single) of the memory. Only the hand-written solves of one right-hand side are left then.
  void set_copy(SupernodalSolve::Copy copy, bool keep_double = true) {
    copy_ = copy;
    keep_double_ = keep_double;
  }
  // x = (S A S + I - S)^-1 b for one right-hand side; with `single` and a single-precision copy,
  // solved with the copy (a preconditioner's solve), else as solve_raw.
  void solve_one(const Eigen::Ref<const Eigen::VectorXd>& b, Eigen::VectorXd& x, bool single);
  int64_t factorizations() const { return factorizations_; }
  // The analysed factor's stored entries (supernodal: dense blocks, zeros included), the ordering
  // chosen (CHOLMOD_AMD, CHOLMOD_NESDIS, ...) and CHOLMOD's counts of the nonzeros in L and of the
  // flops of one factorization; 0 before analyze.
  int64_t factor_entries() const;
  int ordering() const;
  double factor_nonzeros() const { return nonzeros_; }
  double factor_flops() const { return flops_; }
  // The hand-written solve bound to the last factorization (its halves and half columns), or
  // null when CHOLMOD made a factor of another kind.
  const SupernodalSolve* by_hand() const { return by_hand_.bound() ? &by_hand_ : nullptr; }
  // The hand-written solve's bridge to a changed body's nodes (SupernodalSolve::bridge).
  bool bridge(const std::vector<int32_t>& factor_node, const std::vector<std::pair<int32_t, int32_t>>& copy,
              const Eigen::MatrixXd& B, const Eigen::MatrixXd& C) {
    return by_hand_.bridge(factor_node, copy, B, C);
  }
  // Forgets the analysed pattern and its ordering: the next analyze() is of another body's
  // pattern (a body whose topology changed), as in a new solver.
  void forget_pattern() {
    by_hand_.unbind();
    ordering_.clear();
    analyzed_ = false;
  }

 private:
  // lower_ over the block pattern, without the couplings of held_ nodes when `leave_out_held`.
  void build_lower(const BlockPattern& pattern, bool leave_out_held);
  Eigen::SparseMatrix<double> lower_;          // scalar matrix, lower triangle, fixed pattern
  std::vector<int32_t> value_source_;          // per stored value: 9 * block + position in block
  std::vector<uint8_t> held_;                  // per node: held still in the analysed pattern
  std::vector<int> ordering_;                  // the whole pattern's fill-reducing permutation
  int ordering_method_ = 0;                    // CHOLMOD_AMD or CHOLMOD_NESDIS: how it was found
  BlockValues projected_;                      // S A S + I - S per block
  // Supernodal LL^T: dense BLAS on the supernodes, about twice as fast as the simplicial LDL^T
  // with OpenBLAS on bodies of a few thousand nodes (docs/architecture.md).
  // Eigen's wrapper, opened to cholmod_solve2 (its factor is a protected member).
  struct Factor : Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
    cholmod_factor* factor() const { return m_cholmodFactor; }
    // analyzePattern with this fill-reducing permutation (CHOLMOD_GIVEN; postordered after).
    void analyze_given(const Eigen::SparseMatrix<double>& lower, std::vector<int>& perm);
  };
  Factor llt_;
  SupernodalSolve by_hand_;  // bound to llt_'s factor after each factorization
  SupernodalSolve::Copy copy_ = SupernodalSolve::Copy::None;
  bool keep_double_ = true;
  cholmod_dense *x_ = nullptr, *y_ = nullptr, *e_ = nullptr;  // cholmod_solve2's solution and workspaces
  Vec3List rhs_, tmp_, check_;
  Eigen::MatrixXd y_flat_;
  bool analyzed_ = false;
  double nonzeros_ = 0, flops_ = 0;  // CHOLMOD's counts from the analysis
  int64_t factorizations_ = 0;
};

}  // namespace mica
