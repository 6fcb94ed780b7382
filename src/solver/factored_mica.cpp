// SPDX-License-Identifier: Apache-2.0
#include "solver/factored_mica.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "solver/friction_cone.hpp"
#include "solver/frictional_contact.hpp"

namespace mica {

void FactoredMicaSolver::prepare(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                 std::vector<double>& lambda) {
  update_factors(bodies);
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    FactoredBody& f = factored_[bi];
    f.warp.bind(f.factor, f.node_rotation);
    f.pcg.set_preconditioner(&f);
  }
  lambda.resize(rows.size(), 0.0);
  start_compliance(bodies, rows, lambda);
  small_.lemke_failed = small_.lemke_ray = false;
}

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
    cache.factor.set_bridgeable(b.may_be_cut);
    cache.factor.update(*b.fem, LaggedFactor::Key{b.system, b.constraint_version}, *b.A, *b.projection, rotation, b.rotation,
                        rotation ? settings_.refactor_interval : 0, b.extra_stiffness);
    FactoredBody& f = factored_[k];
    f.factor = &cache.factor;
    f.cache = &cache;
    f.node_rotation = rotation;
    f.projection = b.projection;
  }
}

void FactoredMicaSolver::prepare_contact_nodes(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  Compliance& co = compliance_;
  const size_t nt = rows.terms.size();
  co.term_slot.resize(nt);
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    const SolverBody& body = bodies[bi];
    FactoredBody& f = factored_[bi];
    ContactNodes& cn = f.nodes;
    if (co.slot_of.size() < size_t(body.node_count())) co.slot_of.resize(size_t(body.node_count()), -1);
    if (co.last_slot.size() < size_t(body.node_count())) co.last_slot.resize(size_t(body.node_count()), -1);
    cn.node.clear();
    const auto slot = [&](int32_t i) {
      if (co.slot_of[i] < 0) {
        co.slot_of[i] = int32_t(cn.node.size());
        cn.node.push_back(i);
      }
      return co.slot_of[i];
    };
    for (size_t t = 0; t < nt; ++t)
      if (rows.terms[t].body == int32_t(bi)) co.term_slot[t] = slot(rows.terms[t].node);
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
      cn.to_world[size_t(a)] = body.projection->projector(i) * f.factor->turn(f.node_rotation, i);
    }
    // Y from the products H_a^T H_b, those of nodes the last solve had (with these columns) kept.
    FactoredBodyCache::Products &last = f.cache->products, &next = f.cache->products_next;
    const bool columns_kept = last.columns == f.factor->columns_id();
    if (columns_kept)
      for (size_t a = 0; a < last.node.size(); ++a) co.last_slot[last.node[a]] = int32_t(a);
    next.blocks.resize(3 * m, 3 * m);
    cn.Y.resize(3 * m, 3 * m);
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index b = a; b < m; ++b) {
        const int32_t la = co.last_slot[cn.node[size_t(a)]], lb = co.last_slot[cn.node[size_t(b)]];
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
      for (int32_t i : last.node) co.last_slot[i] = -1;
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
            cn.C.block<3, 3>(3 * co.slot_of[e.nodes[r]], 3 * co.slot_of[e.nodes[c]]) +=
                body.projection->projector(e.nodes[r]) * e.K.block<3, 3>(3 * r, 3 * c) *
                body.projection->projector(e.nodes[c]);
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
    for (int32_t i : cn.node) co.slot_of[i] = -1;
  }
}

void FactoredMicaSolver::build_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  prepare_contact_nodes(bodies, rows);
  Compliance& co = compliance_;
  const size_t nr = rows.size(), nt = rows.terms.size();
  std::vector<int32_t>& row_of = co.term_row;
  row_of.resize(nt);
  for (size_t r = 0; r < nr; ++r)
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) row_of[t] = int32_t(r);
  // W = D^T Yc D per body, D's column r the row's direction at its terms' slots (coef_t d_r):
  // first Z = Yc D, the slots' response to each row's unit impulse, then W_rs = sum over the
  // terms t of row r of coef_t d_r^T Z_{slot t, s}. Term by term, not over pairs of terms: a
  // box tool teleported into two boxes made 507 rows of 1500 terms, whose 2.3 M pairs took
  // 50 ms a solve.
  for (FactoredBody& f : factored_) f.nodes.Z.setZero(f.nodes.Yc.rows(), Eigen::Index(nr));
  for (size_t u = 0; u < nt; ++u) {
    const RowTerm& b = rows.terms[u];
    ContactNodes& cn = factored_[b.body].nodes;
    const Vec3 d = b.coef * rows.direction[row_of[u]];
    cn.Z.col(row_of[u]).noalias() += cn.Yc.middleCols<3>(3 * co.term_slot[u]) * d;
  }
  co.W.setZero(Eigen::Index(nr), Eigen::Index(nr));
  for (size_t t = 0; t < nt; ++t) {
    const RowTerm& a = rows.terms[t];
    const Vec3 d = a.coef * rows.direction[row_of[t]];
    co.W.row(row_of[t]).noalias() += d.transpose() * factored_[a.body].nodes.Z.middleRows<3>(3 * co.term_slot[t]);
  }
}

