// SPDX-License-Identifier: Apache-2.0
#include "solver/exact_contact_solver.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "solver/frictional_contact.hpp"

namespace mica {

LinearSolver& ExactContactSolver::linear_solver(const SolveContext& ctx, const SolverBody& body) {
  ExactBodyCache& cache = cache_of(body);
  if (method_ == LinearMethod::Pcg) {
    cache.pcg.reserve(size_t(body.node_count()));  // sizes its workspace once
    cache.pcg.configure(settings_.tolerance, settings_.max_iterations, ctx.deadline);
    return cache.pcg;
  }
  // CHOLMOD: analysed once; factored when A or the constraint set changed.
  if (!cache.direct.analyzed()) cache.direct.analyze(body.pattern(), body.projection);
  if (!cache.factored || cache.matrix_version != body.matrix_version ||
      cache.constraint_version != body.constraint_version) {
    cache.factored = false;
    cache.direct.factorize(body.projected());
    cache.factored = true;
    cache.matrix_version = body.matrix_version;
    cache.constraint_version = body.constraint_version;
  }
  return cache.direct;
}

SolveReport ExactContactSolver::solve(const SolveContext& ctx, std::vector<SolverBody>& bodies,
                                      const ContactRows& rows, std::vector<double>& lambda) {
  const size_t nb = bodies.size(), nr = rows.size();
  SolveReport linear;
  auto record = [&linear](const SolveReport& r) {
    linear.iterations += r.iterations;
    if (!(r.residual <= linear.residual)) linear.residual = r.residual;
    linear.converged = linear.converged && r.converged;
    linear.out_of_time = linear.out_of_time || r.out_of_time;
  };
  // Free velocities: the step without contact.
  solvers_.resize(nb);
  for (size_t bi = 0; bi < nb; ++bi) {
    solvers_[bi] = &linear_solver(ctx, bodies[bi]);
    record(solvers_[bi]->solve(bodies[bi].projected(), *bodies[bi].b, *bodies[bi].v));
  }
  if (nr == 0) {  // no contact: the free velocities are the step's
    for (SolverBody& body : bodies)
      for (Vec3& f : *body.contact_impulse) f.setZero();
    lambda.clear();
    diagonal_.clear();
    return linear;
  }
  warm_.assign(lambda.begin(), lambda.end());
  warm_.resize(nr, 0.0);
  // Responses A^-1 G_s^T, per row and per body the row touches.
  std::vector<std::vector<Vec3List>> response(nr, std::vector<Vec3List>(nb));
  for (size_t s = 0; s < nr; ++s)
    for (int32_t t = rows.start[s]; t < rows.start[s + 1]; ++t) {
      const int32_t bi = rows.terms[t].body;
      if (!response[s][bi].empty()) continue;
      const SolverBody& body = bodies[bi];
      Vec3List f(body.v->size(), Vec3::Zero());
      for (int32_t u = rows.start[s]; u < rows.start[s + 1]; ++u)
        if (rows.terms[u].body == bi) f[rows.terms[u].node] += rows.terms[u].coef * rows.direction[s];
      response[s][bi].resize(f.size());
      record(solvers_[bi]->solve_homogeneous(body.projected(), f, response[s][bi]));
    }
  // W = G A^-1 G^T and q = G v_free + gap / h.
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(Eigen::Index(nr), Eigen::Index(nr));
  Eigen::VectorXd q = Eigen::VectorXd::Zero(Eigen::Index(nr));
  for (size_t r = 0; r < nr; ++r) {
    q[r] = rows.bias[r];
    for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t) {
      const RowTerm& term = rows.terms[t];
      q[r] += term.coef * rows.direction[r].dot((*bodies[term.body].v)[term.node]);
      for (size_t s = 0; s < nr; ++s)
        if (!response[s][term.body].empty())
          W(r, s) += term.coef * rows.direction[r].dot(response[s][term.body][term.node]);
    }
  }
  diagonal_.assign(W.diagonal().data(), W.diagonal().data() + nr);
  // Rows whose points cannot move along them (W_rr ~ 0: fixed nodes) carry no impulse: they are
  // left out, as in MICA, or a penetrating one would make the problem infeasible.
  const double scale = std::max(W.diagonal().cwiseAbs().maxCoeff(), 1e-300);
  std::vector<int32_t> kept, kept_at(nr, -1);
  for (size_t r = 0; r < nr; ++r) {
    // A friction row goes with its normal row (rows come normal first).
    const bool normal_kept = rows.normal_of[r] < 0 || kept_at[rows.normal_of[r]] >= 0;
    if (W(r, r) > 1e-12 * scale && normal_kept) {
      kept_at[r] = int32_t(kept.size());
      kept.push_back(int32_t(r));
    }
  }
  const Eigen::Index nk = Eigen::Index(kept.size());
  Eigen::MatrixXd Wk(nk, nk);
  Eigen::VectorXd qk(nk), mu(nk), warm(nk);
  std::vector<int32_t> normal_of(kept.size());
  bool friction = false;
  for (Eigen::Index i = 0; i < nk; ++i) {
    for (Eigen::Index j = 0; j < nk; ++j) Wk(i, j) = W(kept[i], kept[j]);
    qk[i] = q[kept[i]];
    mu[i] = rows.mu[kept[i]];
    const int32_t n = rows.normal_of[kept[i]];
    normal_of[i] = n < 0 ? -1 : kept_at[n];
    friction = friction || normal_of[i] >= 0;
    warm[i] = warm_[size_t(kept[i])];
  }
  // A contact problem out of double precision (a time step of 1e-300 s makes gap / h infinite)
  // is the step's numerical failure, not a bad argument of the solvers below.
  if (!Wk.allFinite() || !qk.allFinite())
    fail(Errc::Numerical, "the contact problem of this step is not finite (the time step is too small, or the "
                          "velocities too large, for double precision); the step was undone");
  // Without friction the LCP is solved exactly by Lemke's pivoting; with friction (not an LCP:
  // the cone's radius moves with the normal impulse) by block Gauss-Seidel over the contacts,
  // each contact's Coulomb problem solved exactly, to round-off. The sweeps also take over where
  // many redundant contacts (a flat punch: nodes, edges and faces in one plane) defeat the
  // pivoting.
  SolveReport report = linear;
  Eigen::VectorXd z;
  double error = 0;
  std::string pivoting;
  if (!friction) {
    const LcpSolution sol = solve_lcp_lemke(Wk, qk);
    if (sol.solved && sol.z.allFinite()) {
      z = sol.z;
      error = complementarity_error(Wk, qk, z);
    } else {
      pivoting = "pivoting failed (" + sol.message + "), then ";
    }
  }
  if (z.size() != nk) {
    FrictionalSettings fs;
    fs.deadline = ctx.deadline;
    const FrictionalSolution sol = solve_frictional_contact(Wk, qk, mu, normal_of, warm, fs);
    if (!sol.z.allFinite()) fail(Errc::Numerical, "the exact contact solve failed: " + pivoting + sol.message);
    z = sol.z;
    error = sol.scale > 0 ? sol.error / sol.scale : sol.error;
    report.iterations += sol.sweeps;
    report.converged = report.converged && sol.solved;  // unsolved: reported, not thrown
    report.out_of_time = report.out_of_time || sol.out_of_time;
  }
  Eigen::VectorXd l = Eigen::VectorXd::Zero(Eigen::Index(nr));
  for (Eigen::Index i = 0; i < nk; ++i) l[kept[i]] = z[i];
  if (!(error <= report.residual)) report.residual = error;
  lambda.assign(l.data(), l.data() + l.size());
  // v = v_free + A^-1 G^T lambda, and the impulses per node.
  for (size_t s = 0; s < nr; ++s)
    for (size_t bi = 0; bi < nb; ++bi)
      if (!response[s][bi].empty())
        for (size_t i = 0; i < response[s][bi].size(); ++i) (*bodies[bi].v)[i] += response[s][bi][i] * l[s];
  scatter_contact_impulses(rows, lambda, bodies);
  return report;
}

}  // namespace mica
