// SPDX-License-Identifier: Apache-2.0
// The factored MICA loop with the contact rows predicted active held as equalities inside the
// velocity solve (SolverSettings::active_set). Each round:
//  1. a small complementarity problem on W (the factor's compliance, secant-updated) predicts the
//     impulses, and with them which rows press (normal rows with lambda > 0, tangent pairs that
//     stick) and the impulses of the rest (sliding tangent pairs, kept fixed for the round);
//  2. one projected conjugate-gradient solve of the whole step, A v = b + G^T lambda with
//     G_E v + bias_E = 0 on the pressing rows E, gives velocities and lambda_E that balance A, not
//     its factor (Gould, Hribar and Nocedal 2001, the constraint preconditioner
//     [P C^T; C 0] with P the warped factor: a step of it costs one solve pair);
//  3. done when the solved impulses and row velocities are complementary (the natural residual
//     of factored_mica.cpp's test) and the momentum balances; else step 1 around them.
// A round costs one solve to tolerance; the alternating loop needs ~10 rounds of inexact solves
// per step where the factor's compliance misses A's (rotations turned since it was made), this
// one 1-2 on the nidus press (the active set and sliding directions settle), so far fewer solve
// pairs per step.
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>

#include "core/error.hpp"
#include "solver/cod_solve.hpp"
#include "solver/factored_mica.hpp"
#include "solver/flexible_cg.hpp"