void FactoredMicaSolver::start_compliance(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                          std::vector<double>& lambda) {
  Compliance& co = compliance_;
  const size_t nr = rows.size();
  build_compliance(bodies, rows);
  co.diag.assign(nr, 0.0);
  co.warped_diag.assign(nr, 0.0);
  const double w_max = nr ? co.W.diagonal().cwiseAbs().maxCoeff() : 0.0;
  for (size_t r = 0; r < nr; ++r) {
    if (co.W(r, r) > 1e-12 * w_max) co.diag[r] = co.warped_diag[r] = co.W(r, r);
    else lambda[r] = 0;  // nothing can move along this row
  }
  rows.project(lambda);  // the warm start onto the cones
}

bool FactoredMicaSolver::body_response(size_t bi, const ContactRows& rows, const std::vector<double>& w) {
  FactoredBody& f = factored_[bi];
  ContactNodes& cn = f.nodes;
  cn.force.setZero();
  bool any = false;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (w[r] == 0) continue;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      if (rows.terms[t].body != int32_t(bi)) continue;
      cn.force.segment<3>(3 * compliance_.term_slot[t]) += (rows.terms[t].coef * w[r]) * rows.direction[r];
      any = true;
    }
  }
  return any && f.respond();
}

bool FactoredMicaSolver::FactoredBody::add_forces() {
  ContactNodes& cn = nodes;
  const Eigen::VectorXd* f = &cn.force;
  if (cn.corrected) {
    cn.moved.noalias() = cn.M * cn.force;  // P_c^-1 U = X M
    f = &cn.moved;
  }
  const SupernodalSolve& halves = factor->halves();
  bool any = false;
  for (size_t a = 0; a < cn.node.size(); ++a) {
    const Vec3 g = cn.to_world[a].transpose() * f->segment<3>(3 * Eigen::Index(a));
    if (g.isZero(0)) continue;
    halves.add(*cn.columns[a], g);
    any = true;
  }
  return any;
}

bool FactoredMicaSolver::FactoredBody::respond() {
  const SupernodalSolve& halves = factor->halves();
  halves.clear(true);
  if (!add_forces()) return false;
  response.resize(3 * Eigen::Index(factor->node_count()));
  halves.backward(response.data());
  nodes.exact.noalias() = nodes.Yc * nodes.force;  // U^T P_c^-1 U f
  return true;
}

void FactoredMicaSolver::FactoredBody::add_turned(Vec3List& out) const {
  for (size_t i = 0; i < out.size(); ++i) {
    const Vec3 d = factor->turn(node_rotation, int32_t(i)) * response.segment<3>(3 * Eigen::Index(i));
    out[i] += projection->free_part(int32_t(i), d);
  }
  // The contact nodes' exact values in place of the response's.
  for (size_t a = 0; a < nodes.node.size(); ++a) {
    const int32_t i = nodes.node[a];
    out[i] += nodes.exact.segment<3>(3 * Eigen::Index(a)) -
              nodes.to_world[a] * response.segment<3>(3 * Eigen::Index(i));
  }
}

void FactoredMicaSolver::FactoredBody::start_correction() {
  ContactNodes& cn = nodes;
  const SupernodalSolve& halves = factor->halves();
  for (size_t a = 0; a < cn.node.size(); ++a)
    cn.t.segment<3>(3 * Eigen::Index(a)) = cn.to_world[a] * halves.dot(*cn.columns[a]);
  if (cn.corrected) cn.force.noalias() = -cn.C * cn.t;
  else cn.force.setZero();
  cn.u = cn.t;
  cn.u.noalias() += cn.Yc * cn.force;
}

