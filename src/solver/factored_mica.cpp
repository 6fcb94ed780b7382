// SPDX-License-Identifier: Apache-2.0
#include "solver/factored_mica.hpp"

#include "solver/mica_solver.hpp"

#include "solver/friction_cone.hpp"
#include "solver/frictional_contact.hpp"
#include "solver/stall_watch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace mica {

namespace {

const Mat3& projector(const SolverBody& body, int32_t i) {
  static const Mat3 identity = Mat3::Identity();
  return body.projection->active() && body.projection->is_constrained[i] ? body.projection->S[i] : identity;
}

}  // namespace

void FactoredMicaSolver::update_factors(const std::vector<SolverBody>& bodies) {
  factored_.resize(bodies.size());
  for (size_t k = 0; k < bodies.size(); ++k) {
    const SolverBody& b = bodies[k];
    FactoredBodyCache& cache = cache_of(b);
    const std::vector<Mat3>* rotation = nullptr;
    if (b.rotation) {
      compute_node_rotations(*b.fem, *b.rotation, cache.node_rotation);
      rotation = &cache.node_rotation;
    }
    const LaggedFactor::Key key{b.system.h, b.system.alpha, b.system.beta, b.constraint_version};
    cache.factor.update(*b.fem, key, *b.A, *b.projection, rotation, rotation ? settings_.refactor_interval : 0,
                        b.extra_stiffness);
    factored_[k] = {&cache.factor, &cache, rotation, b.projection};
  }
}

void FactoredMicaSolver::prepare_contact_nodes(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  const size_t nt = rows.terms.size();
  nodes_.resize(bodies.size());
  term_slot_.resize(nt);
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    const SolverBody& body = bodies[bi];
    const FactoredBody& f = factored_[bi];
    ContactNodes& cn = nodes_[bi];
    if (slot_of_.size() < size_t(body.node_count())) slot_of_.resize(size_t(body.node_count()), -1);
    if (last_slot_.size() < size_t(body.node_count())) last_slot_.resize(size_t(body.node_count()), -1);
    cn.node.clear();
    const auto slot = [&](int32_t i) {
      if (slot_of_[i] < 0) {
        slot_of_[i] = int32_t(cn.node.size());
        cn.node.push_back(i);
      }
      return slot_of_[i];
    };
    for (size_t t = 0; t < nt; ++t)
      if (rows.terms[t].body == int32_t(bi)) term_slot_[t] = slot(rows.terms[t].node);
    const std::vector<TriangleStiffness>* extra = body.extra_stiffness;
    cn.corrected = extra && !extra->empty();
    if (cn.corrected)
      for (const TriangleStiffness& e : *extra)
        for (int32_t i : e.nodes) slot(i);
    f.factor->prepare_columns(cn.node);  // the new ones' columns, one solve per body
    const Eigen::Index m = Eigen::Index(cn.node.size());
    cn.columns.resize(size_t(m));
    cn.to_world.resize(size_t(m));
    for (Eigen::Index a = 0; a < m; ++a) {
      const int32_t i = cn.node[size_t(a)];
      cn.columns[size_t(a)] = &f.factor->columns(i);
      cn.to_world[size_t(a)] = projector(body, i) * f.factor->turn(f.node_rotation, i);
    }
    // Y from the products H_a^T H_b, those of nodes the last solve had (with these columns) kept.
    FactoredBodyCache::Products &last = f.cache->products, &next = f.cache->products_next;
    const bool columns_kept = last.columns == f.factor->columns_id();
    if (columns_kept)
      for (size_t a = 0; a < last.node.size(); ++a) last_slot_[last.node[a]] = int32_t(a);
    next.blocks.resize(3 * m, 3 * m);
    cn.Y.resize(3 * m, 3 * m);
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index b = a; b < m; ++b) {
        const int32_t la = last_slot_[cn.node[size_t(a)]], lb = last_slot_[cn.node[size_t(b)]];
        const Mat3 product = la >= 0 && lb >= 0
                                 ? Mat3(last.blocks.block<3, 3>(3 * la, 3 * lb))
                                 : SupernodalSolve::product(*cn.columns[size_t(a)], *cn.columns[size_t(b)]);
        next.blocks.block<3, 3>(3 * a, 3 * b) = product;
        next.blocks.block<3, 3>(3 * b, 3 * a) = product.transpose();
        const Mat3 block = cn.to_world[size_t(a)] * product * cn.to_world[size_t(b)].transpose();
        cn.Y.block<3, 3>(3 * a, 3 * b) = block;
        cn.Y.block<3, 3>(3 * b, 3 * a) = block.transpose();
      }
    if (columns_kept)
      for (int32_t i : last.node) last_slot_[i] = -1;
    next.node = cn.node;
    next.columns = f.factor->columns_id();
    std::swap(last, next);
    cn.force.setZero(3 * m);
    cn.t.setZero(3 * m);
    cn.u.setZero(3 * m);
    cn.exact.setZero(3 * m);
    cn.moved.setZero(3 * m);
    cn.load.setZero(3 * m);
    if (cn.corrected) {
      cn.C.setZero(3 * m, 3 * m);
      for (const TriangleStiffness& e : *extra)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            cn.C.block<3, 3>(3 * slot_of_[e.nodes[r]], 3 * slot_of_[e.nodes[c]]) +=
                projector(body, e.nodes[r]) * e.K.block<3, 3>(3 * r, 3 * c) * projector(body, e.nodes[c]);
      cn.M.noalias() = cn.C * cn.Y;
      cn.M.diagonal().array() += 1.0;
      cn.lu.compute(cn.M);  // C Y has eigenvalues >= 0 (C and Y positive semidefinite): I + C Y is regular
      cn.M.setIdentity();
      cn.Yc = cn.lu.solve(cn.M);  // (Eigen's inverse() allocates; a solve into another matrix does not)
      cn.M = cn.Yc;
      cn.Yc.noalias() = cn.Y * cn.M;
    } else {
      cn.Yc = cn.Y;
    }
    for (int32_t i : cn.node) slot_of_[i] = -1;
  }
}