namespace mica {

namespace {

// Rounds of the active-set loop before it hands over to the alternating loop (a set that keeps
// changing: contacts flickering at the threshold of pressing or sticking).
constexpr int32_t kMaxRounds = 25;

void project_free(const Projection& projection, Vec3List& y) {
  for (int32_t i : projection.nodes) y[i] = projection.S[i] * y[i];
}

// v has at least n entries (grown, never shrunk: a smaller Eigen vector would be a new block).
void at_least(Eigen::VectorXd& v, Eigen::Index n) {
  if (v.size() < n) v.resize(n);
}

}  // namespace

void FactoredMicaSolver::choose_equalities(const ContactRows& rows, std::vector<double>& lambda) {
  ActiveSet& as = active_;
  const std::vector<double>& diag = compliance_.diag;
  // Impulses below 1e-12 of the largest are the small solver's round-off: not pressing.
  double largest = 0;
  for (size_t r = 0; r < rows.size(); ++r)
    if (rows.normal_of[r] < 0) largest = std::max(largest, lambda[r]);
  const double pressing = 1e-12 * largest;
  as.eq.clear();
  for (size_t r = 0; r < rows.size(); ++r) {
    const int32_t n = rows.normal_of[r];
    if (n < 0) {
      if (lambda[r] <= pressing) lambda[r] = 0;
      else if (diag[r] > 0) as.eq.push_back(int32_t(r));
      continue;
    }
    if (lambda[n] == 0) lambda[r] = 0;  // the normal row comes first: already cleared
    if (lambda[n] == 0 || diag[r] == 0 || diag[n] == 0) continue;
    const size_t first = rows.first_tangent(r) ? r : r - 1;  // the pair sticks or slides together
    const double t = std::hypot(lambda[first], lambda[first + 1]);
    if (t < (1 - 1e-6) * rows.mu[r] * lambda[n]) as.eq.push_back(int32_t(r));  // inside the disk: sticks
  }
  const Eigen::Index ne = Eigen::Index(as.eq.size()), nr = Eigen::Index(rows.size());
  // Workspaces for any active set of these rows (ne <= nr), grown with the rows only.
  at_least(as.W_eq, nr * nr);
  for (Eigen::VectorXd* v : {&as.mu, &as.mu_total, &as.gap, &as.eq_work, &as.eq_y}) at_least(*v, nr);
  as.prepare_equality_solvers(nr);
  Eigen::Map<Eigen::MatrixXd> W_eq(as.W_eq.data(), ne, ne);
  for (Eigen::Index a = 0; a < ne; ++a)
    for (Eigen::Index b = 0; b < ne; ++b) W_eq(a, b) = as.W0(as.eq[a], as.eq[b]);
  // Rank-revealing: rows pressing on nodes that cannot all move independently are redundant.
  if (ne > 0) {
    as.W_eq_solver = &as.equality_solver(ne);
    as.W_eq_solver->setThreshold(1e-10);
    as.W_eq_solver->compute(W_eq);
  }
}

// One decomposition per size (Eigen's would allocate its matrices afresh for another size), made
// for every size up to the rows' count when the rows first reach it, up to kPreparedEqualitySizes
// (their memory is ~ n^3 / 3 doubles: 5.6 MB at 128); larger sets make theirs on first use.
constexpr Eigen::Index kPreparedEqualitySizes = 128;

void FactoredMicaSolver::ActiveSet::prepare_equality_solvers(Eigen::Index nr) {
  for (Eigen::Index k = Eigen::Index(W_eq_solvers.size()); k <= std::min(nr, kPreparedEqualitySizes); ++k)
    W_eq_solvers.push_back(std::make_unique<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(k, k));
}

Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>& FactoredMicaSolver::ActiveSet::equality_solver(
    Eigen::Index ne) {
  if (Eigen::Index(W_eq_solvers.size()) <= ne) W_eq_solvers.resize(size_t(ne) + 1);
  auto& solver = W_eq_solvers[size_t(ne)];
  if (!solver) solver = std::make_unique<Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>>(ne, ne);
  return *solver;
}

void FactoredMicaSolver::ActiveSet::solve_equalities(const Eigen::Ref<const Eigen::VectorXd>& rhs,
                                                     Eigen::Ref<Eigen::VectorXd> x) {
  if (!eq.empty()) cod_solve(*W_eq_solver, rhs, x, eq_work, eq_y);
}

void FactoredMicaSolver::add_response(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                      const std::vector<int32_t>& which, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      BodyVectors& out) {
  std::vector<double>& weight = active_.row_weight;
  weight.assign(rows.size(), 0.0);  // keeps its capacity
  for (size_t a = 0; a < which.size(); ++a) weight[size_t(which[a])] = x(Eigen::Index(a));
  for (size_t bi = 0; bi < bodies.size(); ++bi)
    if (body_response(bi, rows, weight)) factored_[bi].add_turned(out[bi]);
}

void FactoredMicaSolver::subtract_row_forces(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                             const Eigen::Ref<const Eigen::VectorXd>& x, BodyVectors& out) const {
  const std::vector<int32_t>& eq = active_.eq;
  for (size_t a = 0; a < eq.size(); ++a) {
    const int32_t r = eq[a];
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const RowTerm& term = rows.terms[t];
      const Vec3 g = term.coef * x(Eigen::Index(a)) * rows.direction[r];
      out[term.body][term.node] -= bodies[term.body].projection->free_part(term.node, g);
    }
  }
}

void FactoredMicaSolver::rows_times_nodes(const ContactRows& rows, Eigen::Ref<Eigen::VectorXd> out) const {
  const std::vector<int32_t>& eq = active_.eq;
  for (size_t a = 0; a < eq.size(); ++a) {
    const int32_t r = eq[a];
    double c = 0;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
      c += rows.terms[t].coef *
           rows.direction[r].dot(factored_[rows.terms[t].body].nodes.u.segment<3>(3 * compliance_.term_slot[t]));
    out(Eigen::Index(a)) = c;
  }
}

void FactoredMicaSolver::subtract_node_forces(const ContactRows& rows, const Eigen::Ref<const Eigen::VectorXd>& x) {
  const std::vector<int32_t>& eq = active_.eq;
  for (size_t a = 0; a < eq.size(); ++a) {
    const int32_t r = eq[a];
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
      factored_[rows.terms[t].body].nodes.force.segment<3>(3 * compliance_.term_slot[t]) -=
          (rows.terms[t].coef * x(Eigen::Index(a))) * rows.direction[r];
  }
}

