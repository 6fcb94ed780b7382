// The step: one linearised backward-Euler step at velocity level, per body
//   A v+ = b,  A = M + h C + h^2 K,  b = M v + h (f_int(x) + f_ext),  x+ = x + h v+,
// under the projection constraints (I - S) v+ = z. Each stage runs only when the plan holds it.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "collision/contact_curvature.hpp"
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
  tools_.for_each([&](Id, const Tool&) { p.collide = p.solve; });
  // Two bodies (at least one dynamic) may touch.
  int32_t bodies = 0;
  bodies_.for_each([&](Id, const Body&) { ++bodies; });
  if (settings_.body_contact && bodies > 1) p.collide = p.collide || p.solve;
  if (all) {
    p.constraints = p.constraints || p.solve;
    p.collide = p.collide || p.solve;
  }
  p.forces = p.collide || p.constraints;
  return p;
}

bool World::needs_loads(const Body& b) const {
  return settings_.plan_all_stages || !settings_.gravity.isZero(0) || b.has_node_forces;
}

bool World::needs_damping(const Body& b) const { return settings_.plan_all_stages || b.has_damping(); }

void World::step(double h) {
  if (!(h >= kMinTimeStep && h <= 1)) {
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", h);
    fail(Errc::InvalidArgument, "the time step must be in [1e-9, 1] s, got " + std::string(text));
  }
  save_undo();  // a failed step leaves the world as it was (undo.cpp)
  try {
    advance(h);
  } catch (...) {
    undo();
    throw;
  }
  bodies_.for_each([&](Id, Body& b) { b.factor.commit(); });
}