void FactoredMicaSolver::build_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  prepare_contact_nodes(bodies, rows);
  const size_t nr = rows.size(), nt = rows.terms.size();
  std::vector<int32_t>& row_of = term_row_;
  row_of.resize(nt);
  for (size_t r = 0; r < nr; ++r)
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) row_of[t] = int32_t(r);
  // W = D^T Yc D per body, D's column r the row's direction at its terms' slots (coef_t d_r):
  // first Z = Yc D, the slots' response to each row's unit impulse, then W_rs = sum over the
  // terms t of row r of coef_t d_r^T Z_{slot t, s}. Term by term, not over pairs of terms: a
  // box tool teleported into two boxes made 507 rows of 1500 terms, whose 2.3 M pairs took
  // 50 ms a solve.
  for (ContactNodes& cn : nodes_) cn.Z.setZero(cn.Yc.rows(), Eigen::Index(nr));
  for (size_t u = 0; u < nt; ++u) {
    const RowTerm& b = rows.terms[u];
    ContactNodes& cn = nodes_[b.body];
    const Vec3 d = b.coef * rows.direction[row_of[u]];
    cn.Z.col(row_of[u]).noalias() += cn.Yc.middleCols<3>(3 * term_slot_[u]) * d;
  }
  W_.setZero(Eigen::Index(nr), Eigen::Index(nr));
  for (size_t t = 0; t < nt; ++t) {
    const RowTerm& a = rows.terms[t];
    const Vec3 d = a.coef * rows.direction[row_of[t]];
    W_.row(row_of[t]).noalias() += d.transpose() * nodes_[a.body].Z.middleRows<3>(3 * term_slot_[t]);
  }
}

void FactoredMicaSolver::start_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                          std::vector<double>& lambda) {
  const size_t nr = rows.size();
  build_compliance(bodies, rows);
  diag_.assign(nr, 0.0);
  warped_diag_.assign(nr, 0.0);
  const double w_max = nr ? W_.diagonal().cwiseAbs().maxCoeff() : 0.0;
  for (size_t r = 0; r < nr; ++r) {
    if (W_(r, r) > 1e-12 * w_max) diag_[r] = warped_diag_[r] = W_(r, r);
    else lambda[r] = 0;  // nothing can move along this row
  }
  rows.project(lambda);  // the warm start onto the cones
}

