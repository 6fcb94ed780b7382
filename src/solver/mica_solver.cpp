#include "solver/mica_solver.hpp"

#include <algorithm>
#include <cmath>

namespace mica {

namespace {

// v_i = z_i + Dt_i^-1 (q_i - sum_{j != i} A_ij v_j - D_ii z_i): the constrained-filtered block
// Gauss-Seidel (or, with v read but not written, Jacobi) update of node i.
Vec3 node_update(const MicaBody& body, const Mat3& inv_diag, int32_t i, const Vec3& q_i) {
  const BlockPattern& p = *body.pattern;
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

MicaReport MicaSolver::solve(std::vector<MicaBody>& bodies, const std::vector<Contact>& contacts, double h,
                             const MicaSettings& settings, std::vector<double>& lambda) {
  const size_t nb = bodies.size(), nc = contacts.size();
  inv_diag_.resize(nb);
  u_.resize(nb);
  // Filtered diagonal inverses; the warm start made to satisfy (I - S) v = z.
  for (size_t bi = 0; bi < nb; ++bi) {
    MicaBody& body = bodies[bi];
    const ProjectedSystem sys{*body.pattern, *body.A, *body.projection};
    const int32_t n = body.pattern->rows;
    inv_diag_[bi].resize(size_t(n));
    u_[bi].assign(size_t(n), Vec3::Zero());
    body.contact_impulse.assign(size_t(n), Vec3::Zero());
    for (int32_t i = 0; i < n; ++i) inv_diag_[bi][i] = sys.diagonal_block(i).inverse();
    for (int32_t i : body.projection->nodes) {
      const Mat3& S = body.projection->S[i];
      inv_diag_[bi][i] = S * inv_diag_[bi][i] * S;
      (*body.v)[i] = S * (*body.v)[i] + body.projection->z[i];
    }
  }
  // Per contact: Dt^-1 n, the diagonal of B, the clamped recovery term.
  g_.resize(nc);
  diag_.resize(nc);
  bias_.resize(nc);
  c_.resize(nc);
  lambda.resize(nc, 0.0);
  for (size_t r = 0; r < nc; ++r) {
    const Contact& ct = contacts[r];
    g_[r] = inv_diag_[ct.body][ct.node] * ct.normal;
    diag_[r] = ct.normal.dot(g_[r]);
    bias_[r] = std::max(ct.gap / h, -settings.max_recovery_speed);
    // A row on a node that cannot move along n (B_rr ~ 0) carries no impulse.
    const double scale = inv_diag_[ct.body][ct.node].norm();
    if (!(diag_[r] > 1e-12 * scale)) diag_[r] = 0;
    lambda[r] = diag_[r] > 0 ? std::max(0.0, lambda[r]) : 0.0;
    u_[ct.body][ct.node] += g_[r] * lambda[r];
  }

  // Scales for the stopping test, so it stays meaningful when v or lambda tend to zero (a body
  // at rest): the velocity the momentum and loads alone give, Dt^-1 b, and the impulse the
  // first anticipation calls for, c / B_rr.
  double v_scale2 = 0, l_scale2 = 0;
  for (size_t bi = 0; bi < nb; ++bi)
    for (int32_t i = 0; i < bodies[bi].pattern->rows; ++i) v_scale2 += (inv_diag_[bi][i] * (*bodies[bi].b)[i]).squaredNorm();
  for (size_t r = 0; r < nc; ++r) {
    if (diag_[r] == 0) continue;
    const Contact& ct = contacts[r];
    const MicaBody& body = bodies[ct.body];
    const double c = ct.normal.dot(node_update(body, inv_diag_[ct.body][ct.node], ct.node, (*body.b)[ct.node])) + bias_[r];
    l_scale2 += (c / diag_[r]) * (c / diag_[r]);
  }
  MicaReport report;
  report.converged = false;
  while (report.iterations < settings.max_iterations) {
    ++report.iterations;
    lambda_old_ = lambda;
    // Anticipate: the velocity each contact node would get from the current v, without contact.
    for (size_t r = 0; r < nc; ++r) {
      const Contact& ct = contacts[r];
      const MicaBody& body = bodies[ct.body];
      const Vec3 vt = node_update(body, inv_diag_[ct.body][ct.node], ct.node, (*body.b)[ct.node]);
      c_[r] = ct.normal.dot(vt) + bias_[r];
    }
    // Projected Gauss-Seidel on lambda with B = G Dt^-1 G^T (B couples contacts sharing a node).
    for (int32_t sweep = 0; sweep < settings.pgs_sweeps; ++sweep)
      for (size_t r = 0; r < nc; ++r) {
        if (diag_[r] == 0) continue;
        const Contact& ct = contacts[r];
        Vec3& u = u_[ct.body][ct.node];
        const double w = c_[r] + ct.normal.dot(u);
        const double next = std::max(0.0, lambda[r] - w / diag_[r]);
        u += g_[r] * (next - lambda[r]);
        lambda[r] = next;
      }
    // MBGS sweep with the contact impulses on the right-hand side.
    for (size_t bi = 0; bi < nb; ++bi)
      for (Vec3& f : bodies[bi].contact_impulse) f.setZero();
    for (size_t r = 0; r < nc; ++r)
      bodies[contacts[r].body].contact_impulse[contacts[r].node] += contacts[r].normal * lambda[r];
    double dv2 = 0, v2 = 0;
    for (size_t bi = 0; bi < nb; ++bi) {
      MicaBody& body = bodies[bi];
      Vec3List& v = *body.v;
      for (int32_t i = 0; i < body.pattern->rows; ++i) {
        const Vec3 next = node_update(body, inv_diag_[bi][i], i, (*body.b)[i] + body.contact_impulse[i]);
        dv2 += (next - v[i]).squaredNorm();
        v[i] = next;
        v2 += next.squaredNorm();
      }
    }
    double dl2 = 0, l2 = 0;
    for (size_t r = 0; r < nc; ++r) {
      dl2 += (lambda[r] - lambda_old_[r]) * (lambda[r] - lambda_old_[r]);
      l2 += lambda[r] * lambda[r];
    }
    report.velocity_change = dv2 > 0 ? std::sqrt(dv2 / std::max(v2, v_scale2)) : 0.0;
    report.impulse_change = dl2 > 0 ? std::sqrt(dl2 / std::max(l2, l_scale2)) : 0.0;
    report.paper_change = std::sqrt(dv2 + dl2);
    report.residual = std::max(report.velocity_change, report.impulse_change);
    const bool done = settings.paper_norm ? report.paper_change <= settings.tolerance
                                          : report.residual <= settings.tolerance;
    if (done) {
      report.converged = true;
      break;
    }
  }
  return report;
}

}  // namespace mica