void FactoredMicaSolver::rows_times(const ContactRows& rows, const BodyVectors& y,
                                    Eigen::Ref<Eigen::VectorXd> out) const {
  const std::vector<int32_t>& eq = active_.eq;
  for (size_t a = 0; a < eq.size(); ++a) {
    const int32_t r = eq[a];
    double c = 0;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
      c += rows.terms[t].coef * rows.direction[r].dot(y[rows.terms[t].body][rows.terms[t].node]);
    out(Eigen::Index(a)) = c;
  }
}

void FactoredMicaSolver::equality_loads(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                        const Eigen::Ref<const Eigen::VectorXd>& x) {
  const std::vector<int32_t>& eq = active_.eq;
  for (FactoredBody& f : factored_) f.nodes.load.setZero();
  for (size_t a = 0; a < eq.size(); ++a) {
    const int32_t r = eq[a];
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const RowTerm& term = rows.terms[t];
      const Vec3 g = term.coef * x(Eigen::Index(a)) * rows.direction[r];
      factored_[term.body].nodes.load.segment<3>(3 * compliance_.term_slot[t]) +=
          bodies[term.body].projection->free_part(term.node, g);
    }
  }
}

bool FactoredMicaSolver::set_clearly_wrong(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                           const std::vector<double>& lambda,
                                           const Eigen::Ref<const Eigen::VectorXd>& mu_total, double impulse_scale2,
                                           double residual) {
  ActiveSet& as = active_;
  std::vector<double>& w = rounds_.w;
  // The impulses and row velocities of the solve so far: lambda_E from the equalities' share, the
  // rest as fixed; v = y + z at the rows' nodes.
  std::vector<double>& check = as.lambda_check;
  check = lambda;
  for (size_t a = 0; a < as.eq.size(); ++a) check[size_t(as.eq[a])] = -mu_total(Eigen::Index(a));
  w.assign(rows.size(), 0.0);
  double l2 = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    double c = rows.bias[r];
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const RowTerm& term = rows.terms[t];
      const Projection& p = *bodies[term.body].projection;
      Vec3 v = as.y[term.body][term.node];
      if (p.active() && p.is_constrained[term.node]) v += p.z[term.node];
      c += term.coef * rows.direction[r].dot(v);
    }
    w[r] = c;
    l2 += check[r] * check[r];
  }
  // A right set of normal rows gives no complementarity error however loosely solved (pressing
  // rows push, the others do not sink); a wrong one an error of the size of the impulse it gets
  // wrong. (Not the friction pairs: a sticking pair's impulse wanders across its disk's edge while
  // the solve is loose.)
  double e2 = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows.normal_of[r] >= 0 || compliance_.diag[r] == 0) continue;
    const double next = std::max(0.0, check[r] - w[r] / compliance_.warped_diag[r]);
    e2 += (next - check[r]) * (next - check[r]);
  }
  // The limit follows the residual down: a round that would converge with its set still wrong
  // (its error settling below kWrongSet) stops when the error no longer shrinks with it, not
  // after a full solve (8-9 iterations of a nidus step, in about 1 step of 20).
  const double limit = std::min(kWrongSet, kWrongFactor * residual);
  return e2 > limit * limit * std::max({l2, impulse_scale2, rounds_.impulse_floor2, 1e-300});
}

