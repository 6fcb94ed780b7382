// SPDX-License-Identifier: Apache-2.0
// MICA with a factored anticipation: the same problem and outer loop as MicaSolver (anticipate
// the contact velocities, update the impulses by projected Gauss-Seidel, update the velocities,
// stop on the change of the solution and a balanced momentum), with the block-diagonal
// anticipation Dt^-1 replaced by the warped factor of a recent system, P^-1 = S Q K_f^-1 Q^T S
// (lagged_factor.hpp):
//  - velocities: projected conjugate gradients preconditioned by P^-1 (a few iterations where
//    block Gauss-Seidel needs thousands on stiff or fine meshes);
//  - contact: the impulses see the compliance W = G P^-1 G^T, a small dense matrix built from the
//    cached columns of K_f^-1 at the contact nodes, solved by projected Gauss-Seidel; the
//    velocities then follow the impulse change through the same columns.
// With P = A the loop would end after one correction; the rotations' mismatch costs a few more.
#pragma once
#include <Eigen/QR>
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "solver/frictional_contact.hpp"
#include "solver/lagged_factor.hpp"
#include "solver/pcg.hpp"
#include "solver/velocity_solver.hpp"

namespace mica {

// What the factored solver keeps per body.
struct FactoredBodyCache {
  LaggedFactor factor;
  std::vector<Mat3> node_rotation;  // per node, for warping the factor
  int64_t factorizations() const { return factor.factorizations(); }
};

// Each body's factor is updated once per solve for its SystemKey and constraint version
// (LaggedFactor::update); a co-rotational body's (SolverBody::rotation) is warped by its node
// rotations and refreshed every SolverSettings::refactor_interval solves in the background.
//
// Allocation: solve() allocates only while its workspaces grow: on the first solves, when the
// contact rows change in number (W, the small problem's and the active set's workspaces are
// sized by them; the active set's decompositions, one per size, only grow with them), and when a
// factor is made or adopted (its columns afresh).
// Otherwise it makes no heap allocation (tests/solver/test_solve_allocations.cpp).
class FactoredMicaSolver : public CachingVelocitySolver<FactoredBodyCache> {
 public:
  explicit FactoredMicaSolver(const SolverSettings& settings = {}) : settings_(settings) {}
  SolveReport solve(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                    std::vector<double>& lambda) override;
  // W_rr of the last solve, per row (0 for a row nothing can move along).
  const std::vector<double>& row_diagonal() const override { return diag_; }
  // The factors' refresh schedules and caches (LaggedFactor::begin, commit, rollback).
  void begin_step() override {
    for_each_cache([](FactoredBodyCache& c) { c.factor.begin(); });
  }
  void commit_step() override {
    for_each_cache([](FactoredBodyCache& c) { c.factor.commit(); });
  }
  void rollback_step() override {
    for_each_cache([](FactoredBodyCache& c) { c.factor.rollback(); });
  }
  // Each body's lagged factor (LaggedFactor::save, load).
  void save_body(uint64_t key, ByteWriter& out) const override;
  void restore_bodies(const std::vector<SavedBody>& bodies) override;