void FactoredMicaSolver::FactoredBody::finish_correction(Vec3List& z) {
  ContactNodes& cn = nodes;
  cn.u = cn.t;
  cn.u.noalias() += cn.Yc * cn.force;
  for (size_t a = 0; a < cn.node.size(); ++a) z[cn.node[a]] = cn.u.segment<3>(3 * Eigen::Index(a));
}

void FactoredMicaSolver::FactoredBody::apply(const Vec3List& r, Vec3List& z) {
  if (!nodes.corrected) return warp.apply(r, z);
  warp.forward(r);
  start_correction();
  add_forces();
  warp.backward(z);
  finish_correction(z);  // the contact nodes exact and projected; PcgSolver projects the rest
}

void FactoredMicaSolver::apply_impulse_change(std::vector<SolverBody>& bodies, const ContactRows& rows,
                                              const std::vector<double>& dlambda) {
  for (size_t bi = 0; bi < bodies.size(); ++bi)
    if (body_response(bi, rows, dlambda)) factored_[bi].add_turned(*bodies[bi].v);
}

void FactoredMicaSolver::solve_small_lcp(const ContactRows& rows, double tolerance, const std::vector<double>& lambda,
                                         const std::optional<std::chrono::steady_clock::time_point>& deadline) {
  SmallProblem& sp = small_;
  const Compliance& co = compliance_;
  const size_t nr = rows.size();
  sp.lambda_next = lambda;
  // The rows something can move along; a tangent row only with its normal row.
  sp.live.clear();
  sp.live_at.assign(nr, -1);
  bool friction = false;
  for (size_t r = 0; r < nr; ++r)
    if (co.diag[r] > 0 && (rows.normal_of[r] < 0 || sp.live_at[rows.normal_of[r]] >= 0)) {
      sp.live_at[r] = int32_t(sp.live.size());
      sp.live.push_back(int32_t(r));
      friction = friction || rows.normal_of[r] >= 0;
    }
  const Eigen::Index n = Eigen::Index(sp.live.size());
  sp.M.resize(n, n);
  sp.q.resize(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    sp.q(a) = rounds_.w[sp.live[a]];
    for (Eigen::Index b = 0; b < n; ++b) {
      sp.M(a, b) = co.W(sp.live[a], sp.live[b]);
      sp.q(a) -= sp.M(a, b) * lambda[sp.live[b]];
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
  if (!friction && !sp.lemke_failed) {
    constexpr double kPivotWork = 50.0 * 120 * 120 * 120;
    const double max_pivots = std::clamp(kPivotWork / (double(n) * double(n)), double(n), 50.0 * double(n));
    const LcpSolution sol = solve_lcp_lemke(sp.M, sp.q, int32_t(std::max(max_pivots, 1.0)));
    if (sol.solved) {
      for (Eigen::Index a = 0; a < n; ++a) sp.lambda_next[sp.live[a]] = sol.z(a);
      return;
    }
    sp.lemke_failed = true;
    sp.lemke_ray = sol.ray;
  }
  // With friction (or if pivoting failed): block Gauss-Seidel over the contacts with the exact
  // local Coulomb solve, from lambda, to well below the tolerance.
  sp.mu.resize(n);
  sp.normal.resize(size_t(n));
  sp.start.resize(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    const int32_t r = sp.live[a];
    sp.mu(a) = rows.mu[r];
    sp.normal[size_t(a)] = rows.normal_of[r] < 0 ? -1 : sp.live_at[rows.normal_of[r]];
    sp.start(a) = lambda[r];
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
  // Frictionless rows on which Lemke ended on a ray have no solution (W is positive semidefinite,
  // hence copositive-plus), so no Newton step can converge to one: after a ray the sweeps alone
  // give the rounds their prediction. A box tool teleported into a 27-node box, 110 rows, took
  // 1933 Newton steps (110 x 110 factorizations) in the 113 rounds of one step: 0.84 s, 0.47 s
  // without them; 386 -> 14 ms at 20 iterations (found_box_enclosed_110_rows).
  fs.max_newton_rows = sp.lemke_ray ? 0 : 120;
  fs.deadline = deadline;
  FrictionalSolution& sol = sp.solution;
  solve_frictional_contact(sp.M, sp.q, sp.mu, sp.normal, sp.start, fs, sp.workspace, sol);
  for (Eigen::Index a = 0; a < n; ++a) sp.lambda_next[sp.live[a]] = sol.z(a);
}

double FactoredMicaSolver::complementarity_error(const ContactRows& rows, const std::vector<double>& lambda) {
  // Per contact the natural residual lambda - P(lambda - rho w) (the normal row onto lambda_n >= 0,
  // the tangent pair onto the disk of mu lambda_n), rho = 1 / the warped compliance's own diagonal
  // W0 (not the secant-updated one: the test does not trust what it learned), one rho for both
  // tangent rows (a step per row would bend the slip direction the test accepts).
  const std::vector<double>& diag = compliance_.diag;
  const std::vector<double>& warped_diag = compliance_.warped_diag;
  const std::vector<double>& w = rounds_.w;
  double e2 = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows.normal_of[r] < 0) {
      if (diag[r] == 0) continue;
      const double next = std::max(0.0, lambda[r] - w[r] / warped_diag[r]);
      e2 += (next - lambda[r]) * (next - lambda[r]);
    } else if (rows.first_tangent(r)) {
      const double largest = std::max(diag[r] > 0 ? warped_diag[r] : 0.0, diag[r + 1] > 0 ? warped_diag[r + 1] : 0.0);
      if (largest == 0) continue;
      double t[2];
      for (int k = 0; k < 2; ++k) t[k] = diag[r + k] > 0 ? lambda[r + k] - w[r + k] / largest : lambda[r + k];
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
                                         factored_[bi].node_rotation, bodies[bi].rotation, bodies[bi].extra_stiffness);
  for (FactoredBody& f : factored_) f.warp.bind(f.factor, f.node_rotation);
  start_compliance(bodies, rows, lambda);
}

void FactoredMicaSolver::Compliance::secant_update(const std::vector<double>& w, const std::vector<double>& w_prev) {
  const Eigen::Index nr = Eigen::Index(w.size());
  y = Eigen::Map<const Eigen::VectorXd>(w.data(), nr) - Eigen::Map<const Eigen::VectorXd>(w_prev.data(), nr);
  Ws.noalias() = W * s;
  const double sWs = s.dot(Ws), sy = s.dot(y);
  if (sWs > 0 && sy > 1e-3 * sWs) {  // curvature confirmed (inexact solves blur small steps)
    // W += y y^T / sy - Ws Ws^T / sWs entry by entry (as a product expression it made two n x n
    // temporaries).
    for (Eigen::Index j = 0; j < nr; ++j)
      for (Eigen::Index i = 0; i < nr; ++i) W(i, j) += y(i) * y(j) / sy - Ws(i) * Ws(j) / sWs;
    for (size_t q = 0; q < diag.size(); ++q) diag[q] = diag[q] > 0 ? W(Eigen::Index(q), Eigen::Index(q)) : 0.0;
  }
}

void FactoredMicaSolver::row_velocities(const std::vector<SolverBody>& bodies, const ContactRows& rows) {
  std::vector<double>& w = rounds_.w;
  w.assign(rows.size(), 0.0);
  double floor = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    double c = rows.bias[r], speed = 0;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const Vec3& v = (*bodies[rows.terms[t].body].v)[rows.terms[t].node];
      c += rows.terms[t].coef * rows.direction[r].dot(v);
      speed += std::abs(rows.terms[t].coef) * v.norm();
    }
    w[r] = c;
    if (compliance_.warped_diag[r] > 0) floor = std::max(floor, speed / compliance_.warped_diag[r]);
  }
  rounds_.impulse_floor2 = floor * floor;
}

