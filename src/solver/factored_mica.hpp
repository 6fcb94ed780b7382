// SPDX-License-Identifier: Apache-2.0
// MICA with a factored anticipation: the same problem and outer loop as MicaSolver (anticipate
// the contact velocities, update the impulses by projected Gauss-Seidel, update the velocities,
// stop on the change of the solution and a balanced momentum), with the block-diagonal
// anticipation Dt^-1 replaced by the warped factor of a recent system, P^-1 = S Q K_f^-1 Q^T S
// (lagged_factor.hpp):
//  - velocities: projected conjugate gradients preconditioned by P^-1 (a few iterations where
//    block Gauss-Seidel needs thousands on stiff or fine meshes);
//  - contact: the impulses see the compliance W = G P^-1 G^T, a small dense matrix built from the
//    factor's half columns at the contact nodes (below), solved by a small LCP; the velocities
//    then follow the impulse change through the same half columns.
// With P = A the loop would end after one correction; the rotations' mismatch costs a few more.
//
// The contacts' own stiffness (SolverBody::extra_stiffness: a rounded tool's curvature, new every
// step) is left out of the factor and added back exactly: P_c = P + U C U^T with U the contact
// nodes and C that stiffness, P_c^-1 = P^-1 - X (I + C Y)^-1 C X^T (Woodbury), X = P^-1 U,
// Y = U^T X. Both the compliance W and the conjugate gradients use P_c; without it the gradients
// spend half their iterations rediscovering a stiffness of rank ~30 (nidus press, linear body:
// 6.5 iterations per round against 2).
//
// Everything about the contact nodes goes through their half columns H = L^-1 P U of the factor
// K_f = P^T L L^T P (LaggedFactor::columns): Y from H^T H, and a correction of a solve pair
// between its two halves (SupernodalSolve::forward .. backward). A preconditioner step with
// Woodbury's correction and the projection onto the equalities costs one solve pair, and a new
// factor's contact nodes cost a forward solve each, along their elimination path only.
#pragma once
#include <Eigen/LU>
#include <Eigen/QR>
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "solver/frictional_contact.hpp"
#include "solver/lagged_factor.hpp"
#include "solver/flexible_cg.hpp"
#include "solver/pcg.hpp"
#include "solver/stall_watch.hpp"
#include "solver/velocity_solver.hpp"

namespace mica {

// What the factored solver keeps per body.
struct FactoredBodyCache {
  LaggedFactor factor;
  std::vector<Mat3> node_rotation;  // per node, for warping the factor
  // H_a^T H_b among the last solve's contact nodes (the factor's frame, 3 x 3 blocks by slot), of
  // the factor's columns `columns` (LaggedFactor::columns_id): the next solve copies the blocks of
  // the nodes it still has (the same bits) and makes only the new ones' (prepare_contact_nodes).
  struct Products {
    std::vector<int32_t> node;
    Eigen::MatrixXd blocks;
    uint64_t columns = 0;  // 0: none
  } products, products_next;
  int64_t factorizations() const { return factor.factorizations(); }
  int64_t factor_waits() const { return factor.waits(); }
};

// Each body's factor is updated once per solve for its SystemKey and constraint version
// (LaggedFactor::update); a co-rotational body's (SolverBody::rotation) is warped by its node
// rotations and refreshed every SolverSettings::refactor_interval solves in the background.
//
// Allocation: solve() allocates only while its workspaces grow: on the first solves, when the
// contact rows or their nodes change in number (W, Y, the small problem's and the active set's
// workspaces are sized by them; the active set's decompositions, one per size, only grow with
// them), and for the half columns of a node new to contact (a factor made or adopted remakes
// those it has in the same buffers).
// Otherwise it makes no heap allocation (tests/solver/test_solve_allocations.cpp).
class FactoredMicaSolver : public CachingVelocitySolver<FactoredBodyCache> {
 public:
  explicit FactoredMicaSolver(const SolverSettings& settings = {}) : settings_(settings) {}
  // prepare() (the factors, their preconditioners, W), then the active-set loop's rounds
  // (solve_active_set), and the alternating loop's (alternate) where those did not settle.
  SolveReport solve(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                    std::vector<double>& lambda) override;
  // W_rr of the last solve, per row (0 for a row nothing can move along).
  const std::vector<double>& row_diagonal() const override { return compliance_.diag; }
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
  // The active-set loop: once a round's solve is this close (relative residual), it checks its set
  // at every iteration and gives the set up as soon as it is clearly wrong (a pressing row pulls
  // or a free one sinks by kWrongSet of the impulses, or by kWrongFactor times the residual once
  // that is smaller), instead of polishing a solution the next round replaces. 0: never (each
  // round solves to the tolerance; the tests compare both).
  void set_check_residual(double residual) { set_check_residual_ = residual; }
  static constexpr double kSetCheckResidual = 1e-2;
  // A body's lagged factor goes on across a topology change as a bridge (LaggedFactor::remap).
  void remap(uint64_t key, const BodyRemap& change) override;
  int64_t factor_waits(uint64_t key) const override {
    const FactoredBodyCache* cache = find_cache(key);
    return cache ? cache->factor_waits() : 0;
  }
  // Each body's lagged factor (LaggedFactor::save, load).
  void save_body(uint64_t key, ByteWriter& out) const override;
  void restore_bodies(const std::vector<SavedBody>& bodies) override;