void World::advance(double h) {
  const auto start = step_start_ = std::chrono::steady_clock::now();
  const Plan plan = this->plan();
  std::vector<Body*>& dynamic = dynamic_;
  dynamic.clear();
  bodies_.for_each([&](Id, Body& b) {
    if (b.is_dynamic()) dynamic.push_back(&b);
  });
  stats_.solver_iterations = 0;
  stats_.solver_residual = 0;
  stats_.converged = true;
  stats_.out_of_time = false;

  follow_devices();
  StageRunner stage(stats_);
  stage.run(Stage::Collide, plan.collide, [&] { collide(dynamic, h); });
  if (!plan.collide) {  // nothing to collide: drop last step's contacts and tool pointers (a tool may be gone)
    contacts_.clear();
    step_tools_.clear();
  }
  rows_.clear();
  lambda_.clear();
  stage.run(Stage::Loads, plan.loads, [&] {
    for (Body* b : dynamic)
      if (needs_loads(*b)) apply_loads(*b);
  });
  stage.run(Stage::Rotations, plan.rotations, [&] {
    for (Body* b : dynamic)
      if (b->settings.corotational) start_rotations(*b);
  });
  stage.run(Stage::Elements, plan.elements, [&] {
    for (Body* b : dynamic) assemble_elements(*b, h, needs_damping(*b));
  });
  stage.run(Stage::Damping, plan.damping, [&] {
    for (Body* b : dynamic)
      if (needs_damping(*b)) add_damping(*b, h);
  });
  stage.run(Stage::Constraints, plan.constraints, [&] {
    for (Body* b : dynamic) build_projection(*b, h);
  });
  const std::function<void()> solve = [&] {
    if (settings_.solver == SolverKind::Mica) {
      solve_mica(dynamic, h);
    } else if (!contacts_.empty()) {
      solve_delassus(dynamic, h);
    } else {
      for (Body* b : dynamic) solve_velocities(*b, h);
    }
  };
  stage.run(Stage::Solve, plan.solve, solve);
  if (plan.rotations && plan.solve) relinearise(dynamic, h, stage, solve);
  stage.run(Stage::Integrate, plan.integrate, [&] {
    for (Body* b : dynamic)
      for (size_t i = 0; i < b->x.size(); ++i) b->x_next[i] = b->x[i] + h * b->v_next[i];
  });
  check_finite(dynamic);  // throws before anything observable has changed
  stage.run(Stage::Forces, plan.forces, [&] { compute_forces(dynamic, h); });
  check_forces();
  commit(dynamic);
  publish_force_models();
  stats_.step_count += 1;
  stats_.ms_last_step = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void World::follow_devices() {
  // Each device's newest pose moves its tool before the step (the servo thread wrote it).
  devices_.for_each([&](Id, DeviceLink& link) {
    ScenePose pose;
    // (The servo path publishes only finite unit poses; checked again: a tool never gets NaN.)
    if (link.settings().tool && link.latest_pose(pose) && pose.position.allFinite() &&
        pose.orientation.coeffs().allFinite() && std::fabs(pose.orientation.norm() - 1) < 1e-6) {
      Tool& t = tool(link.settings().tool);
      t.position = pose.position;
      t.orientation = pose.orientation;
    }
  });
}

void World::publish_force_models() {
  devices_.for_each([&](Id, DeviceLink& link) {
    ForceModel model;
    model.step = stats_.step_count;
    if (const Tool* t = link.settings().tool ? tools_.find(link.settings().tool) : nullptr) {
      model.f0 = t->force;
      model.x0 = t->position;
      model.in_contact = t->contact_count > 0;
      // The device can render only so stiff a spring: cap the model's stiffness at its nominal one.
      const double k = t->stiffness.norm(), k_max = link.info().nominal_stiffness;
      model.H = k > k_max ? Mat3(t->stiffness * (k_max / k)) : t->stiffness;
    }
    link.publish(model);
  });
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
  if (pool_ && !b.element_colours.empty()) {
    if (rebuild) set_scaled_mass(b.fem, 1.0, b.A, *pool_);
    assemble_elastic(b.fem, b.x, R, h * h + h * beta, rebuild ? &b.A : nullptr, b.f_int, b.element_colours, *pool_);
  } else {
    if (rebuild) set_scaled_mass(b.fem, 1.0, b.A);
    assemble_elastic(b.fem, b.x, R, h * h + h * beta, rebuild ? &b.A : nullptr, b.f_int);
  }
  if (rebuild) {
    b.matrix_key = key;
    b.matrix_current = !b.settings.corotational;
    b.factor_current = false;
  }
  b.matrix_rebuilt = rebuild;
  add_contact_stiffness(b, h);
}

void World::add_contact_stiffness(Body& b, double h) const {
  // h^2 K_c with K_c = F (-H)+ per contact of a rounded tool on a triangle, F the contact's force
  // in the last step (this step's force is the unknown: the lag keeps the system linear).
  const auto it = std::find(dynamic_.begin(), dynamic_.end(), &b);
  if (it == dynamic_.end()) return;
  const int32_t index = int32_t(it - dynamic_.begin());
  thread_local ToolCore core;  // kept: a step allocates nothing here
  int32_t core_of = -1;
  for (const Contact& c : contacts_) {
    if (c.tool < 0 || (c.core_corner < 0 && c.core_edge < 0) || c.a.body != index) continue;
    const auto last = warm_start_.find(ContactRows::normal_row_key(c.key));
    if (last == warm_start_.end() || !(last->second > 0)) continue;
    if (core_of != c.tool) tool_core(*step_tools_[size_t(c.tool)], core);
    core_of = c.tool;
    const Tri& t = b.surface[size_t(c.triangle)];
    Mat9 K;
    if (!contact_curvature(core, c, t, b.x, K)) continue;
    K *= h * last->second;  // h^2 F
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) b.A[size_t(b.fem.pattern.find(t[r], t[s]))] += K.block<3, 3>(3 * r, 3 * s);
    // A linear body keeps A between steps: this one is not its plain matrix any more.
    b.matrix_current = false;
    b.factor_current = false;
  }
}

void World::add_damping(Body& b, double h) const {
  // C = alpha M + beta K: beta K is folded into the stiffness scale above; alpha M here.
  if (b.matrix_rebuilt) add_scaled_mass(b.fem, h * b.settings.rayleigh_alpha, b.A);
}

void World::build_projection(Body& b, double h) const {
  b.projection.reset(b.fem.node_count());
  lpcs_.for_each([&](Id, const Lpc& c) {
    if (&bodies_.get(c.body, "body") != &b) return;
    if (!c.handle) {
      for (int32_t node : c.nodes) b.projection.constrain(node, c.constrained, c.velocity);
      return;
    }
    // Dragging: each node gets the velocity that brings it to its target in this step.
    const Handle& hd = *c.handle;
    const Tool* tool = hd.tool ? tools_.find(hd.tool) : nullptr;
    const Vec3& p = tool ? tool->position : hd.position;
    const Eigen::Quaterniond& q = tool ? tool->orientation : hd.orientation;
    for (size_t k = 0; k < c.nodes.size(); ++k) {
      const Vec3 target = p + q * hd.offsets[k];
      b.projection.constrain(c.nodes[k], c.constrained, (target - b.x[c.nodes[k]]) / h);
    }
  });
}