void FactoredMicaSolver::balance(std::vector<SolverBody>& bodies, const ContactRows& rows,
                                 const std::vector<double>& lambda, SolveReport& report) {
  scatter_contact_impulses(rows, lambda, bodies);
  report.momentum_residual = momentum_residual(bodies);
  report.residual = std::max({report.velocity_change, report.impulse_change, report.momentum_residual});
}

SolveReport FactoredMicaSolver::solve(const SolveContext& ctx, std::vector<SolverBody>& bodies,
                                      const ContactRows& rows, std::vector<double>& lambda) {
  if (!settings_.warm_start) zero_velocities(bodies);
  prepare(bodies, rows, lambda);
  SolveReport report;
  if (settings_.active_set && rows.size() > 0) {
    report = solve_active_set(ctx, bodies, rows, lambda);
    if (report.converged || report.out_of_time) return report;
    // Not settled in its rounds: the alternating loop goes on from its impulses and velocities,
    // with what is left of the iteration cap.
  }
  return alternate(ctx, bodies, rows, lambda, report);
}

SolveReport FactoredMicaSolver::alternate(const SolveContext& ctx, std::vector<SolverBody>& bodies,
                                          const ContactRows& rows, std::vector<double>& lambda, SolveReport report) {
  const SolverSettings& settings = settings_;
  // Rounds whose impulses have stopped converging end the solve, not converged: the best relative
  // impulse change must halve every kStallRounds rounds. At a slower rate no solve reaches a
  // tolerance within a cap of a few hundred rounds; a contact problem with no solution (a tool
  // closed around a body) grows its impulses by the same step every round, a change of 1/k, and
  // took the whole default cap (test_hostile.c: test_tool_closed_around_a_body).
  constexpr int32_t kStallRounds = 16;
  Alternation a(kStallRounds);
  for (const FactoredBody& f : factored_)
    a.may_refactor = a.may_refactor || (f.node_rotation && settings.refactor_after > report.iterations);
  report.converged = false;
  report.momentum_residual = std::numeric_limits<double>::quiet_NaN();
  while (report.iterations < settings.max_iterations) {
    if (ctx.deadline && a.round > 0 && SolveContext::Clock::now() >= *ctx.deadline) {
      report.out_of_time = true;
      break;
    }
    // A solve that has used as many iterations as a factorization costs (crushed elements turning
    // fast under a tool) gives up on the factor: the current system is factored now, and the loop
    // then ends in a few rounds. Once per solve; the secant history belongs to the old factor.
    if (a.may_refactor && report.iterations >= settings.refactor_after) {
      refactor_now(bodies, rows, lambda);
      a.previous_inner_tolerance = 1;
      a.may_refactor = false;
    }
    ++a.round;
    ++report.solves;
    solve_velocities(ctx.deadline, bodies, rows, lambda, a, report);
    if (report.out_of_time) break;
    if (rows.size() == 0) {
      if (solve_again(bodies, a, report)) continue;
      break;
    }
    predict_impulses(bodies, rows, lambda, ctx.deadline, a);
    if (settled(bodies, rows, lambda, a, report)) return report;
    a.progress.add(report.impulse_change);
    if (!a.progress.progressing(a.round)) break;  // stalled
    apply_impulse_change(bodies, rows, rounds_.dlambda);
    lambda = small_.lambda_next;
  }
  // Stopped early (cap or budget): report G^T lambda of the impulses returned, and how far the
  // velocities are from balancing them.
  balance(bodies, rows, lambda, report);
  return report;
}