 private:
  // A body's contact nodes in a solve (its rows' terms' and extra stiffness's nodes: U), their
  // half columns and the compliance among them, world frame, 3 entries per slot (m slots).
  struct ContactNodes {
    std::vector<int32_t> node;                    // per slot
    std::vector<const SupernodalSolve::HalfColumns*> columns;  // per slot: its half columns (the factor's frame)
    std::vector<Mat3> to_world;                   // per slot: S_i Q_i (P^-1 = S Q K_f^-1 Q^T S)
    Eigen::MatrixXd Y;                            // U^T P^-1 U
    bool corrected = false;                       // C != 0 (else M = I, Yc = Y)
    Eigen::MatrixXd C;                            // S U^T (extra stiffness) U S
    Eigen::MatrixXd M;                            // (I + C Y)^-1
    Eigen::MatrixXd Yc;                           // U^T P_c^-1 U = Y M
    Eigen::MatrixXd Z;                            // Yc D: the slots' response to each row (build_compliance)
    Eigen::PartialPivLU<Eigen::MatrixXd> lu;      // of I + C Y
    // Node forces, M force; t = U^T z of a preconditioner's z = P^-1 r, u = U^T of z corrected (as
    // of the forces); U^T of a response: the values a single-precision backward solve only
    // approximates, put back exactly.
    Eigen::VectorXd force, moved, t, u, exact;
    Eigen::VectorXd load;  // the equalities' impulses on the contact nodes (equality_loads)
  };
  // Per body of a solve: its factor, updated for this solve's system and constraints, and what
  // its velocity solve needs beyond SolverBody. As a preconditioner, z = P_c^-1 r: the warped
  // factor with Woodbury's correction between its halves.
  struct FactoredBody : Preconditioner {
    LaggedFactor* factor = nullptr;
    FactoredBodyCache* cache = nullptr;               // the body's (factor is its)
    const std::vector<Mat3>* node_rotation = nullptr;  // null: the linear model (no warping)
    const Projection* projection = nullptr;
    WarpedFactorPreconditioner warp;  // bound to factor
    PcgSolver pcg;                    // preconditioned by this
    Vec3List rhs;                     // b + G^T lambda
    ContactNodes nodes;
    Eigen::VectorXd response;  // y with S Q y = P_c^-1 U f (the factor's frame, 3 per node: respond)

