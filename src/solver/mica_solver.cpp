// SPDX-License-Identifier: Apache-2.0
#include "solver/mica_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "solver/friction_cone.hpp"

namespace mica {

namespace {

// v_i = z_i + Dt_i^-1 (q_i - sum_{j != i} A_ij v_j - D_ii z_i): the constraint-filtered block
// Gauss-Seidel update of node i (with v read but not written, the Jacobi anticipation).
Vec3 node_update(const SolverBody& body, const Mat3& inv_diag, int32_t i, const Vec3& q_i) {
  const BlockPattern& p = body.pattern();
  const BlockValues& A = *body.A;
  const Vec3List& v = *body.v;
  Vec3 r = q_i;
  for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k)
    if (p.col[k] != i) r -= A[k] * v[p.col[k]];
  if (body.projection->active() && body.projection->is_constrained[i]) {
    const Vec3& z = body.projection->z[i];
    return z + inv_diag * (r - A[p.diag[i]] * z);
  }
  return inv_diag * r;
}

}  // namespace

double MicaSolver::anticipated_velocity(const std::vector<SolverBody>& bodies, const ContactRows& rows, size_t r) const {
  double c = rows.bias[r];
  for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
    const RowTerm& term = rows.terms[t];
    const SolverBody& body = bodies[term.body];
    const Vec3 vt = node_update(body, inv_diag_[term.body][term.node], term.node, (*body.b)[term.node]);
    c += term.coef * rows.direction[r].dot(vt);
  }
  return c;
}

// The PGS update of a contact's tangent pair, rows r and r + 1 (ContactRows' layout): one
// projected gradient step on the pair's quadratic, lambda_t <- P_disk(lambda_t - alpha w_t),
// with one step length for both rows. Its fixed point is the Coulomb law (w_t opposes lambda_t
// when on the rim); a step per row (1 / B_rr each) would bend the slip direction wherever
// B_t1t1 != B_t2t2. alpha = 1 / (max B_tt + |B_t1t2|) is at most 1 / the pair's largest eigenvalue
// (Gershgorin): each step lowers the pair's energy, as a row's PGS update does.
void MicaSolver::update_tangents(const ContactRows& rows, size_t r, std::vector<double>& lambda) {
  double before[2], w[2];
  for (int k = 0; k < 2; ++k) {
    const size_t row = r + size_t(k);
    before[k] = lambda[row];
    w[k] = c_[row];
    for (int32_t t = rows.start[row]; t < rows.start[row + 1]; ++t)
      w[k] += rows.terms[t].coef * rows.direction[row].dot(u_[rows.terms[t].body][rows.terms[t].node]);
    if (diag_[row] > 0) lambda[row] -= pair_step_[r] * w[k];
  }
  project_onto_disk(rows.mu[r] * lambda[rows.normal_of[r]], lambda[r], lambda[r + 1]);
  for (int k = 0; k < 2; ++k) {
    const size_t row = r + size_t(k);
    for (int32_t t = rows.start[row]; t < rows.start[row + 1]; ++t)
      u_[rows.terms[t].body][rows.terms[t].node] += g_[t] * (lambda[row] - before[k]);
  }
}