void FactoredMicaSolver::solve_velocities(const std::optional<SolveContext::Clock::time_point>& deadline,
                                          std::vector<SolverBody>& bodies, const ContactRows& rows,
                                          const std::vector<double>& lambda, Alternation& a, SolveReport& report) {
  const SolverSettings& settings = settings_;
  // Velocities for the current impulses: A v = b + G^T lambda on the free directions. While the
  // impulses still move, a hundredth of their last change is accuracy enough (inexact Newton);
  // near the end the solves aim a little below the tolerance, so the outer test is not starved.
  a.final_tolerance = 0.3 * settings.tolerance * a.tighten;
  a.inner_tolerance =
      a.round == 1 || rows.size() == 0 || report.impulse_change < 30 * settings.tolerance
          ? a.final_tolerance
          : std::clamp(0.01 * report.impulse_change, a.final_tolerance, std::max(a.final_tolerance, 1e-2));
  // While a refactor is still possible, no single solve may run past the point where it pays.
  const int32_t inner_cap = a.may_refactor ? std::max(1, settings.refactor_after - report.iterations)
                                           : settings.max_iterations;
  for (FactoredBody& f : factored_) f.pcg.configure(a.inner_tolerance, inner_cap, deadline);
  a.velocities_solved = true;
  report.velocity_change = 0;  // the residual of this round's solves
  scatter_contact_impulses(rows, lambda, bodies);
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    SolverBody& body = bodies[bi];
    Vec3List& rhs = factored_[bi].rhs;
    rhs = *body.b;
    for (size_t i = 0; i < rhs.size(); ++i) rhs[i] += (*body.contact_impulse)[i];
    const SolveReport s = factored_[bi].pcg.solve(body.projected(), rhs, *body.v);
    report.iterations += std::max(1, s.iterations);
    report.velocity_change = std::max(report.velocity_change, s.residual);
    a.velocities_solved = a.velocities_solved && s.converged && a.inner_tolerance == a.final_tolerance;
    report.out_of_time = report.out_of_time || s.out_of_time;
  }
}