void FactoredMicaSolver::start_constrained(std::vector<SolverBody>& bodies, const ContactRows& rows,
                                           const std::vector<double>& lambda) {
  ActiveSet& as = active_;
  FlexibleCg<BodyVectors>& cg = as.cg;
  const size_t nb = bodies.size();
  const std::initializer_list<BodyVectors*> vectors = {&cg.r, &cg.z, &cg.p, &cg.q, &cg.z_last, &as.y, &as.t, &as.f};
  for (BodyVectors* v : vectors) v->resize(nb);
  // The fixed impulses: every row but the equalities.
  as.fixed = lambda;
  for (int32_t r : as.eq) as.fixed[r] = 0;
  scatter_contact_impulses(rows, as.fixed, bodies);
  for (size_t bi = 0; bi < nb; ++bi) {
    const SolverBody& body = bodies[bi];
    const size_t n = size_t(body.node_count());
    for (BodyVectors* v : vectors) (*v)[bi].resize(n);
    Vec3List& rhs = factored_[bi].rhs;
    rhs = *body.b;
    for (size_t i = 0; i < n; ++i) rhs[i] += (*body.contact_impulse)[i];
    body.projected().right_hand_side(rhs, as.f[bi], as.t[bi]);  // S (b + G_F^T lambda_F - A z)
    as.y[bi] = *body.v;
    project_free(*body.projection, as.y[bi]);  // the unknown y = S (v - z)
  }
  // Onto the equalities: G_E (y + z) + bias_E = 0, through P^-1 G_E^T and W_E = G_E P^-1 G_E^T.
  const Eigen::Index ne = Eigen::Index(as.eq.size());
  auto gap = as.gap.head(ne);
  auto mu = as.mu.head(ne);
  rows_times(rows, as.y, gap);
  for (size_t a = 0; a < as.eq.size(); ++a) {
    const int32_t r = as.eq[a];
    double c = rows.bias[r];
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const SolverBody& body = bodies[rows.terms[t].body];
      const int32_t i = rows.terms[t].node;
      if (body.projection->active() && body.projection->is_constrained[i])
        c += rows.terms[t].coef * rows.direction[r].dot(body.projection->z[i]);
    }
    gap(Eigen::Index(a)) = -(gap(Eigen::Index(a)) + c);
  }
  as.solve_equalities(gap, mu);
  add_response(bodies, rows, as.eq, mu, as.y);
  // Each body's residual is relative to its own loads, as in the momentum test that follows the
  // solve (momentum_residual): a small body's may not hide in a large one's.
  as.body_scale2.resize(nb);
  for (size_t bi = 0; bi < nb; ++bi) {
    const ProjectedSystem sys = bodies[bi].projected();
    sys.apply(as.y[bi], cg.q[bi], as.t[bi]);
    for (size_t i = 0; i < as.y[bi].size(); ++i) cg.r[bi][i] = as.f[bi][i] - cg.q[bi][i];
    double floor2 = 0;  // momentum_residual's floor, 1e-6 of each node's mass
    for (double m : bodies[bi].fem->node_mass) floor2 += 1e-12 * m * m;
    as.body_scale2[bi] = std::max(flat(as.f[bi]).squaredNorm(), floor2);
  }
  as.mu_total.head(ne).setZero();
}

void FactoredMicaSolver::precondition_constrained(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  // Both corrections of P^-1 r (Woodbury's and the projection's) are responses to forces on the
  // contact nodes, added between the halves of its solve pair.
  ActiveSet& as = active_;
  const Eigen::Index ne = Eigen::Index(as.eq.size());
  auto gap = as.gap.head(ne);
  auto mu = as.mu.head(ne);
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    factored_[bi].warp.forward(as.cg.r[bi]);
    factored_[bi].start_correction();
  }
  rows_times_nodes(rows, gap);
  as.solve_equalities(gap, mu);
  subtract_node_forces(rows, mu);
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    FactoredBody& f = factored_[bi];
    f.add_forces();
    f.warp.backward(as.cg.z[bi]);
    project_free(*bodies[bi].projection, as.cg.z[bi]);
    f.finish_correction(as.cg.z[bi]);
  }
}