 private:
  // What the loop needs beyond SolverBody, per body of a solve.
  struct FactoredBody {
    LaggedFactor* factor;                     // updated for this solve's system and constraints
    const std::vector<Mat3>* node_rotation;   // null: the linear model (no warping)
  };
  // Each body's factor brought up to its system (factored_ in the bodies' order).
  void update_factors(const std::vector<SolverBody>& bodies);
  // W, its diagonal and the rows nothing can move along, from the factor in use.
  void start_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda);
  void build_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows);
  // v += S Q K_f^-1 Q^T S G^T dlambda, through the cached columns.
  void apply_impulse_change(std::vector<SolverBody>& bodies, const ContactRows& rows,
                            const std::vector<double>& dlambda);
  // lambda_next_ solves the contact problem on W around lambda: 0 <= lambda_next _|_ w + W (lambda_next - lambda) >= 0
  // on normal rows, Coulomb's cone on tangent pairs (frictional_contact.hpp).
  void solve_small_lcp(const ContactRows& rows, double tolerance, const std::vector<double>& lambda,
                       const std::optional<std::chrono::steady_clock::time_point>& deadline);
  // Of the current lambda against the current row velocities w_ (N s).
  double complementarity_error(const ContactRows& rows, const std::vector<double>& lambda);
  // The current systems factored now (co-rotational bodies), W and its diagonal from the new factor.
  void refactor_now(const std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda);
  // Two solved velocity fields secant_s_ apart in the impulses measure the true compliance along
  // it, y = w_ - w_prev_: a BFGS update takes that into W_ (kept symmetric positive definite).
  void secant_update();
  // w_ = G v + bias of the bodies' current velocities.
  void row_velocities(const std::vector<SolverBody>& bodies, const ContactRows& rows);

  // The active-set loop (factored_mica_active_set.cpp, SolverSettings::active_set).
  SolveReport solve_active_set(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                               std::vector<double>& lambda);
  // eq_: the rows held as equalities for these impulses (pressing normal rows, sticking tangent
  // pairs), and W_E = G_E P^-1 G_E^T factored; impulses at round-off level set to 0.
  void choose_equalities(const ContactRows& rows, std::vector<double>& lambda);
  // A v = b + G^T lambda with G_E v + bias_E = 0, by projected PCG; lambda_E out, the rest fixed.
  SolveReport constrained_solve(std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda,
                                double tolerance, int32_t cap,
                                const std::optional<SolveContext::Clock::time_point>& deadline);
  // x = W_E^-1 rhs (the least-squares solution where rows are redundant).
  void solve_equalities(const Eigen::Ref<const Eigen::VectorXd>& rhs, Eigen::Ref<Eigen::VectorXd> x);
  // y_ = K_f^-1 G^T w on body bi for row weights w (the factor's frame, through the cached
  // columns); false when no row with a weight has a term on the body.
  bool body_response(size_t bi, const ContactRows& rows, const std::vector<double>& w);
  // out += P^-1 G_which^T x (through the cached columns).
  void add_response(const std::vector<SolverBody>& bodies, const ContactRows& rows, const std::vector<int32_t>& which,
                    const Eigen::Ref<const Eigen::VectorXd>& x, std::vector<Vec3List>& out);
  // out -= S G_E^T x.
  void subtract_row_forces(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                           const Eigen::Ref<const Eigen::VectorXd>& x, std::vector<Vec3List>& out) const;
  // out = G_E y (no bias).
  void rows_times(const ContactRows& rows, const std::vector<Vec3List>& y, Eigen::Ref<Eigen::VectorXd> out) const;
  // The decomposition kept for active sets of ne rows, and those of every size up to nr made at once.
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>& equality_solver(Eigen::Index ne);
  void prepare_equality_solvers(Eigen::Index nr);

  SolverSettings settings_;
  std::vector<FactoredBody> factored_;
  std::vector<PcgSolver> pcg_;
  std::vector<WarpedFactorPreconditioner> warp_;
  std::vector<const Eigen::MatrixXd*> term_columns_;  // per row term: K_f^-1 columns of its node
  std::vector<int32_t> term_row_;                     // per row term: its row
  std::vector<Vec3> term_force_;                      // per row term: coef Q_i^T S_i d (the factor's frame)
  Eigen::MatrixXd W_;                                 // G P^-1 G^T
  std::vector<double> w_, w_prev_, lambda_next_, dlambda_, diag_;
  std::vector<int32_t> live_, live_at_, contact_nodes_;
  Eigen::MatrixXd small_M_;                           // W on the live rows
  Eigen::VectorXd small_q_, small_mu_, small_start_;
  std::vector<int32_t> small_normal_;
  FrictionalSolution small_solution_;
  FrictionalWorkspace small_workspace_;
  std::vector<double> warped_diag_;  // W_rr before the secant updates
  std::vector<Vec3List> rhs_;
  Eigen::VectorXd y_;
  // body_response's: the row weights, and the rows' forces summed per node (node_term_: the node's
  // first term, -1 untouched); grown, never shrunk.
  std::vector<double> row_weight_;
  Vec3List node_force_;
  std::vector<int32_t> node_term_, touched_;
  Eigen::VectorXd secant_s_, secant_y_, secant_Ws_;  // secant_update's (no allocation once sized)
  // The active-set loop's.
  Eigen::MatrixXd W0_;  // G P^-1 G^T of the factor, without the secant updates (the projections need it exact)
  // Sized to the largest active set seen (only ever grown); a set of ne rows uses the first ne
  // entries (ne^2 of W_eq_, column-major).
  Eigen::VectorXd W_eq_;
  std::vector<std::unique_ptr<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>> W_eq_solvers_;  // by size
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>* W_eq_solver_ = nullptr;  // this set's
  std::vector<int32_t> eq_;
  Eigen::VectorXd mu_, mu_neg_, mu_total_, row_scratch_, eq_work_, eq_y_;
  std::vector<double> fixed_, lambda_prev_;
  std::vector<Vec3List> cy_, cr_, cz_, cp_, cq_, ct_, cf_;  // per body: y, r, z, p, A p, scratch, rhs
  std::vector<Vec3List> cz_last_;                           // per body: the last z (the flexible beta)
};

}  // namespace mica