bool FactoredMicaSolver::solve_again(const std::vector<SolverBody>& bodies, Alternation& a, SolveReport& report) {
  const double tolerance = settings_.tolerance;
  if (!a.velocities_solved && a.may_refactor) return true;  // stopped where refactoring pays: refactor, go on
  // A solve's tolerance is relative to its right-hand side S (b - A z), which a prescribed
  // motion z of a stiff body can make far larger than the terms the momentum balances (A v,
  // b): the momentum decides, and a solve short of it goes on with a tighter aim.
  report.momentum_residual = momentum_residual(bodies);
  report.converged = a.velocities_solved && report.momentum_residual <= tolerance;
  if (a.velocities_solved && !report.converged && report.momentum_residual > 0 && a.tighten > 1e-12) {
    a.tighten *= std::max(1e-6, 0.3 * tolerance / report.momentum_residual);
    return true;
  }
  return false;
}

void FactoredMicaSolver::predict_impulses(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                          const std::vector<double>& lambda,
                                          const std::optional<SolveContext::Clock::time_point>& deadline,
                                          Alternation& a) {
  const size_t nr = rows.size();
  row_velocities(bodies, rows);
  // Two solved velocity fields a step s of the impulses apart measure the true compliance along
  // it, y = W_true s = w - w_prev. A BFGS update takes that into W and keeps it symmetric
  // positive definite (while s.y > 0, as for the true W), so the rotations the warped factor
  // misses stop slowing the loop. Only solved pairs measure it.
  if (a.round > 1 && std::max(a.inner_tolerance, a.previous_inner_tolerance) <= a.final_tolerance) {
    compliance_.s = Eigen::Map<const Eigen::VectorXd>(rounds_.dlambda.data(), Eigen::Index(nr));
    compliance_.secant_update(rounds_.w, rounds_.w_prev);
  }
  rounds_.w_prev = rounds_.w;
  a.previous_inner_tolerance = a.inner_tolerance;
  solve_small_lcp(rows, settings_.tolerance, lambda, deadline);
}

bool FactoredMicaSolver::settled(const std::vector<SolverBody>& bodies, const ContactRows& rows,
                                 const std::vector<double>& lambda, Alternation& a, SolveReport& report) {
  const double tolerance = settings_.tolerance;
  const std::vector<double>& next = small_.lambda_next;
  std::vector<double>& dlambda = rounds_.dlambda;
  dlambda.resize(rows.size());
  double dl2 = 0, l2 = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    dlambda[r] = next[r] - lambda[r];
    dl2 += dlambda[r] * dlambda[r];
    l2 += next[r] * next[r];
  }
  if (a.round == 1) a.l_scale = l2;  // the first correction sets the scale when lambda starts at zero
  const double scale2 = std::max({l2, a.l_scale, rounds_.impulse_floor2});
  report.impulse_change = dl2 > 0 ? std::sqrt(dl2 / scale2) : 0.0;
  if (report.impulse_change <= tolerance && a.velocities_solved &&
      complementarity_error(rows, lambda) <= tolerance * std::sqrt(scale2)) {
    // v balances the current impulses and the impulses no longer move: done.
    report.momentum_residual = momentum_residual(bodies);
    report.residual = std::max({report.velocity_change, report.impulse_change, report.momentum_residual});
    report.converged = report.momentum_residual <= tolerance;
  }
  return report.converged;
}

void FactoredMicaSolver::remap(uint64_t key, const BodyRemap& change) {
  FactoredBodyCache* cache = find_cache(key);
  bool kept = false;
  try {
    kept = cache && cache->factor.remap(change);
  } catch (...) {  // out of memory: nothing changed, and a dropped cache is made again
  }
  if (!kept) forget(key);
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
      cache->factor.load(in, *b.fem);
    }
    if (in.remaining()) fail(Errc::Parse, "a body's solver state is longer than its factor: corrupt state");
    made.emplace_back(b.key, std::move(cache));
  }
  replace_caches(made);
}

}  // namespace mica