    void apply(const Vec3List& r, Vec3List& z) override;
    // Between the halves of z = P^-1 r: t = U^T z, force = -C t (Woodbury's forces), u = U^T of z
    // corrected.
    void start_correction();
    // After the backward half into z (projected): z = u = t + Yc force exactly at the contact nodes.
    void finish_correction(Vec3List& z);
    // Adds the response to nodes.force, H M force (the factor's frame), to the halves' workspace;
    // false when there is no force.
    bool add_forces();
    // The response to the node forces nodes.force (U f), and nodes.exact; false when there are none.
    bool respond();
    // out += S Q response, with the contact nodes' exact values.
    void add_turned(Vec3List& out) const;
  };
  // The contact rows' compliance (nr rows, nt row terms): W = G P_c^-1 G^T of the factors in use,
  // which the rounds' secant updates correct toward A's, and how the terms find their nodes.
  struct Compliance {
    std::vector<int32_t> term_slot;  // per row term: its node's slot in its body's nodes
    std::vector<int32_t> term_row;   // per row term: its row
    Eigen::MatrixXd W;               // nr x nr
    std::vector<double> diag;        // W_rr, 0 for a row nothing can move along (row_diagonal)
    std::vector<double> warped_diag;  // W_rr before the secant updates
    // Two solved velocity fields s apart in the impulses measure the true compliance along it,
    // y = w - w_prev: a BFGS update takes that into W (kept symmetric positive definite).
    Eigen::VectorXd s, y, Ws;  // (no allocation once sized)
    void secant_update(const std::vector<double>& w, const std::vector<double>& w_prev);
    std::vector<int32_t> slot_of, last_slot;  // per node of the largest body, -1 (prepare_contact_nodes')
  };
  // The small contact problem on W (n <= nr live rows: those something can move along).
  struct SmallProblem {
    std::vector<double> lambda_next;  // per row: its solution
    bool lemke_failed = false;        // Lemke's pivoting found no solution this solve (solve_small_lcp)
    bool lemke_ray = false;           // ... because it ended on a ray: the rows have none
    std::vector<int32_t> live, live_at;  // per live row its row; per row its live row or -1
    Eigen::MatrixXd M;                   // W on the live rows, n x n
    Eigen::VectorXd q, mu, start;
    std::vector<int32_t> normal;
    FrictionalSolution solution;
    FrictionalWorkspace workspace;
  };
  // What the rounds of both loops measure (nr rows).
  struct Rounds {
    std::vector<double> w, w_prev;  // G v + bias of the current velocities, and of the last round's
    std::vector<double> dlambda;    // the small problem's change of the impulses (the alternating loop's)
    // The squared impulse that changes a row's velocity by the speed of its nodes (the largest over
    // the rows): the tests' impulse scale is at least this. Below it a row velocity is zero to the
    // tolerance, and impulses and their complementarity are the solves' round-off: two bodies that
    // touch and fall together carry none, and a test relative to their ~1e-23 N s never passed.
    double impulse_floor2 = 0;
  };
  // The active-set loop's (ne <= nr equalities, nb bodies).
  struct ActiveSet {
    std::vector<int32_t> eq;  // the rows held as equalities
    Eigen::MatrixXd W0;       // G P_c^-1 G^T of the factor, without the secant updates (the projections need it exact)
    // Sized to the largest active set seen (only ever grown); a set of ne rows uses the first ne
    // entries (ne^2 of W_eq, column-major).
    Eigen::VectorXd W_eq;
    std::vector<std::unique_ptr<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>> W_eq_solvers;  // by size
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>* W_eq_solver = nullptr;  // this set's
    Eigen::VectorXd mu, mu_total, gap, eq_work, eq_y;  // per equality (nr entries kept)
    std::vector<double> fixed, lambda_prev, lambda_check;  // per row
    std::vector<double> row_weight;                        // per row: add_response's weights
    std::vector<double> body_scale2;  // per body: |f|^2 (or its mass floor), constrained_solve's scale
    FlexibleCg<BodyVectors> cg;       // per body, of the unknown y = S (v - z)
    BodyVectors y, t, f;              // per body: y, scratch, the right-hand side S (b + G_F^T lambda_F - A z)
    // The decomposition kept for active sets of ne rows, and those of every size up to nr made at once.
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>& equality_solver(Eigen::Index ne);
    void prepare_equality_solvers(Eigen::Index nr);
    // x = W_E^-1 rhs (the least-squares solution where rows are redundant).
    void solve_equalities(const Eigen::Ref<const Eigen::VectorXd>& rhs, Eigen::Ref<Eigen::VectorXd> x);
  };
  // The alternating loop's state (solve()).
  struct Alternation {
    explicit Alternation(int32_t stall_rounds) : progress(stall_rounds) {}
    int32_t round = 0;
    bool may_refactor = false;  // only co-rotational bodies: a linear body's factor is its A
    double final_tolerance = 0, inner_tolerance = 1, previous_inner_tolerance = 1;
    double tighten = 1;  // without contact rows: how much tighter than the tolerance the solves must aim
    bool velocities_solved = false;
    double l_scale = 0;  // the impulses' scale, set by the first correction
    StallWatch progress;
  };