SolveReport MicaSolver::solve(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                              std::vector<double>& lambda) {
  const SolverSettings& settings = settings_;
  const size_t nb = bodies.size(), nr = rows.size();
  // The warm start: the last step's velocities (MICA's iterate carries its information in v: one
  // PGS sweep makes an isolated row's impulse a function of v alone), or zero.
  if (!settings.warm_start) zero_velocities(bodies);
  inv_diag_.resize(nb);
  u_.resize(nb);
  // Filtered diagonal inverses; the warm start made to satisfy (I - S) v = z.
  for (size_t bi = 0; bi < nb; ++bi) {
    SolverBody& body = bodies[bi];
    const ProjectedSystem sys = body.projected();
    const int32_t n = body.node_count();
    inv_diag_[bi].resize(size_t(n));
    u_[bi].assign(size_t(n), Vec3::Zero());
    body.contact_impulse->assign(size_t(n), Vec3::Zero());
    for (int32_t i = 0; i < n; ++i) inv_diag_[bi][i] = sys.diagonal_block(i).inverse();
    for (int32_t i : body.projection->nodes) {
      const Mat3& S = body.projection->S[i];
      inv_diag_[bi][i] = S * inv_diag_[bi][i] * S;
      (*body.v)[i] = S * (*body.v)[i] + body.projection->z[i];
    }
  }
  // Per row: the terms of Dt^-1 G_r^T and B_rr; the warm start projected onto the bounds.
  g_.resize(rows.terms.size());
  diag_.assign(nr, 0.0);
  c_.resize(nr);
  lambda.resize(nr, 0.0);
  for (size_t r = 0; r < nr; ++r) {
    double scale = 0;
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const RowTerm& term = rows.terms[t];
      const Mat3& inv = inv_diag_[term.body][term.node];
      g_[t] = term.coef * (inv * rows.direction[r]);
      diag_[r] += term.coef * rows.direction[r].dot(g_[t]);
      scale += term.coef * term.coef * inv.norm();
    }
    // A row whose nodes cannot move along it (B_rr ~ 0: fixed nodes) carries no impulse.
    if (!(diag_[r] > 1e-12 * scale)) diag_[r] = 0;
  }
  pair_step_.assign(nr, 0.0);
  for (size_t r = 0; r < nr; ++r) {
    if (!rows.first_tangent(r)) continue;
    double coupling = 0;  // B_t1t2: the terms of the two rows on one node
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
      for (int32_t u = rows.start[r + 1]; u < rows.start[r + 2]; ++u)
        if (rows.terms[t].body == rows.terms[u].body && rows.terms[t].node == rows.terms[u].node)
          coupling += rows.terms[t].coef * rows.direction[r].dot(g_[u]);
    if (diag_[r] == 0 || diag_[r + 1] == 0) coupling = 0;  // a row nothing moves along takes no step
    const double largest = std::max(diag_[r], diag_[r + 1]) + std::abs(coupling);
    if (largest > 0) pair_step_[r] = 1 / largest;
  }
  for (size_t r = 0; r < nr; ++r)
    if (diag_[r] == 0) lambda[r] = 0;
  rows.project(lambda);  // the warm start onto the cones
  for (size_t r = 0; r < nr; ++r)
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
      u_[rows.terms[t].body][rows.terms[t].node] += g_[t] * lambda[r];

  // Scales for the stopping test, so it stays meaningful when v or lambda tend to zero (a body
  // at rest): the velocity the momentum and loads alone give, Dt^-1 b, and the impulse the
  // first anticipation calls for, c / B_rr.
  // Below 1 micrometre per second (RMS per node) velocity changes are round-off for any tissue
  // scene, so a body at rest with no loads stops at once.
  double v_scale2 = 0, l_scale2 = 0;
  for (size_t bi = 0; bi < nb; ++bi) v_scale2 += 1e-12 * bodies[bi].node_count();
  for (size_t bi = 0; bi < nb; ++bi)
    for (int32_t i = 0; i < bodies[bi].node_count(); ++i)
      v_scale2 += (inv_diag_[bi][i] * (*bodies[bi].b)[i]).squaredNorm();
  for (size_t r = 0; r < nr; ++r)
    if (diag_[r] > 0) l_scale2 += std::pow(anticipated_velocity(bodies, rows, r) / diag_[r], 2);

  SolveReport report;
  report.converged = false;
  report.momentum_residual = std::numeric_limits<double>::quiet_NaN();
  int32_t next_residual_check = 0;  // the true residual costs a sweep: checked when the changes say done
  while (report.iterations < settings.max_iterations) {
    if (ctx.deadline && report.iterations > 0 && SolveContext::Clock::now() >= *ctx.deadline) {
      report.out_of_time = true;
      break;
    }
    ++report.iterations;
    lambda_old_ = lambda;
    // Anticipate: each row's velocity from the current v, without contact.
    for (size_t r = 0; r < nr; ++r) c_[r] = anticipated_velocity(bodies, rows, r);
    // Projected Gauss-Seidel on lambda with B = G Dt^-1 G^T (B couples rows sharing a node): a
    // normal row onto lambda >= 0, a contact's tangent pair together onto its friction disk.
    for (int32_t sweep = 0; sweep < settings.pgs_sweeps; ++sweep)
      for (size_t r = 0; r < nr; ++r) {
        if (rows.normal_of[r] >= 0) {
          if (rows.first_tangent(r)) update_tangents(rows, r++, lambda);  // r + 1 done with it
          continue;
        }
        if (diag_[r] == 0) continue;
        double w = c_[r];
        for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
          w += rows.terms[t].coef * rows.direction[r].dot(u_[rows.terms[t].body][rows.terms[t].node]);
        const double before = lambda[r];
        lambda[r] = std::max(0.0, lambda[r] - w / diag_[r]);
        for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
          u_[rows.terms[t].body][rows.terms[t].node] += g_[t] * (lambda[r] - before);
      }
    // MBGS sweep with the contact impulses G^T lambda on the right-hand side.
    scatter_contact_impulses(rows, lambda, bodies);
    double dv2 = 0, v2 = 0;
    const auto has_colours = [](const SolverBody& body) { return body.colours != nullptr; };
    if (ctx.pool && std::all_of(bodies.begin(), bodies.end(), has_colours))
      coloured_sweep(bodies, *ctx.pool, dv2, v2);
    else for (size_t bi = 0; bi < nb; ++bi) {
      SolverBody& body = bodies[bi];
      Vec3List& v = *body.v;
      const Vec3List& impulse = *body.contact_impulse;
      for (int32_t i = 0; i < body.node_count(); ++i) {
        const Vec3 gs = node_update(body, inv_diag_[bi][i], i, (*body.b)[i] + impulse[i]);
        // Over-relaxation keeps (I - S) v = z: both v_i and the Gauss-Seidel value satisfy it.
        const Vec3 next = v[i] + settings.relaxation * (gs - v[i]);
        dv2 += (next - v[i]).squaredNorm();
        v[i] = next;
        v2 += next.squaredNorm();
      }
    }
    double dl2 = 0, l2 = 0;
    for (size_t r = 0; r < nr; ++r) {
      dl2 += (lambda[r] - lambda_old_[r]) * (lambda[r] - lambda_old_[r]);
      l2 += lambda[r] * lambda[r];
    }
    report.velocity_change = dv2 > 0 ? std::sqrt(dv2 / std::max(v2, v_scale2)) : 0.0;
    report.impulse_change = dl2 > 0 ? std::sqrt(dl2 / std::max(l2, l_scale2)) : 0.0;
    report.paper_change = std::sqrt(dv2 + dl2);
    report.residual = std::max(report.velocity_change, report.impulse_change);
    if (settings.paper_norm) {
      if (report.paper_change <= settings.tolerance) {
        report.converged = true;
        break;
      }
    } else if (report.residual <= settings.tolerance && report.iterations >= next_residual_check) {
      report.momentum_residual = momentum_residual(bodies);
      if (report.momentum_residual <= settings.tolerance) {
        report.residual = std::max(report.residual, report.momentum_residual);
        report.converged = true;
        break;
      }
      next_residual_check = report.iterations + std::max(1, report.iterations / 8);
    }
  }
  if (!report.converged && !settings.paper_norm) {  // say how far from balance the step stopped
    report.momentum_residual = momentum_residual(bodies);
    report.residual = std::max(report.residual, report.momentum_residual);
  }
  return report;
}