double FactoredMicaSolver::constrained_residual2(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  // The equalities take their share of the residual, r -= S G_E^T mu, at every step (the
  // residual update of Gould, Hribar and Nocedal: without it round-off in the projection stalls
  // the residual of a solve far from its factor's system); what is left must be small.
  ActiveSet& as = active_;
  const Eigen::Index ne = Eigen::Index(as.eq.size());
  auto mu = as.mu.head(ne), mu_total = as.mu_total.head(ne);
  mu_total += mu;
  subtract_row_forces(bodies, rows, mu, as.cg.r);
  equality_loads(bodies, rows, mu_total);
  double worst2 = 0;
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    const double g2 = flat(as.cg.r[bi]).squaredNorm();
    if (!std::isfinite(g2)) fail(Errc::Numerical, "the constrained velocity solve diverged (loads or state overflow)");
    worst2 = std::max(worst2, g2 / std::max({as.body_scale2[bi], factored_[bi].nodes.load.squaredNorm(), 1e-300}));
  }
  return worst2;
}

SolveReport FactoredMicaSolver::constrained_solve(std::vector<SolverBody>& bodies, const ContactRows& rows,
                                                  std::vector<double>& lambda, double tolerance, int32_t cap,
                                                  const std::optional<SolveContext::Clock::time_point>& deadline,
                                                  double impulse_scale2, bool& set_changed) {
  ActiveSet& as = active_;
  start_constrained(bodies, rows, lambda);
  const auto mu_total = as.mu_total.head(Eigen::Index(as.eq.size()));
  const auto apply = [&](const BodyVectors& p, BodyVectors& q) {
    for (size_t bi = 0; bi < bodies.size(); ++bi) bodies[bi].projected().apply(p[bi], q[bi], as.t[bi]);
  };
  set_changed = false;
  SolveReport report;
  as.cg.start();
  for (;;) {
    // z = P_c^-1 r projected onto G_E z = 0; mu: the impulses on E the residual asks for.
    precondition_constrained(bodies, rows);
    const double worst2 = constrained_residual2(bodies, rows);
    report.residual = std::sqrt(worst2);
    report.converged = worst2 <= tolerance * tolerance;
    if (report.converged || report.iterations >= cap) break;
    // A wrong set shows long before the solve is polished: stop, and the caller predicts again.
    if (report.residual <= set_check_residual_ &&
        set_clearly_wrong(bodies, rows, lambda, mu_total, impulse_scale2, report.residual)) {
      set_changed = true;
      break;
    }
    if (deadline && report.iterations > 0 && SolveContext::Clock::now() >= *deadline) {
      report.out_of_time = true;
      break;
    }
    if (!as.cg.step(as.y, apply)) break;  // breakdown: not positive definite on the equalities' null space
    ++report.iterations;
  }
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    Vec3List& v = *bodies[bi].v;
    v = as.y[bi];
    const Projection& p = *bodies[bi].projection;
    for (int32_t i : p.nodes) v[i] += p.z[i];
  }
  // The residual the equalities took, f - A y = S G_E^T mu_total = -S G_E^T lambda_E.
  for (size_t a = 0; a < as.eq.size(); ++a) lambda[as.eq[a]] = -mu_total(Eigen::Index(a));
  return report;
}