void World::form_rhs(Body& b, double h) const {
  // b = M v + h (f_int + f_ext)
  mass_multiply(b.fem, b.v, b.b);
  const bool loads = needs_loads(b);
  for (size_t i = 0; i < b.b.size(); ++i) b.b[i] += h * (loads ? b.f_int[i] + b.f_ext[i] : b.f_int[i]);
}

void World::collide(const std::vector<Body*>& dynamic, double h) {
  contacts_.clear();
  step_tools_.clear();
  // Tool velocities from the pose change the host made since the last step.
  tools_.for_each([&](Id, Tool& t) {
    t.velocity = (t.position - t.previous_position) / h;
    const Eigen::AngleAxisd turn(t.orientation * t.previous_orientation.inverse());
    t.angular_velocity = turn.axis() * (turn.angle() > M_PI ? turn.angle() - 2 * M_PI : turn.angle()) / h;
  });
  // Every body's surface as collision sees it; dynamic bodies' trees follow their nodes.
  views_.clear();
  bodies_.for_each([&](Id id, Body& b) {
    const auto it = std::find(dynamic.begin(), dynamic.end(), &b);
    const int32_t index = it == dynamic.end() ? -1 : int32_t(it - dynamic.begin());
    double speed = 0;
    if (index >= 0) {
      b.bvh.refit(b.x);
      b.pseudo_normals.update(b.x, b.surface);
      for (int32_t i : b.surface_node_list) speed = std::max(speed, b.v[i].norm());
    }
    views_.push_back(SurfaceView{index, id, &b.x, &b.surface, &b.surface_node_list, &b.bvh, &b.pseudo_normals,
                                 b.surface_edge, h * speed});
  });
  tools_.for_each([&](Id tool_id, Tool& t) {
    step_tools_.push_back(&t);
    for (const SurfaceView& v : views_)
      if (v.index >= 0) collide_tool(t, int32_t(step_tools_.size() - 1), tool_id, v, h, contacts_);
  });
  if (!settings_.body_contact) return;
  for (const SurfaceView& a : views_)
    for (const SurfaceView& b : views_)
      if (a.index >= 0 && &a != &b && (b.index < 0 || bounds_overlap(a, b)))
        collide_bodies(a, b, settings_.body_margin, settings_.body_friction, contacts_);
}

bool World::bounds_overlap(const SurfaceView& a, const SurfaceView& b) const {
  if (a.bvh->empty() || b.bvh->empty()) return false;  // no surface (validate_topology refuses one): no contact
  const double reach = std::max(settings_.body_margin + a.travel + b.travel, b.depth);
  return a.bvh->bounds().inflated(reach).overlaps(b.bvh->bounds());
}

