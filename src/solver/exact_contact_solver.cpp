#include "solver/exact_contact_solver.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace mica {

namespace {

// Box-constrained projected Gauss-Seidel on the exact W, to round-off: normal rows
// lambda >= 0, friction rows |lambda| <= mu lambda_normal. W is symmetric positive semidefinite.
int32_t solve_complementarity(const Eigen::MatrixXd& W, const Eigen::VectorXd& q, const ContactRows& rows,
                              Eigen::VectorXd& l) {
  const Eigen::Index n = q.size();
  l.setZero(n);
  int32_t sweeps = 0;
  for (; sweeps < 1000000; ++sweeps) {
    double change = 0;
    for (Eigen::Index r = 0; r < n; ++r) {
      if (!(W(r, r) > 0)) continue;
      double next = l[r] - (W.row(r).dot(l) + q[r]) / W(r, r);
      if (rows.normal_of[r] < 0) {
        next = std::max(0.0, next);
      } else {
        const double bound = rows.mu[r] * l[rows.normal_of[r]];
        next = std::clamp(next, -bound, bound);
      }
      change = std::max(change, std::fabs(next - l[r]));
      l[r] = next;
    }
    if (change <= 1e-15 * std::max(1e-300, l.cwiseAbs().maxCoeff())) break;
  }
  return sweeps + 1;
}

}  // namespace

SolveReport solve_exact_contact(std::vector<ExactBody>& bodies, const ContactRows& rows, std::vector<double>& lambda) {
  const size_t nb = bodies.size(), nr = rows.size();
  // Free velocities: the step without contact.
  for (ExactBody& body : bodies) {
    const ProjectedSystem sys{*body.pattern, *body.A, *body.projection};
    body.direct->solve(sys, *body.b, *body.v);
  }
  // Responses A^-1 G_s^T, per row and per body the row touches.
  std::vector<std::vector<Vec3List>> response(nr, std::vector<Vec3List>(nb));
  for (size_t s = 0; s < nr; ++s)
    for (int32_t t = rows.start[s]; t < rows.start[s + 1]; ++t) {
      const int32_t bi = rows.terms[t].body;
      if (!response[s][bi].empty()) continue;
      ExactBody& body = bodies[bi];
      Vec3List f(body.v->size(), Vec3::Zero());
      for (int32_t u = rows.start[s]; u < rows.start[s + 1]; ++u)
        if (rows.terms[u].body == bi) f[rows.terms[u].node] += rows.terms[u].coef * rows.direction[s];
      response[s][bi].resize(f.size());
      const ProjectedSystem sys{*body.pattern, *body.A, *body.projection};
      body.direct->solve_homogeneous(sys, f, response[s][bi]);
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
  Eigen::VectorXd l;
  SolveReport report;
  report.iterations = solve_complementarity(W, q, rows, l);
  if (!l.allFinite()) fail(Errc::Numerical, "the exact contact solve produced non-finite impulses");
  lambda.assign(l.data(), l.data() + l.size());
  // v = v_free + A^-1 G^T lambda, and the impulses per node.
  for (size_t bi = 0; bi < nb; ++bi) bodies[bi].contact_impulse.assign(bodies[bi].v->size(), Vec3::Zero());
  for (size_t s = 0; s < nr; ++s) {
    for (size_t bi = 0; bi < nb; ++bi)
      if (!response[s][bi].empty())
        for (size_t i = 0; i < response[s][bi].size(); ++i) (*bodies[bi].v)[i] += response[s][bi][i] * l[s];
    for (int32_t t = rows.start[s]; t < rows.start[s + 1]; ++t)
      bodies[rows.terms[t].body].contact_impulse[rows.terms[t].node] += rows.terms[t].coef * l[s] * rows.direction[s];
  }
  // Complementarity of the result, reported as the residual.
  const Eigen::VectorXd w = W * l + q;
  double worst = 0;
  for (size_t r = 0; r < nr; ++r)
    if (rows.normal_of[r] < 0) worst = std::max({worst, -w[r], std::fabs(w[r] * l[r])});
  report.residual = worst;
  report.converged = true;
  return report;
}

}  // namespace mica