// The MBGS sweep colour by colour: blocks of one colour share no block of A, so updating them
// at once is the Gauss-Seidel sweep in the colouring's order (each block in node order),
// whichever thread takes which block. The sums of the stopping test add up per block, then in
// the colouring's order: the result does not depend on the thread count either.
void MicaSolver::coloured_sweep(std::vector<SolverBody>& bodies, ThreadPool& pool, double& dv2, double& v2) {
  const double relaxation = settings_.relaxation;
  for (size_t bi = 0; bi < bodies.size(); ++bi) {
    SolverBody& body = bodies[bi];
    const Colouring& c = *body.colours;
    const std::vector<Mat3>& inv_diag = inv_diag_[bi];
    Vec3List& v = *body.v;
    const Vec3List& impulse = *body.contact_impulse;
    if (block_sums_.size() < size_t(c.blocks())) block_sums_.resize(size_t(c.blocks()));  // the first solve only
    auto blocks = [&](int32_t, int32_t first, int32_t last, int32_t) {
      for (int32_t n = first; n < last; ++n) {
        double d = 0, s = 0;
        for (int32_t i = c.block_start[c.order[n]]; i < c.block_start[c.order[n] + 1]; ++i) {
          const Vec3 gs = node_update(body, inv_diag[i], i, (*body.b)[i] + impulse[i]);
          const Vec3 next = v[i] + relaxation * (gs - v[i]);
          d += (next - v[i]).squaredNorm();
          v[i] = next;
          s += next.squaredNorm();
        }
        block_sums_[n] = {d, s};
      }
    };
    pool.phased_for(c.start.data(), c.colours(), 1, blocks);
    for (int32_t n = 0; n < c.blocks(); ++n) {
      dv2 += block_sums_[n][0];
      v2 += block_sums_[n][1];
    }
  }
}

}  // namespace mica
