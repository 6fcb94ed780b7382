// SPDX-License-Identifier: Apache-2.0
#include "solver/velocity_solver.hpp"

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

}  // namespace mica