bool FactoredMicaSolver::body_response(size_t bi, const ContactRows& rows, const std::vector<double>& w) {
  ContactNodes& cn = nodes_[bi];
  cn.force.setZero();
  bool any = false;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (w[r] == 0) continue;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      if (rows.terms[t].body != int32_t(bi)) continue;
      cn.force.segment<3>(3 * term_slot_[t]) += (rows.terms[t].coef * w[r]) * rows.direction[r];
      any = true;
    }
  }
  return any && respond(bi);
}

bool FactoredMicaSolver::add_forces(size_t bi) {
  ContactNodes& cn = nodes_[bi];
  const Eigen::VectorXd* f = &cn.force;
  if (cn.corrected) {
    cn.moved.noalias() = cn.M * cn.force;  // P_c^-1 U = X M
    f = &cn.moved;
  }
  const SupernodalSolve& halves = factored_[bi].factor->halves();
  bool any = false;
  for (size_t a = 0; a < cn.node.size(); ++a) {
    const Vec3 g = cn.to_world[a].transpose() * f->segment<3>(3 * Eigen::Index(a));
    if (g.isZero(0)) continue;
    halves.add(*cn.columns[a], g);
    any = true;
  }
  return any;
}

bool FactoredMicaSolver::respond(size_t bi) {
  const SupernodalSolve& halves = factored_[bi].factor->halves();
  halves.clear(true);
  if (!add_forces(bi)) return false;
  y_.resize(3 * Eigen::Index(factored_[bi].factor->node_count()));
  halves.backward(y_.data());
  ContactNodes& cn = nodes_[bi];
  cn.exact.noalias() = cn.Yc * cn.force;  // U^T P_c^-1 U f
  return true;
}

void FactoredMicaSolver::add_turned(size_t bi, Vec3List& out) const {
  const FactoredBody& f = factored_[bi];
  const Projection& p = *f.projection;
  for (size_t i = 0; i < out.size(); ++i) {
    const Vec3 d = f.factor->turn(f.node_rotation, int32_t(i)) * y_.segment<3>(3 * Eigen::Index(i));
    out[i] += p.active() && p.is_constrained[i] ? Vec3(p.S[i] * d) : d;
  }
  const ContactNodes& cn = nodes_[bi];  // the contact nodes' exact values in place of y_'s
  for (size_t a = 0; a < cn.node.size(); ++a) {
    const int32_t i = cn.node[a];
    out[i] += cn.exact.segment<3>(3 * Eigen::Index(a)) - cn.to_world[a] * y_.segment<3>(3 * Eigen::Index(i));
  }
}

void FactoredMicaSolver::start_correction(size_t bi) {
  ContactNodes& cn = nodes_[bi];
  const SupernodalSolve& halves = factored_[bi].factor->halves();
  for (size_t a = 0; a < cn.node.size(); ++a)
    cn.t.segment<3>(3 * Eigen::Index(a)) = cn.to_world[a] * halves.dot(*cn.columns[a]);
  if (cn.corrected) cn.force.noalias() = -cn.C * cn.t;
  else cn.force.setZero();
  cn.u = cn.t;
  cn.u.noalias() += cn.Yc * cn.force;
}

void FactoredMicaSolver::finish_correction(size_t bi, Vec3List& z) {
  ContactNodes& cn = nodes_[bi];
  cn.u = cn.t;
  cn.u.noalias() += cn.Yc * cn.force;
  for (size_t a = 0; a < cn.node.size(); ++a) z[cn.node[a]] = cn.u.segment<3>(3 * Eigen::Index(a));
}

void FactoredMicaSolver::precondition(size_t bi, const Vec3List& r, Vec3List& z) {
  if (!nodes_[bi].corrected) return warp_[bi].apply(r, z);
  warp_[bi].forward(r);
  start_correction(bi);
  add_forces(bi);
  warp_[bi].backward(z);
  finish_correction(bi, z);  // the contact nodes exact and projected; PcgSolver projects the rest
}

void FactoredMicaSolver::apply_impulse_change(std::vector<SolverBody>& bodies, const ContactRows& rows,
                                              const std::vector<double>& dlambda) {
  for (size_t bi = 0; bi < bodies.size(); ++bi)
    if (body_response(bi, rows, dlambda)) add_turned(bi, *bodies[bi].v);
}

