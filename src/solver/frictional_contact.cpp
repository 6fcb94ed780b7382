// SPDX-License-Identifier: Apache-2.0
#include "solver/frictional_contact.hpp"

#include <Eigen/QR>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "solver/cod_solve.hpp"
#include "solver/friction_cone.hpp"
#include "solver/stall_watch.hpp"

namespace mica {

namespace {

using Block = FrictionalWorkspace::Block;

void blocks_of(const Eigen::MatrixXd& M, const std::vector<ConeContact>& contacts, std::vector<Block>& blocks) {
  blocks.clear();
  for (const ConeContact& c : contacts) {
    Block b{{c.normal, c.tangent[0], c.tangent[1]}, Mat3::Zero(), c.mu};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (b.row[i] >= 0 && b.row[j] >= 0) b.W(i, j) = M(b.row[i], b.row[j]);
        else if (i == j) b.W(i, j) = M(c.normal, c.normal);
    blocks.push_back(b);
  }
}

// One sweep over the contacts, each moved a fraction omega of the way to its exact local solution
// (omega = 1: block Gauss-Seidel). w follows z.
void sweep(const Eigen::MatrixXd& M, const std::vector<Block>& blocks, double omega, Eigen::VectorXd& z,
           Eigen::VectorXd& w) {
  for (const Block& b : blocks) {
    Vec3 z_c = Vec3::Zero(), q_c = Vec3::Zero();
    for (int i = 0; i < 3; ++i)
      if (b.row[i] >= 0) {
        z_c(i) = z(b.row[i]);
        q_c(i) = w(b.row[i]);
      }
    q_c -= b.W * z_c;  // the others' part: w of this contact without its own impulse
    for (int i = 0; i < 3; ++i)
      if (b.row[i] < 0) q_c(i) = 0;
    // A convex combination of two points of the cone stays in it.
    const Vec3 dz = omega * (solve_contact_coulomb(b.W, q_c, b.mu) - z_c);
    for (int i = 0; i < 3; ++i)
      if (b.row[i] >= 0 && dz(i) != 0) {
        z(b.row[i]) += dz(i);
        w.noalias() += M.col(b.row[i]) * dz(i);
      }
  }
}

// The natural map of cone_error as a vector, F(z) = z - P(z - rho w) per contact (rho = 1 / the
// contact's largest diagonal entry), and, if J is given, an element of its generalized Jacobian.
// Its per-contact 2-norms are cone_error's.
void natural_map(const Eigen::MatrixXd& M, const std::vector<Block>& blocks, const Eigen::VectorXd& z,
                 const Eigen::VectorXd& w, Eigen::VectorXd& F, Eigen::MatrixXd* J) {
  if (J) J->setZero();
  for (const Block& b : blocks) {
    const double rho = 1 / b.W.diagonal().maxCoeff();  // absent rows carry the normal's diagonal
    const int32_t n = b.row[0];
    const double zn = z(n), yn = zn - rho * w(n);
    // Normal row: F = z_n - max(0, y_n).
    F(n) = yn > 0 ? rho * w(n) : zn;
    if (J) {
      if (yn > 0) J->row(n) = rho * M.row(n);
      else (*J)(n, n) = 1;
    }
    // Tangent pair: F_t = z_t - P_disk(y_t), radius r = mu max(z_n, 0).
    Eigen::Vector2d zt = Eigen::Vector2d::Zero(), yt = Eigen::Vector2d::Zero();
    for (int k = 0; k < 2; ++k)
      if (b.row[k + 1] >= 0) {
        zt(k) = z(b.row[k + 1]);
        yt(k) = zt(k) - rho * w(b.row[k + 1]);
      }
    const double r = b.mu * std::max(zn, 0.0), norm = yt.norm();
    const bool inside = norm <= r;
    const Eigen::Vector2d unit = norm > 0 ? Eigen::Vector2d(yt / norm) : Eigen::Vector2d::Zero();
    const Eigen::Vector2d Ft = inside ? Eigen::Vector2d(zt - yt) : Eigen::Vector2d(zt - r * unit);
    // Outside: dF_t = dz_t - mu unit dz_n - (r / |y_t|) (I - unit unit^T) (dz_t - rho M_t dz).
    const Eigen::Matrix2d bend = inside || norm == 0 ? Eigen::Matrix2d::Zero()
                                                     : Eigen::Matrix2d((r / norm) * (Eigen::Matrix2d::Identity() - unit * unit.transpose()));
    for (int k = 0; k < 2; ++k) {
      const int32_t t = b.row[k + 1];
      if (t < 0) continue;
      F(t) = Ft(k);
      if (!J) continue;
      if (inside) {
        J->row(t) = rho * M.row(t);
        continue;
      }
      (*J)(t, t) += 1;
      if (zn > 0) (*J)(t, n) -= b.mu * unit(k);
      for (int j = 0; j < 2; ++j) {
        const int32_t s = b.row[j + 1];
        if (s < 0 || bend(k, j) == 0) continue;
        (*J)(t, s) -= bend(k, j);
        J->row(t) += bend(k, j) * rho * M.row(s);
      }
    }
  }
}

}  // namespace

FrictionalSolution solve_frictional_contact(const Eigen::MatrixXd& M, const Eigen::VectorXd& q,
                                            const Eigen::VectorXd& mu, const std::vector<int32_t>& normal_index,
                                            const Eigen::VectorXd& z0, const FrictionalSettings& settings) {
  FrictionalWorkspace ws;
  FrictionalSolution s;
  solve_frictional_contact(M, q, mu, normal_index, z0, settings, ws, s);
  return s;
}

void solve_frictional_contact(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu,
                              const std::vector<int32_t>& normal_index, const Eigen::VectorXd& z0,
                              const FrictionalSettings& settings, FrictionalWorkspace& ws, FrictionalSolution& s) {
  cone_contacts(M, q, mu, normal_index, "solve_frictional_contact", ws.contacts, ws.contact_of);
  const std::vector<ConeContact>& contacts = ws.contacts;
  const Eigen::Index n = q.size();
  if (z0.size() != 0 && (z0.size() != n || !z0.allFinite()))
    fail(Errc::InvalidArgument, "solve_frictional_contact: the warm start needs one finite entry per row");
  if (!(settings.tolerance >= 0) || settings.max_sweeps < 0)
    fail(Errc::InvalidArgument, "solve_frictional_contact: need tolerance >= 0 and max_sweeps >= 0");
  blocks_of(M, contacts, ws.blocks);
  const std::vector<Block>& blocks = ws.blocks;

  s.solved = s.out_of_time = false;
  s.sweeps = s.newton_steps = 0;
  s.error = s.scale = 0;
  if (z0.size()) s.z = z0;
  else s.z.setZero(n);
  for (const Block& b : blocks) {
    double t[2] = {b.row[1] >= 0 ? s.z(b.row[1]) : 0.0, b.row[2] >= 0 ? s.z(b.row[2]) : 0.0};
    project_onto_cone(b.mu, s.z(b.row[0]), t[0], t[1]);
    for (int k = 0; k < 2; ++k)
      if (b.row[k + 1] >= 0) s.z(b.row[k + 1]) = t[k];
  }
  double demand = 0;  // the impulse each normal row alone asks for
  for (const Block& b : blocks) demand = std::max(demand, -q(b.row[0]) / b.W(0, 0));
  // fresh: w = M z + q afresh (the sweeps' incremental updates drift by round-off); otherwise the
  // sweeps' w, which costs nothing to check and is refreshed before it may say "solved".
  auto check = [&](bool fresh) {
    if (fresh) {
      s.w.noalias() = M * s.z;
      s.w += q;
    }
    s.error = cone_error(M, contacts, s.z, s.w);
    s.scale = std::max(demand, s.z.size() ? s.z.cwiseAbs().maxCoeff() : 0.0);
    return s.error <= settings.tolerance * s.scale;
  };
  auto converged = [&] { return check(true); };
  auto converged_after_sweep = [&] { return check(s.sweeps % 64 == 0) && converged(); };
  // Block Gauss-Seidel converges, but linearly, and slowly where contacts are nearly redundant
  // (several contact points on the nodes of one face: W is close to singular). So batches of
  // sweeps alternate with Newton steps on the natural map F (cone_error's residual vector), which
  // converge quadratically once the sweeps have found which contacts stick, slide or separate.
  // A Newton step is kept only if it lowers |F| (backtracking); a singular Jacobian (redundant
  // contacts) takes its least-squares minimum-norm step. Should the sweeps cycle, as nonsmooth
  // Gauss-Seidel can with strongly coupled sliding contacts, the second half of the sweep budget
  // is damped (half way to each local solution): slower, but a contraction in practice. Either
  // way the result is checked by cone_error and said.
  for (Eigen::VectorXd* v : {&ws.F, &ws.F_trial, &ws.dz, &ws.z_trial, &ws.w_trial, &ws.cod_work, &ws.cod_y}) v->resize(n);
  ws.J.resize(n, n);
  Eigen::VectorXd &F = ws.F, &F_trial = ws.F_trial, &dz = ws.dz, &z_trial = ws.z_trial, &w_trial = ws.w_trial;
  Eigen::MatrixXd& J = ws.J;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>& cod = ws.cod;
  auto out_of_time = [&] {
    s.out_of_time = settings.deadline && std::chrono::steady_clock::now() >= *settings.deadline;
    return s.out_of_time;
  };
  // A Newton step factors the dense n x n Jacobian: past kMaxNewtonRows rows (hundreds of
  // contacts, a body gone wild) twenty of them per batch took minutes a step; sweeps only there.
  const bool newton = n <= std::min(kMaxNewtonRows, settings.max_newton_rows);
  // Progress is judged every kStallWindow sweeps: a window that did not halve the best relative
  // residual switches to the damped sweeps, a second such window stops ("stalled"). A problem that
  // stalls (friction near redundant contacts, which need not have a unique solution) would
  // otherwise spend its whole budget, 10^4 sweeps and ~100 Newton steps, at the same residual.
  // Halving per window is the slowest rate that reaches 1e-10 from 1e-1 (30 halvings) within
  // the default budget, so the rule gives up only on what the budget would not have solved.
  constexpr int32_t kStallWindow = 256;
  bool damped = false, stalled = false;
  StallWatch progress(kStallWindow);
  s.solved = converged();
  for (int32_t batch = 8; !s.solved && !stalled && s.sweeps < 2 * settings.max_sweeps;
       batch = std::min(2 * batch, 512)) {
    damped = damped || s.sweeps >= settings.max_sweeps;
    const int32_t sweeps_end = std::min(s.sweeps + batch, 2 * settings.max_sweeps);
    while (!s.solved && s.sweeps < sweeps_end && !out_of_time()) {
      sweep(M, blocks, damped ? 0.5 : 1.0, s.z, s.w);
      ++s.sweeps;
      s.solved = converged_after_sweep();
      progress.add(s.error / s.scale);
    }
    for (int k = 0; k < 20 && newton && !s.solved && !out_of_time(); ++k) {
      natural_map(M, blocks, s.z, s.w, F, &J);
      cod.compute(J);
      cod_solve(cod, F, dz, ws.cod_work, ws.cod_y);
      dz = -dz;
      const double f0 = F.norm();
      bool lowered = false;
      for (double alpha = 1; alpha >= 1.0 / 256 && !lowered; alpha /= 2) {
        z_trial = s.z + alpha * dz;
        w_trial.noalias() = M * z_trial;
        w_trial += q;
        natural_map(M, blocks, z_trial, w_trial, F_trial, nullptr);
        lowered = F_trial.norm() <= (1 - 1e-4 * alpha) * f0;
      }
      ++s.newton_steps;
      if (!lowered) break;  // back to the sweeps
      s.z.swap(z_trial);
      s.solved = converged();
      progress.add(s.error / s.scale);
    }
    if (s.out_of_time) break;
    if (!progress.progressing(s.sweeps)) {
      stalled = damped;
      damped = true;
    }
  }
  // Newton steps may leave a cone by round-off: the impulses returned are admissible.
  for (const Block& b : blocks) {
    double t[2] = {b.row[1] >= 0 ? s.z(b.row[1]) : 0.0, b.row[2] >= 0 ? s.z(b.row[2]) : 0.0};
    project_onto_cone(b.mu, s.z(b.row[0]), t[0], t[1]);
    for (int k = 0; k < 2; ++k)
      if (b.row[k + 1] >= 0) s.z(b.row[k + 1]) = t[k];
  }
  s.solved = converged();
  char text[200];
  std::snprintf(text, sizeof text,
                "%s after %d sweeps and %d Newton steps: cone residual %.3g, %.3g of the impulse scale %.3g",
                s.solved        ? "converged"
                : s.out_of_time ? "stopped at the deadline"
                : stalled       ? "stalled"
                                : "sweep limit reached",
                int(s.sweeps), int(s.newton_steps), s.error, s.scale > 0 ? s.error / s.scale : 0.0, s.scale);
  s.message.reserve(sizeof text);  // kept: later messages fit
  s.message = text;
}

}  // namespace mica