void World::solve_mica(const std::vector<Body*>& dynamic, double h) {
  mica_bodies_.resize(dynamic.size());
  for (size_t k = 0; k < dynamic.size(); ++k) {
    Body& b = *dynamic[k];
    form_rhs(b, h);
    // The warm start: the last step's velocities (MICA's iterate carries its information in v:
    // one PGS sweep makes an isolated row's impulse a function of v alone).
    if (settings_.warm_start) b.v_next = b.v;
    else for (Vec3& v : b.v_next) v.setZero();
    mica_bodies_[k].colours = pool_ && !b.node_colours.empty() ? &b.node_colours : nullptr;
    mica_bodies_[k].pattern = &b.fem.pattern;
    mica_bodies_[k].A = &b.A;
    mica_bodies_[k].b = &b.b;
    mica_bodies_[k].projection = &b.projection;
    mica_bodies_[k].v = &b.v_next;
    mica_bodies_[k].node_mass = &b.fem.node_mass;
  }
  // Warm start the impulses of contact rows that persist from the last step.
  rows_.build(contacts_, h, settings_.max_recovery_speed);
  lambda_.assign(rows_.size(), 0.0);
  for (size_t r = 0; settings_.warm_start && r < rows_.size(); ++r) {
    const auto it = warm_start_.find(rows_.key[r]);
    if (it != warm_start_.end()) lambda_[r] = it->second;
  }
  MicaSettings ms;
  ms.pool = pool_.get();
  ms.tolerance = settings_.tolerance;
  ms.max_iterations = settings_.max_iterations;
  ms.pgs_sweeps = settings_.pgs_sweeps;
  ms.paper_norm = settings_.paper_norm;
  ms.relaxation = settings_.relaxation;
  ms.refactor_after = settings_.refactor_after;
  if (settings_.time_budget_ms > 0)  // what the stages before the solve left of the step's budget
    ms.time_budget_ms = std::max(1e-6, settings_.time_budget_ms - std::chrono::duration<double, std::milli>(
                                                                       std::chrono::steady_clock::now() - step_start_)
                                                                       .count());
  if (settings_.mica_sweep == MicaSweep::Factored) {
    factored_bodies_.resize(dynamic.size());
    for (size_t k = 0; k < dynamic.size(); ++k) {
      Body& b = *dynamic[k];
      const bool damped = needs_damping(b);
      const std::vector<Mat3>* rotation = nullptr;
      if (b.settings.corotational) {
        compute_node_rotations(b.fem, b.R, b.node_rotation);
        rotation = &b.node_rotation;
      }
      const LaggedFactor::Key key{h, damped ? b.settings.rayleigh_alpha : 0.0,
                                  damped ? b.settings.rayleigh_beta : 0.0, b.lpc_version};
      b.factor.update(b.fem, key, b.A, b.projection, rotation, rotation ? settings_.refactor_interval : 0);
      factored_bodies_[k] = {&b.factor, rotation};
    }
    record(factored_mica_.solve(mica_bodies_, factored_bodies_, rows_, ms, lambda_));
    row_diagonal_ = factored_mica_.row_diagonal();
  } else {
    record(mica_.solve(mica_bodies_, rows_, ms, lambda_));
    row_diagonal_ = mica_.row_diagonal();
  }
  for (size_t k = 0; k < dynamic.size(); ++k) std::swap(dynamic[k]->contact_impulse, mica_bodies_[k].contact_impulse);
}

void World::solve_delassus(const std::vector<Body*>& dynamic, double h) {
  exact_bodies_.resize(dynamic.size());
  for (size_t k = 0; k < dynamic.size(); ++k) {
    Body& b = *dynamic[k];
    form_rhs(b, h);
    b.v_next = b.v;  // the warm start of an iterative solve
    exact_bodies_[k] = ExactBody{&b.fem.pattern, &b.A, &b.b, &b.projection, &linear_solver(b), &b.v_next, {}};
  }
  rows_.build(contacts_, h, settings_.max_recovery_speed);
  if (rows_.size() > kExactRowsWarning && !warned_exact_rows_ && settings_.log) {
    warned_exact_rows_ = true;  // once per world
    settings_.log(LogLevel::Warning,
                  std::to_string(rows_.size()) + " contact rows in one step: the exact solvers (DIRECT, PCG) form a dense "
                  "Delassus matrix with one linear solve per row, which takes seconds above some hundred rows "
                  "(docs/solvers.md); MICA_SOLVER_MICA scales to such contact sets");
  }
  // The sweeps (friction, or a degenerate frictionless problem) start from the last step's
  // impulses and stop at the time budget.
  exact_warm_start_.assign(rows_.size(), 0.0);
  for (size_t r = 0; settings_.warm_start && r < rows_.size(); ++r) {
    const auto it = warm_start_.find(rows_.key[r]);
    if (it != warm_start_.end()) exact_warm_start_[r] = it->second;
  }
  ExactContactSettings es;
  es.warm_start = &exact_warm_start_;
  es.deadline = deadline();
  record(solve_contact_delassus(exact_bodies_, rows_, lambda_, row_diagonal_, es));
  for (size_t k = 0; k < dynamic.size(); ++k) std::swap(dynamic[k]->contact_impulse, exact_bodies_[k].contact_impulse);
}

std::optional<std::chrono::steady_clock::time_point> World::deadline() const {
  if (!(settings_.time_budget_ms > 0)) return std::nullopt;
  return step_start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           std::chrono::duration<double, std::milli>(settings_.time_budget_ms));
}

LinearSolver& World::linear_solver(Body& b) {
  if (settings_.solver == SolverKind::Pcg) {
    b.pcg.configure(settings_.tolerance, settings_.max_iterations, deadline());
    return b.pcg;
  }
  // CHOLMOD: analysed once; factored when A or the constraint set changed (a linear body with
  // fixed constraints keeps its factor).
  if (!b.direct.analyzed()) b.direct.analyze(b.fem.pattern);
  if (!b.factor_current || b.factored_lpc_version != b.lpc_version) {
    b.direct.factorize(ProjectedSystem{b.fem.pattern, b.A, b.projection});
    b.factor_current = true;
    b.factored_lpc_version = b.lpc_version;
  }
  return b.direct;
}

