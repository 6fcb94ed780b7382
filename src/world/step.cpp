// The step: one linearised backward-Euler step at velocity level, per body
//   A v+ = b,  A = M + h C + h^2 K,  b = M v + h (f_int(x) + f_ext),  x+ = x + h v+,
// under the projection constraints (I - S) v+ = z. Each stage runs only when the plan holds it.
#include <cmath>

#include "world/world.hpp"

namespace mica {

Plan World::plan() const {
  Plan p;
  const bool all = settings_.plan_all_stages;
  bodies_.for_each([&](Id, const Body& b) {
    if (!b.is_dynamic()) return;
    p.elements = p.solve = p.integrate = true;
    p.loads = p.loads || needs_loads(b);
    p.rotations = p.rotations || b.settings.corotational;
    p.damping = p.damping || needs_damping(b);
  });
  lpcs_.for_each([&](Id, const Lpc& c) { p.constraints = p.constraints || bodies_.get(c.body, "body").is_dynamic(); });
  if (all) p.constraints = p.constraints || p.solve;
  return p;
}

bool World::needs_loads(const Body& b) const {
  return settings_.plan_all_stages || !settings_.gravity.isZero(0) || b.has_node_forces;
}

bool World::needs_damping(const Body& b) const { return settings_.plan_all_stages || b.has_damping(); }

void World::step(double h) {
  if (!(h > 0 && h <= 1)) fail(Errc::InvalidArgument, "the time step must be in (0, 1] s, got " + std::to_string(h));
  const auto start = std::chrono::steady_clock::now();
  const Plan plan = this->plan();
  std::vector<Body*> dynamic;
  bodies_.for_each([&](Id, Body& b) {
    if (b.is_dynamic()) dynamic.push_back(&b);
  });
  stats_.solver_iterations = 0;
  stats_.solver_residual = 0;
  stats_.converged = true;

  StageRunner stage(stats_);
  stage.run(Stage::Loads, plan.loads, [&] {
    for (Body* b : dynamic)
      if (needs_loads(*b)) apply_loads(*b);
  });
  stage.run(Stage::Rotations, plan.rotations, [&] {
    for (Body* b : dynamic)
      if (b->settings.corotational) compute_rotations(b->fem, b->x, b->R);
  });
  stage.run(Stage::Elements, plan.elements, [&] {
    for (Body* b : dynamic) assemble_elements(*b, h, needs_damping(*b));
  });
  stage.run(Stage::Damping, plan.damping, [&] {
    for (Body* b : dynamic)
      if (needs_damping(*b)) add_damping(*b, h);
  });
  stage.run(Stage::Constraints, plan.constraints, [&] {
    for (Body* b : dynamic) build_projection(*b);
  });
  stage.run(Stage::Solve, plan.solve, [&] {
    for (Body* b : dynamic) solve_velocities(*b, h);
  });
  stage.run(Stage::Integrate, plan.integrate, [&] {
    for (Body* b : dynamic)
      for (size_t i = 0; i < b->x.size(); ++i) b->x_next[i] = b->x[i] + h * b->v_next[i];
  });
  commit();
  stats_.step_count += 1;
  stats_.ms_last_step = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void World::apply_loads(Body& b) const {
  // Gravity through the mass matrix: M g has the node's mass share (row sum) times g.
  for (size_t i = 0; i < b.f_ext.size(); ++i) b.f_ext[i] = b.fem.node_mass[i] * settings_.gravity + b.node_forces[i];
}

void World::assemble_elements(Body& b, double h, bool damping) const {
  const double beta = damping ? b.settings.rayleigh_beta : 0.0;
  const double alpha = damping ? b.settings.rayleigh_alpha : 0.0;
  const Body::MatrixKey key{h, alpha, beta};
  // A linear body keeps A while h and the damping stay: only its forces are recomputed.
  const bool rebuild = b.settings.corotational || !b.matrix_current || !(key == b.matrix_key);
  const std::vector<Mat3>* R = b.settings.corotational ? &b.R : nullptr;
  if (rebuild) set_scaled_mass(b.fem, 1.0, b.A);
  assemble_elastic(b.fem, b.x, R, h * h + h * beta, rebuild ? &b.A : nullptr, b.f_int);
  if (rebuild) {
    b.matrix_key = key;
    b.matrix_current = !b.settings.corotational;
    b.factor_current = false;
  }
  b.matrix_rebuilt = rebuild;
}

void World::add_damping(Body& b, double h) const {
  // C = alpha M + beta K: beta K is folded into the stiffness scale above; alpha M here.
  if (b.matrix_rebuilt) add_scaled_mass(b.fem, h * b.settings.rayleigh_alpha, b.A);
}

void World::build_projection(Body& b) const {
  b.projection.reset(b.fem.node_count());
  lpcs_.for_each([&](Id, const Lpc& c) {
    if (&bodies_.get(c.body, "body") != &b) return;
    for (int32_t node : c.nodes) b.projection.constrain(node, c.constrained, c.velocity);
  });
}

void World::solve_velocities(Body& b, double h) {
  // b = M v + h (f_int + f_ext)
  mass_multiply(b.fem, b.v, b.b);
  const bool loads = needs_loads(b);
  for (size_t i = 0; i < b.b.size(); ++i) b.b[i] += h * (loads ? b.f_int[i] + b.f_ext[i] : b.f_int[i]);

  const ProjectedSystem sys{b.fem.pattern, b.A, b.projection};
  SolveReport report;
  if (settings_.solver == SolverKind::Direct) {
    if (!b.direct.analyzed()) b.direct.analyze(b.fem.pattern);
    if (!b.factor_current || b.factored_lpc_version != b.lpc_version) {
      b.direct.factorize(sys);
      b.factor_current = true;
      b.factored_lpc_version = b.lpc_version;
    }
    report = b.direct.solve(sys, b.b, b.v_next);
  } else {
    b.v_next = b.v;  // warm start from the last velocity
    report = solve_pcg(sys, b.b, b.v_next, settings_.tolerance, settings_.max_iterations, b.pcg);
  }
  stats_.solver_iterations += report.iterations;
  stats_.solver_residual = std::max(stats_.solver_residual, report.residual);
  stats_.converged = stats_.converged && report.converged;
}

void World::commit() {
  // All or nothing: a non-finite result anywhere keeps every body's old state.
  bodies_.for_each([&](Id, Body& b) {
    if (b.is_dynamic() && !(flat(b.v_next).allFinite() && flat(b.x_next).allFinite()))
      fail(Errc::Numerical, b.name + ": the step produced non-finite velocities or positions; the step was undone");
  });
  bodies_.for_each([&](Id, Body& b) {
    if (!b.is_dynamic()) return;
    std::swap(b.x, b.x_next);
    std::swap(b.v, b.v_next);
  });
}

}  // namespace mica