SolveReport FactoredMicaSolver::solve_active_set(const SolveContext& ctx, std::vector<SolverBody>& bodies,
                                                 const ContactRows& rows, std::vector<double>& lambda) {
  using Clock = SolveContext::Clock;
  const SolverSettings& settings = settings_;
  const std::optional<Clock::time_point>& deadline = ctx.deadline;
  const size_t nr = rows.size();
  ActiveSet& as = active_;
  std::vector<double>& lambda_next = small_.lambda_next;
  as.W0 = compliance_.W;
  bool may_refactor = false;
  for (const FactoredBody& f : factored_)
    may_refactor = may_refactor || (f.node_rotation && settings.refactor_after > 0);

  SolveReport report;
  report.converged = false;
  report.momentum_residual = std::numeric_limits<double>::quiet_NaN();
  // Each solve to the outer tolerance: its residual is relative to its right-hand side, which is
  // at most the momentum test's scale, so that test still passes (and when it does not, the next
  // round solves tighter). On the nidus, 10.7 -> 10.2 iterations a step against half the
  // tolerance, with the same rounds; 1.5 or 2 times it fail the momentum test: 1.37, 1.52 rounds.
  double tolerance = settings.tolerance;
  // The first prediction: the warm start's row velocities (the last step's solution).
  row_velocities(bodies, rows);
  solve_small_lcp(rows, settings.tolerance, lambda, deadline);
  double l_scale = 0;
  for (double l : lambda_next) l_scale += l * l;
  int32_t outer = 0;
  bool have_pair = false;  // lambda_prev and w_prev are a solved round of this solve and factor
  while (report.iterations < settings.max_iterations) {
    if (deadline && outer > 0 && Clock::now() >= *deadline) {
      report.out_of_time = true;
      break;
    }
    if (may_refactor && report.iterations >= settings.refactor_after) {  // as in solve(): once
      refactor_now(bodies, rows, lambda_next);
      as.W0 = compliance_.W;
      may_refactor = false;
      have_pair = false;
    }
    ++outer;
    ++report.solves;
    lambda = lambda_next;
    choose_equalities(rows, lambda);
    const int32_t cap = may_refactor ? std::max(1, settings.refactor_after - report.iterations)
                                     : settings.max_iterations - report.iterations;
    bool set_changed = false;
    const SolveReport s =
        constrained_solve(bodies, rows, lambda, tolerance, std::max(cap, 1), deadline, l_scale, set_changed);
    report.iterations += std::max(1, s.iterations);
    report.velocity_change = s.residual;
    report.out_of_time = s.out_of_time;
    if (s.out_of_time) break;
    if (set_changed) {  // stopped early: predict again around its impulses (no secant pair: not solved)
      row_velocities(bodies, rows);
      have_pair = false;
      if (outer >= kMaxRounds) break;
      solve_small_lcp(rows, settings.tolerance, lambda, deadline);
      continue;
    }
    if (!s.converged) {
      if (may_refactor) continue;  // stopped where refactoring pays: refactor, go on
      break;
    }
    // Solved: the impulses balance A with the equalities held. Done when they and the row
    // velocities are complementary (the natural residual, as in solve()) and the momentum balances.
    // The impulses of redundant rows are not unique, so the test is on (lambda, w), not on how far
    // the small problem would move lambda.
    row_velocities(bodies, rows);
    double l2 = 0;
    for (double l : lambda) l2 += l * l;
    l_scale = std::max(l_scale, l2);
    report.impulse_change =
        complementarity_error(rows, lambda) / std::sqrt(std::max({l_scale, rounds_.impulse_floor2, 1e-300}));
    if (report.impulse_change <= settings.tolerance) {
      rows.project(lambda);  // a sliding pair kept its impulse while lambda_n was solved: back onto the disk
      balance(bodies, rows, lambda, report);
      report.converged = report.momentum_residual <= settings.tolerance;
      if (report.converged) return report;
      // Solved to its own test but not to the momentum test (the recurrence's residual has drifted
      // from the true one): the next round solves tighter, or it would repeat this one.
      tolerance = std::max(0.1 * tolerance, 1e-15);
    }
    if (outer >= kMaxRounds) break;  // the set keeps changing: the alternating loop takes over (solve())
    // The solved pair measures the true compliance along the impulses' change (secant update, as
    // in solve()); then the small problem around the solved impulses predicts the next set.
    if (have_pair) {
      compliance_.s = Eigen::Map<const Eigen::VectorXd>(lambda.data(), Eigen::Index(nr)) -
                      Eigen::Map<const Eigen::VectorXd>(as.lambda_prev.data(), Eigen::Index(nr));
      compliance_.secant_update(rounds_.w, rounds_.w_prev);
    }
    rounds_.w_prev = rounds_.w;
    as.lambda_prev = lambda;
    have_pair = true;
    solve_small_lcp(rows, settings.tolerance, lambda, deadline);
  }
  rows.project(lambda);
  balance(bodies, rows, lambda, report);
  return report;
}

}  // namespace mica