void World::compute_forces(const std::vector<Body*>& dynamic, double h) {
  // Tools: the force the tissue puts on the tool is -sum n lambda / h.
  for (Tool* t : step_tools_) {
    t->force.setZero();
    t->torque.setZero();
    t->contact_count = 0;
    t->stiffness.setZero();
  }
  for (size_t r = 0; r < rows_.size(); ++r) {
    const Contact& c = contacts_[rows_.contact[r]];
    if (c.tool < 0) continue;
    Tool& t = *step_tools_[c.tool];
    const Vec3 f = -rows_.direction[r] * lambda_[r] / h;
    t.force += f;
    t.torque += (c.point - t.position).cross(f);
    if (rows_.normal_of[r] < 0 && lambda_[r] > 0) {
      t.contact_count += 1;
      // Around the pose it used, pushing the tool in by dx along n raises this row's impulse by
      // n.dx / (h W_rr): the force changes by -n n^T dx / (h^2 W_rr).
      if (row_diagonal_.size() == rows_.size() && row_diagonal_[r] > 0)
        t.stiffness -= rows_.direction[r] * rows_.direction[r].transpose() / (h * h * row_diagonal_[r]);
    }
  }
  // Constraints: the impulse r = (I - S)(A v - b - G^T lambda) holds the body; whoever holds
  // the constraint (the user's hand) feels the opposite force, -r / h.
  lpcs_.for_each([&](Id, Lpc& c) {
    Body& b = bodies_.get(c.body, "body");
    c.reaction.setZero();
    if (std::find(dynamic.begin(), dynamic.end(), &b) == dynamic.end()) return;
    for (int32_t i : c.nodes) {
      Vec3 Av = Vec3::Zero();
      for (int32_t k = b.fem.pattern.row_start[i]; k < b.fem.pattern.row_start[i + 1]; ++k)
        Av += b.A[k] * b.v_next[b.fem.pattern.col[k]];
      c.reaction -= c.constrained * (Av - b.b[i] - b.contact_impulse[i]) / h;
    }
  });
}

void World::solve_velocities(Body& b, double h) {
  form_rhs(b, h);

  b.v_next = b.v;  // the warm start of an iterative solve
  for (Vec3& f : b.contact_impulse) f.setZero();  // no contact rows this step: no stale impulse in the reactions
  record(linear_solver(b).solve(ProjectedSystem{b.fem.pattern, b.A, b.projection}, b.b, b.v_next));
}

void World::record(const SolveReport& report) {
  stats_.solver_iterations += report.iterations;
  // A NaN residual must show, not vanish in a max.
  if (!(report.residual <= stats_.solver_residual)) stats_.solver_residual = report.residual;
  stats_.converged = stats_.converged && report.converged;
  stats_.out_of_time = stats_.out_of_time || report.out_of_time;
}

void World::check_finite(const std::vector<Body*>& dynamic) const {
  for (const Body* b : dynamic)
    if (!(flat(b->v_next).allFinite() && flat(b->x_next).allFinite()))
      fail(Errc::Numerical, b->name + ": the step produced non-finite velocities or positions; the step was undone");
  for (double l : lambda_)
    if (!std::isfinite(l)) fail(Errc::Numerical, "a contact impulse is not finite; the step was undone");
}

void World::check_forces() const {
  tools_.for_each([&](Id, const Tool& t) {
    if (!(t.force.allFinite() && t.torque.allFinite() && t.stiffness.allFinite()))
      fail(Errc::Numerical, "a tool force is not finite (the time step is too small, or the contact too stiff, "
                            "for double precision); the step was undone");
  });
  lpcs_.for_each([&](Id, const Lpc& c) {
    if (!c.reaction.allFinite())
      fail(Errc::Numerical, "a constraint reaction is not finite (the time step is too small for double "
                            "precision); the step was undone");
  });
}

void World::commit(const std::vector<Body*>& dynamic) {
  for (Body* b : dynamic) {
    std::swap(b->x, b->x_next);
    std::swap(b->v, b->v_next);
  }
  warm_start_.clear();
  for (size_t r = 0; r < rows_.size(); ++r) warm_start_[rows_.key[r]] = lambda_[r];
  tools_.for_each([&](Id, Tool& t) {
    t.previous_position = t.position;
    t.previous_orientation = t.orientation;
  });
}

}  // namespace mica