void FactoredMicaSolver::solve_small_lcp(const ContactRows& rows, double tolerance, const std::vector<double>& lambda,
                                         const std::optional<std::chrono::steady_clock::time_point>& deadline) {
  const size_t nr = rows.size();
  lambda_next_ = lambda;
  // The rows something can move along; a tangent row only with its normal row.
  live_.clear();
  live_at_.assign(nr, -1);
  bool friction = false;
  for (size_t r = 0; r < nr; ++r)
    if (diag_[r] > 0 && (rows.normal_of[r] < 0 || live_at_[rows.normal_of[r]] >= 0)) {
      live_at_[r] = int32_t(live_.size());
      live_.push_back(int32_t(r));
      friction = friction || rows.normal_of[r] >= 0;
    }
  const Eigen::Index n = Eigen::Index(live_.size());
  small_M_.resize(n, n);
  small_q_.resize(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    small_q_(a) = w_[live_[a]];
    for (Eigen::Index b = 0; b < n; ++b) {
      small_M_(a, b) = W_(live_[a], live_[b]);
      small_q_(a) -= small_M_(a, b) * lambda[live_[b]];
    }
  }
  // Frictionless: Lemke's pivoting, exact (PGS on a few strongly coupled rows, contacts sharing
  // nodes, would crawl and stop far from the answer).
  // Its ray (no impulses satisfy the rows: a tool closed around a body) stays one for the rest
  // of the solve, whose rounds change the problem only by what they learn of W: they go straight
  // to the sweeps (a pivot costs n^2 too, and 30-50 of them on 507 rows took 15 ms a round).
  // Past 120 rows its pivots are bounded by their work, that of 50 n pivots on 120 rows (at least
  // n): on the same fuzzed box, 506 rows with the half-precision copy's W, it cycled through its
  // 50 n = 25300 pivots twice, 2.4 s a step (found_lemke_cycling_506_rows).
  if (!friction && !lemke_failed_) {
    constexpr double kPivotWork = 50.0 * 120 * 120 * 120;
    const double max_pivots = std::clamp(kPivotWork / (double(n) * double(n)), double(n), 50.0 * double(n));
    const LcpSolution sol = solve_lcp_lemke(small_M_, small_q_, int32_t(std::max(max_pivots, 1.0)));
    if (sol.solved) {
      for (Eigen::Index a = 0; a < n; ++a) lambda_next_[live_[a]] = sol.z(a);
      return;
    }
    lemke_failed_ = true;
  }
  // With friction (or if pivoting failed): block Gauss-Seidel over the contacts with the exact
  // local Coulomb solve, from lambda, to well below the tolerance.
  small_mu_.resize(n);
  small_normal_.resize(size_t(n));
  small_start_.resize(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    const int32_t r = live_[a];
    small_mu_(a) = rows.mu[r];
    small_normal_[size_t(a)] = rows.normal_of[r] < 0 ? -1 : live_at_[rows.normal_of[r]];
    small_start_(a) = lambda[r];
  }
  FrictionalSettings fs;
  fs.tolerance = std::max(1e-3 * tolerance, 1e-13);
  // A prediction, solved again from its result every round: not worth 10^4 sweeps or a dense
  // Newton step on hundreds of rows (a fuzzed box under a tool, 78 frictional contacts that
  // stall spent 32-92 ms per call in 234 x 234 factorizations, found_frictional_stall_78_contacts;
  // the tests' problems need far fewer sweeps, the largest, test_solve_allocations', 117 rows).
  // A sweep costs n^2 (each row's change updates every w), so past 120 rows the sweeps are
  // bounded by that work, 256 sweeps of 120 rows: a box tool teleported into two boxes made 507
  // contacts that no impulses satisfy (found_teleported_box_507_contacts), and 512 sweeps of them
  // per round took 350 ms a step.
  constexpr double kSweepWork = 256.0 * 120 * 120;
  fs.max_sweeps = int32_t(std::clamp(kSweepWork / (double(n) * double(n)), 16.0, 256.0));
  fs.max_newton_rows = 120;
  fs.deadline = deadline;
  FrictionalSolution& sol = small_solution_;
  solve_frictional_contact(small_M_, small_q_, small_mu_, small_normal_, small_start_, fs, small_workspace_, sol);
  for (Eigen::Index a = 0; a < n; ++a) lambda_next_[live_[a]] = sol.z(a);
}

