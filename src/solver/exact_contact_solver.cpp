#include "solver/exact_contact_solver.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "solver/lcp.hpp"

namespace mica {


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
  // Without friction the LCP is solved exactly by Lemke's pivoting; friction's box bounds by
  // projected Gauss-Seidel on the exact W, to round-off.
  const bool friction = std::any_of(rows.normal_of.begin(), rows.normal_of.end(), [](int32_t n) { return n >= 0; });
  const Eigen::VectorXd mu = Eigen::Map<const Eigen::VectorXd>(rows.mu.data(), Eigen::Index(nr));
  const LcpSolution sol = friction ? solve_box_lcp_pgs(W, q, mu, rows.normal_of, 1e-14, 1000000)
                                   : solve_lcp_lemke(W, q);
  if (!sol.solved || !sol.z.allFinite())
    fail(Errc::Numerical, "the exact contact solve failed: " + sol.message);
  const Eigen::VectorXd& l = sol.z;
  SolveReport report;
  report.iterations = sol.pivots;
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
  report.residual = friction ? box_lcp_error(W, q, mu, rows.normal_of, l) : complementarity_error(W, q, l);
  report.converged = true;
  return report;
}

}  // namespace mica
