// SPDX-License-Identifier: Apache-2.0
#include "solver/velocity_solver.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "solver/exact_contact_solver.hpp"
#include "solver/factored_mica.hpp"
#include "solver/mica_solver.hpp"

namespace mica {

std::unique_ptr<VelocitySolver> make_velocity_solver(SolverKind kind, MicaSweep sweep, const SolverSettings& settings) {
  switch (kind) {
    case SolverKind::Direct: return std::make_unique<ExactContactSolver>(LinearMethod::Direct, settings);
    case SolverKind::Pcg: return std::make_unique<ExactContactSolver>(LinearMethod::Pcg, settings);
    case SolverKind::Mica:
      if (sweep == MicaSweep::Factored) return std::make_unique<FactoredMicaSolver>(settings);
      return std::make_unique<MicaSolver>(settings);
  }
  fail(Errc::InvalidArgument, "unknown solver kind");
}

void zero_velocities(std::vector<SolverBody>& bodies) {
  for (SolverBody& body : bodies)
    for (Vec3& v : *body.v) v.setZero();
}

void scatter_contact_impulses(const ContactRows& rows, const std::vector<double>& lambda,
                              std::vector<SolverBody>& bodies) {
  for (SolverBody& body : bodies) body.contact_impulse->assign(size_t(body.node_count()), Vec3::Zero());
  rows.scatter(lambda, [&](int32_t body) -> Vec3List& { return *bodies[size_t(body)].contact_impulse; });
}

double momentum_residual(const std::vector<SolverBody>& bodies) {
  thread_local Vec3List av;  // kept: grown to the largest body, then no allocation
  thread_local std::vector<double> bound;
  double worst = 0;
  for (const SolverBody& body : bodies) {  // per body: a small body's imbalance may not hide in a large one's
    const BlockPattern& p = body.pattern();
    if (av.size() < size_t(p.rows)) av.resize(size_t(p.rows)), bound.resize(size_t(p.rows));
    // A v, and what its round-off is relative to: sum_j |A_ij| |v_j|, bounded (block_multiply_bound).
    block_multiply_bound(p, *body.A, *body.v, av, bound);
    double r2 = 0, scale2 = 0, terms2 = 0;
    for (int32_t i = 0; i < p.rows; ++i) {
      const Vec3& b = (*body.b)[i];
      const Vec3& g = (*body.contact_impulse)[i];
      const Vec3 r = b + g - av[i];
      r2 += body.projection->free_part(i, r).squaredNorm();
      const double floor = 1e-6 * body.fem->node_mass[i];
      scale2 += std::max({b.squaredNorm(), g.squaredNorm(), av[i].squaredNorm(), floor * floor});
      terms2 += bound[size_t(i)];
    }
    // A v is a sum of large terms that cancel where the body is driven through its constraints:
    // its rounding (a few hundred ulps of those terms) is no error of the solve.
    const double r = std::max(0.0, std::sqrt(r2) - 1e-13 * std::sqrt(terms2));
    if (scale2 > 0) worst = std::max(worst, r / std::sqrt(scale2));
  }
  return worst;
}

}  // namespace mica