double FactoredMicaSolver::complementarity_error(const ContactRows& rows, const std::vector<double>& lambda) {
  // Per contact the natural residual lambda - P(lambda - rho w) (the normal row onto lambda_n >= 0,
  // the tangent pair onto the disk of mu lambda_n), rho = 1 / the warped compliance's own diagonal
  // W0 (not the secant-updated one: the test does not trust what it learned), one rho for both
  // tangent rows (a step per row would bend the slip direction the test accepts).
  double e2 = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows.normal_of[r] < 0) {
      if (diag_[r] == 0) continue;
      const double next = std::max(0.0, lambda[r] - w_[r] / warped_diag_[r]);
      e2 += (next - lambda[r]) * (next - lambda[r]);
    } else if (rows.first_tangent(r)) {
      const double largest = std::max(diag_[r] > 0 ? warped_diag_[r] : 0.0, diag_[r + 1] > 0 ? warped_diag_[r + 1] : 0.0);
      if (largest == 0) continue;
      double t[2];
      for (int k = 0; k < 2; ++k) t[k] = diag_[r + k] > 0 ? lambda[r + k] - w_[r + k] / largest : lambda[r + k];
      project_onto_disk(rows.mu[r] * std::max(lambda[rows.normal_of[r]], 0.0), t[0], t[1]);
      for (int k = 0; k < 2; ++k) e2 += (t[k] - lambda[r + k]) * (t[k] - lambda[r + k]);
    }
  }
  return std::sqrt(e2);
}

void FactoredMicaSolver::refactor_now(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                      std::vector<double>& lambda) {
  for (size_t bi = 0; bi < bodies.size(); ++bi)
    if (factored_[bi].node_rotation)
      factored_[bi].factor->refactor_now(bodies[bi].pattern(), *bodies[bi].A, *bodies[bi].projection,
                                         factored_[bi].node_rotation, bodies[bi].extra_stiffness);
  for (size_t bi = 0; bi < bodies.size(); ++bi) warp_[bi].bind(factored_[bi].factor, factored_[bi].node_rotation);
  start_compliance(bodies, rows, lambda);
}

void FactoredMicaSolver::secant_update() {
  const Eigen::Index nr = Eigen::Index(w_.size());
  secant_y_ = Eigen::Map<const Eigen::VectorXd>(w_.data(), nr) - Eigen::Map<const Eigen::VectorXd>(w_prev_.data(), nr);
  secant_Ws_.noalias() = W_ * secant_s_;
  const double sWs = secant_s_.dot(secant_Ws_), sy = secant_s_.dot(secant_y_);
  if (sWs > 0 && sy > 1e-3 * sWs) {  // curvature confirmed (inexact solves blur small steps)
    // W += y y^T / sy - Ws Ws^T / sWs entry by entry (as a product expression it made two n x n
    // temporaries).
    for (Eigen::Index j = 0; j < nr; ++j)
      for (Eigen::Index i = 0; i < nr; ++i)
        W_(i, j) += secant_y_(i) * secant_y_(j) / sy - secant_Ws_(i) * secant_Ws_(j) / sWs;
    for (size_t q = 0; q < diag_.size(); ++q) diag_[q] = diag_[q] > 0 ? W_(Eigen::Index(q), Eigen::Index(q)) : 0.0;
  }
}

void FactoredMicaSolver::row_velocities(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  w_.assign(rows.size(), 0.0);
  double floor = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    double c = rows.bias[r], speed = 0;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const Vec3& v = (*bodies[rows.terms[t].body].v)[rows.terms[t].node];
      c += rows.terms[t].coef * rows.direction[r].dot(v);
      speed += std::abs(rows.terms[t].coef) * v.norm();
    }
    w_[r] = c;
    if (warped_diag_[r] > 0) floor = std::max(floor, speed / warped_diag_[r]);
  }
  impulse_floor2_ = floor * floor;
}