  // Each body's factor brought up to its system, the preconditioners bound, W (factored_).
  void prepare(const std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda);
  void update_factors(const std::vector<SolverBody>& bodies);
  // W, its diagonal and the rows nothing can move along, from the factor in use.
  void start_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda);
  void build_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows);
  // The contact nodes, their half columns, Y and the Woodbury terms of each body (nodes,
  // term_slot).
  void prepare_contact_nodes(const std::vector<SolverBody>& bodies, const ContactRows& rows);
  // v += P_c^-1 G^T dlambda (a backward solve of the half columns).
  void apply_impulse_change(std::vector<SolverBody>& bodies, const ContactRows& rows,
                            const std::vector<double>& dlambda);
  // small_.lambda_next solves the contact problem on W around lambda: on normal rows
  // 0 <= lambda_next _|_ w + W (lambda_next - lambda) >= 0, on tangent pairs Coulomb's cone
  // (frictional_contact.hpp).
  void solve_small_lcp(const ContactRows& rows, double tolerance, const std::vector<double>& lambda,
                       const std::optional<std::chrono::steady_clock::time_point>& deadline);
  // Of the current lambda against the current row velocities rounds_.w (N s).
  double complementarity_error(const ContactRows& rows, const std::vector<double>& lambda);
  // The current systems factored now (co-rotational bodies), W and its diagonal from the new factor.
  void refactor_now(const std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda);
  // rounds_.w = G v + bias of the bodies' current velocities, and rounds_.impulse_floor2.
  void row_velocities(const std::vector<SolverBody>& bodies, const ContactRows& rows);
  // y such that S Q y = P_c^-1 G^T w on body bi for row weights w (FactoredBody::response: a
  // backward solve of the half columns); false when no row with a weight has a term on the body.
  bool body_response(size_t bi, const ContactRows& rows, const std::vector<double>& w);
  // The report's measures of the velocities and impulses returned (contact_impulse scattered).
  void balance(std::vector<SolverBody>& bodies, const ContactRows& rows, const std::vector<double>& lambda,
               SolveReport& report);

  // The alternating loop (solve()), from the active-set loop's report (or none), in stages:
  SolveReport alternate(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                        std::vector<double>& lambda, SolveReport report);
  // A v = b + G^T lambda on each body, to this round's tolerance.
  void solve_velocities(const std::optional<SolveContext::Clock::time_point>& deadline,
                        std::vector<SolverBody>& bodies, const ContactRows& rows, const std::vector<double>& lambda,
                        Alternation& a, SolveReport& report);
  // Without contact rows: whether the solves go on (tighter, or after a refactor) or stop.
  bool solve_again(const std::vector<SolverBody>& bodies, Alternation& a, SolveReport& report);
  // The row velocities of the solved velocities, what they teach W, and the small problem's
  // impulses (small_.lambda_next, rounds_.dlambda).
  void predict_impulses(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                        const std::vector<double>& lambda,
                        const std::optional<SolveContext::Clock::time_point>& deadline, Alternation& a);
  // Whether the impulses have settled with the velocities balancing them (converged).
  bool settled(const std::vector<SolverBody>& bodies, const ContactRows& rows, const std::vector<double>& lambda,
               Alternation& a, SolveReport& report);

  // The active-set loop (factored_mica_active_set.cpp, SolverSettings::active_set).
  SolveReport solve_active_set(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                               std::vector<double>& lambda);
  // active_.eq: the rows held as equalities for these impulses (pressing normal rows, sticking
  // tangent pairs), and W_E = G_E P^-1 G_E^T factored; impulses at round-off level set to 0.
  void choose_equalities(const ContactRows& rows, std::vector<double>& lambda);
  // A v = b + G^T lambda with G_E v + bias_E = 0, by projected PCG; lambda_E out, the rest fixed.
  // Stops early with set_changed when the set is clearly wrong (set_clearly_wrong), impulse_scale2
  // the squared size of the step's impulses so far.
  SolveReport constrained_solve(std::vector<SolverBody>& bodies, const ContactRows& rows, std::vector<double>& lambda,
                                double tolerance, int32_t cap,
                                const std::optional<SolveContext::Clock::time_point>& deadline, double impulse_scale2,
                                bool& set_changed);
  // constrained_solve's start: the fixed impulses' right-hand side f, and y from the warm start
  // onto the equalities.
  void start_constrained(std::vector<SolverBody>& bodies, const ContactRows& rows, const std::vector<double>& lambda);
  // z = P_c^-1 r projected onto G_E z = 0, and mu, the impulses on E the residual asks for.
  void precondition_constrained(const std::vector<SolverBody>& bodies, const ContactRows& rows);
  // The equalities take mu's share of the residual; the worst body's relative residual, squared.
  double constrained_residual2(const std::vector<SolverBody>& bodies, const ContactRows& rows);
  // During constrained_solve, at relative residual `residual`: the complementarity error of its
  // normal rows' impulses and velocities so far is above min(kWrongSet, kWrongFactor residual) of
  // the impulses (it leaves them in lambda_check and rounds_.w). A right set's error shrinks with
  // the residual (about 1e-16 of the impulses once solved); a wrong set's settles at the size of the
  // impulse it gets wrong, which may be below kWrongSet.
  bool set_clearly_wrong(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                         const std::vector<double>& lambda, const Eigen::Ref<const Eigen::VectorXd>& mu_total,
                         double impulse_scale2, double residual);
  static constexpr double kWrongSet = 1e-2;
  static constexpr double kWrongFactor = 3;
  // out += P_c^-1 G_which^T x (a backward solve of the half columns).
  void add_response(const std::vector<SolverBody>& bodies, const ContactRows& rows, const std::vector<int32_t>& which,
                    const Eigen::Ref<const Eigen::VectorXd>& x, BodyVectors& out);
  // out -= S G_E^T x.
  void subtract_row_forces(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                           const Eigen::Ref<const Eigen::VectorXd>& x, BodyVectors& out) const;
  // nodes.load = S G_E^T x on each body's contact nodes, the equalities' load on the bodies (part
  // of the scale of constrained_solve's residual).
  void equality_loads(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                      const Eigen::Ref<const Eigen::VectorXd>& x);
  // out = G_E y (no bias).
  void rows_times(const ContactRows& rows, const BodyVectors& y, Eigen::Ref<Eigen::VectorXd> out) const;
  // out = G_E U u of the bodies' nodes.u, and each body's force -= U^T G_E^T x.
  void rows_times_nodes(const ContactRows& rows, Eigen::Ref<Eigen::VectorXd> out) const;
  void subtract_node_forces(const ContactRows& rows, const Eigen::Ref<const Eigen::VectorXd>& x);

  SolverSettings settings_;
  double set_check_residual_ = kSetCheckResidual;
  std::vector<FactoredBody> factored_;  // per body
  Compliance compliance_;
  SmallProblem small_;
  Rounds rounds_;
  ActiveSet active_;
};

}  // namespace mica