SolveReport FactoredMicaSolver::solve(const SolveContext& ctx, std::vector<SolverBody>& bodies,
                                      const ContactRows& rows, std::vector<double>& lambda) {
  using Clock = SolveContext::Clock;
  const SolverSettings& settings = settings_;
  const std::optional<Clock::time_point>& deadline = ctx.deadline;
  if (!settings.warm_start) zero_velocities(bodies);
  update_factors(bodies);
  const std::vector<FactoredBody>& factored = factored_;
  const size_t nb = bodies.size(), nr = rows.size();
  pcg_.resize(nb);
  warp_.resize(nb);
  rhs_.resize(nb);
  corrected_.clear();  // no allocation once it has held nb
  for (size_t bi = 0; bi < nb; ++bi) corrected_.emplace_back(this, bi);
  for (size_t bi = 0; bi < nb; ++bi) {
    warp_[bi].bind(factored[bi].factor, factored[bi].node_rotation);
    pcg_[bi].set_preconditioner(&corrected_[bi]);
  }
  lambda.resize(nr, 0.0);
  start_compliance(bodies, rows, lambda);
  lemke_failed_ = false;
  SolveReport report;
  if (settings.active_set && nr > 0) {
    report = solve_active_set(ctx, bodies, rows, lambda);
    if (report.converged || report.out_of_time) return report;
    // Not settled in its rounds: the alternating loop below goes on from its impulses and
    // velocities, with what is left of the iteration cap.
  }
  bool may_refactor = false;  // only co-rotational bodies: a linear body's factor is its A
  for (const FactoredBody& f : factored)
    may_refactor = may_refactor || (f.node_rotation && settings.refactor_after > report.iterations);

  report.converged = false;
  report.momentum_residual = std::numeric_limits<double>::quiet_NaN();
  double l_scale = 0;
  int32_t outer = 0;
  double previous_inner_tolerance = 1;
  double tighten = 1;  // without contact rows: how much tighter than the tolerance the solves must aim
  bool velocities_solved = false;
  // Rounds whose impulses have stopped converging end the solve, not converged: the best relative
  // impulse change must halve every kStallRounds rounds. At a slower rate no solve reaches a
  // tolerance within a cap of a few hundred rounds; a contact problem with no solution (a tool
  // closed around a body) grows its impulses by the same step every round, a change of 1/k, and
  // took the whole default cap (test_hostile.c: test_tool_closed_around_a_body).
  constexpr int32_t kStallRounds = 16;
  StallWatch progress(kStallRounds);
  while (report.iterations < settings.max_iterations) {
    if (deadline && outer > 0 && Clock::now() >= *deadline) {
      report.out_of_time = true;
      break;
    }
    // A solve that has used as many iterations as a factorization costs (crushed elements turning
    // fast under a tool) gives up on the factor: the current system is factored now, and the loop
    // then ends in a few rounds. Once per solve; the secant history belongs to the old factor.
    if (may_refactor && report.iterations >= settings.refactor_after) {
      refactor_now(bodies, rows, lambda);
      previous_inner_tolerance = 1;
      may_refactor = false;
    }
    ++outer;
    ++report.solves;
    // Velocities for the current impulses: A v = b + G^T lambda on the free directions. While the
    // impulses still move, a hundredth of their last change is accuracy enough (inexact Newton);
    // near the end the solves aim a little below the tolerance, so the outer test is not starved.
    const double final_tolerance = 0.3 * settings.tolerance * tighten;
    const double inner_tolerance =
        outer == 1 || nr == 0 || report.impulse_change < 30 * settings.tolerance
            ? final_tolerance
            : std::clamp(0.01 * report.impulse_change, final_tolerance, std::max(final_tolerance, 1e-2));
    // While a refactor is still possible, no single solve may run past the point where it pays.
    const int32_t inner_cap = may_refactor ? std::max(1, settings.refactor_after - report.iterations)
                                           : settings.max_iterations;
    for (size_t bi = 0; bi < nb; ++bi) pcg_[bi].configure(inner_tolerance, inner_cap, deadline);
    velocities_solved = true;
    report.velocity_change = 0;  // the residual of this round's solves
    scatter_contact_impulses(rows, lambda, bodies);
    for (size_t bi = 0; bi < nb; ++bi) {
      SolverBody& body = bodies[bi];
      rhs_[bi] = *body.b;
      for (size_t i = 0; i < rhs_[bi].size(); ++i) rhs_[bi][i] += (*body.contact_impulse)[i];
      const SolveReport s = pcg_[bi].solve(body.projected(), rhs_[bi], *body.v);
      report.iterations += std::max(1, s.iterations);
      report.velocity_change = std::max(report.velocity_change, s.residual);
      velocities_solved = velocities_solved && s.converged && inner_tolerance == final_tolerance;
      report.out_of_time = report.out_of_time || s.out_of_time;
    }
    if (report.out_of_time) break;
    if (nr == 0) {
      if (!velocities_solved && may_refactor) continue;  // stopped where refactoring pays: refactor, go on
      // A solve's tolerance is relative to its right-hand side S (b - A z), which a prescribed
      // motion z of a stiff body can make far larger than the terms the momentum balances (A v,
      // b): the momentum decides, and a solve short of it goes on with a tighter aim.
      report.momentum_residual = momentum_residual(bodies);
      report.converged = velocities_solved && report.momentum_residual <= settings.tolerance;
      if (velocities_solved && !report.converged && report.momentum_residual > 0 && tighten > 1e-12) {
        tighten *= std::max(1e-6, 0.3 * settings.tolerance / report.momentum_residual);
        continue;
      }
      break;
    }
    // Anticipate the row velocities and solve the small complementarity problem on W.
    row_velocities(bodies, rows);
    // Two solved velocity fields a step s of the impulses apart measure the true compliance along
    // it, y = W_true s = w - w_prev. A BFGS update takes that into W and keeps it symmetric
    // positive definite (while s.y > 0, as for the true W), so the rotations the warped factor
    // misses stop slowing the loop.
    if (outer > 1 && std::max(inner_tolerance, previous_inner_tolerance) <= final_tolerance) {  // only solved pairs measure it
      secant_s_ = Eigen::Map<const Eigen::VectorXd>(dlambda_.data(), Eigen::Index(nr));
      secant_update();
    }
    w_prev_ = w_;
    previous_inner_tolerance = inner_tolerance;
    solve_small_lcp(rows, settings.tolerance, lambda, deadline);
    dlambda_.resize(nr);
    double dl2 = 0, l2 = 0;
    for (size_t r = 0; r < nr; ++r) {
      dlambda_[r] = lambda_next_[r] - lambda[r];
      dl2 += dlambda_[r] * dlambda_[r];
      l2 += lambda_next_[r] * lambda_next_[r];
    }
    if (outer == 1) l_scale = l2;  // the first correction sets the scale when lambda starts at zero
    const double scale2 = std::max({l2, l_scale, impulse_floor2_});
    report.impulse_change = dl2 > 0 ? std::sqrt(dl2 / scale2) : 0.0;
    if (report.impulse_change <= settings.tolerance && velocities_solved &&
        complementarity_error(rows, lambda) <= settings.tolerance * std::sqrt(scale2)) {
      // v balances the current impulses and the impulses no longer move: done.
      report.momentum_residual = momentum_residual(bodies);
      report.residual = std::max({report.velocity_change, report.impulse_change, report.momentum_residual});
      report.converged = report.momentum_residual <= settings.tolerance;
      if (report.converged) return report;
    }
    progress.add(report.impulse_change);
    if (!progress.progressing(outer)) break;  // stalled
    apply_impulse_change(bodies, rows, dlambda_);
    lambda = lambda_next_;
  }
  // Stopped early (cap or budget): report G^T lambda of the impulses returned, and how far the
  // velocities are from balancing them.
  scatter_contact_impulses(rows, lambda, bodies);
  report.momentum_residual = momentum_residual(bodies);
  report.residual = std::max({report.velocity_change, report.impulse_change, report.momentum_residual});
  return report;
}

void FactoredMicaSolver::save_body(uint64_t key, ByteWriter& out) const {
  const FactoredBodyCache* cache = find_cache(key);
  out.put(uint8_t(cache != nullptr));
  if (cache) cache->factor.save(out);
}

void FactoredMicaSolver::restore_bodies(const std::vector<SavedBody>& bodies) {
  std::vector<std::pair<uint64_t, std::unique_ptr<FactoredBodyCache>>> made;
  for (const SavedBody& b : bodies) {
    ByteReader in(b.data, b.size);
    std::unique_ptr<FactoredBodyCache> cache;
    if (in.get<uint8_t>("a body's factor flag")) {
      cache = std::make_unique<FactoredBodyCache>();
      cache->factor.load(in, b.fem->pattern);
    }
    if (in.remaining()) fail(Errc::Parse, "a body's solver state is longer than its factor: corrupt state");
    made.emplace_back(b.key, std::move(cache));
  }
  replace_caches(made);
}

}  // namespace mica
