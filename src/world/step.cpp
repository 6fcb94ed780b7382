// SPDX-License-Identifier: Apache-2.0
// The step: one linearised backward-Euler step at velocity level, per body
//   A v+ = b,  A = M + h C + h^2 K,  b = M v + h (f_int(x) + f_ext),  x+ = x + h v+,
// under the projection constraints (I - S) v+ = z. Each stage runs only when the plan holds it.
// Tested as a whole by tests/world/test_plan.cpp (the stages a scene calls for) and
// tests/capi/test_world_state.c (the step as a transaction, for every solver).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "collision/closest_point.hpp"
#include "collision/contact_curvature.hpp"
#include "core/assert.hpp"
#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

// The Moore-Penrose inverse of a symmetric positive semidefinite 3x3 (a sum of projectors).
Mat3 pseudo_inverse(const Mat3& m) {
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(m);
  Vec3 inverse = Vec3::Zero();
  for (int k = 0; k < 3; ++k)
    if (eig.eigenvalues()[k] > 1e-9 * eig.eigenvalues().cwiseAbs().maxCoeff()) inverse[k] = 1 / eig.eigenvalues()[k];
  return eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace

Plan World::plan() const {
  Plan p;
  const bool all = settings_.plan_all_stages;
  bodies_.for_each([&](Id, const Body& b) {
    if (!b.is_dynamic()) return;
    p.elements = p.solve = p.integrate = true;
    p.loads = p.loads || needs_loads(b);
    p.rotations = p.rotations || b.settings.corotational();
    p.newton = p.newton || b.settings.corotational() || b.settings.neo_hookean();
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
  // The step writes into its own buffers until commit: a failed one puts back only the poses it
  // took from the devices, and the solver's schedules (undo.cpp).
  save_undo();
  try {
    advance(h);
  } catch (...) {
    undo();
    if (recorder_) recorder_->write(RecordKind::Step, h, adopted_, false, uint64_t(0));
    throw;
  }
  if (recorder_) recorder_->write(RecordKind::Step, h, adopted_, true, fingerprint());
}

void World::step_replayed(double h, const std::vector<AdoptedPose>& poses) {
  replayed_ = &poses;
  try {
    step(h);
  } catch (...) {
    replayed_ = nullptr;
    throw;
  }
  replayed_ = nullptr;
}

void World::prepare_step(double h) {
  StepContext& ctx = step_;  // its lists keep their capacity from step to step
  ctx.start = StepContext::Clock::now();
  ctx.deadline.reset();
  constexpr double kNoBudgetAboveMs = 86400e3;  // a budget beyond a day is no budget (nor a clock overflow)
  if (settings_.time_budget_ms > 0 && settings_.time_budget_ms <= kNoBudgetAboveMs)
    ctx.deadline = ctx.start + std::chrono::duration_cast<StepContext::Clock::duration>(
                                   std::chrono::duration<double, std::milli>(settings_.time_budget_ms));
  ctx.pool = pool_.get();
  ctx.h = h;
  ctx.plan = plan();
  ctx.dynamic.clear();
  ctx.tools.clear();
  next_.bodies.clear();
  next_.tools.clear();
  next_.contacts.clear();
  next_.rows.clear();
  next_.lambda.clear();
  bodies_.for_each([&](Id id, Body& b) {
    b.step_index = b.is_dynamic() ? int32_t(ctx.dynamic.size()) : -1;
    if (!b.is_dynamic()) return;
    if (b.settings.neo_hookean()) {
      // The first Newton iterate is the explicit predictor v: the step linearises at x + h v.
      b.relin.v_lin = b.v;
      for (size_t i = 0; i < b.x.size(); ++i) b.relin.x_lin[i] = b.x[i] + h * b.v[i];
    }
    ctx.dynamic.push_back(&b);
    next_.bodies.push_back(id);
  });
  next_.stats = last_.stats;
  next_.stats.solver_iterations = 0;
  next_.stats.solver_solves = 0;
  next_.stats.solver_residual = 0;
  next_.stats.converged = true;
  next_.stats.out_of_time = false;
  next_.debt = last_.debt;
}

void World::advance(double h) {
  prepare_step(h);
  StepContext& ctx = step_;
  const Plan& plan = ctx.plan;
  WorldStats& stats = next_.stats;

  follow_devices();
  StageRunner stage(stats);
  stage.run(Stage::Collide, plan.collide, [&] { collide(ctx); });
  next_.curvature_impulse.assign(next_.contacts.size(), Vec3::Zero());  // compute_forces fills the rounded tools'
  stage.run(Stage::Loads, plan.loads, [&] {
    for (Body* b : ctx.dynamic)
      if (needs_loads(*b)) apply_loads(*b);
  });
  stage.run(Stage::Rotations, plan.rotations, [&] {
    for (Body* b : ctx.dynamic)
      if (b->settings.corotational()) start_rotations(ctx, *b);
  });
  stage.run(Stage::Elements, plan.elements, [&] {
    for (Body* b : ctx.dynamic) assemble_elements(ctx, *b);
  });
  stage.run(Stage::Damping, plan.damping, [&] {
    for (Body* b : ctx.dynamic)
      if (needs_damping(*b)) add_damping(ctx, *b);
  });
  stage.run(Stage::Constraints, plan.constraints, [&] {
    for (Body* b : ctx.dynamic) build_projection(ctx, *b);
  });
  const int64_t factored_before = factorizations(ctx), waited_before = factor_waits(ctx);
  stage.run(Stage::Solve, plan.solve, [&] { solve(ctx); });
  if (plan.newton && plan.solve) relinearise(ctx, stage);
  stats.factorizations = int32_t(factorizations(ctx) - factored_before);
  stats.factor_waits = uint8_t(std::min<int64_t>(factor_waits(ctx) - waited_before, 255));
  stage.run(Stage::Integrate, plan.integrate, [&] {
    for (Body* b : ctx.dynamic)
      for (size_t i = 0; i < b->x.size(); ++i) b->x_next[i] = b->x[i] + h * b->v_next[i];
  });
  check_finite(ctx);
  stage.run(Stage::Forces, plan.forces, [&] { compute_forces(ctx); });
  check_forces();
  stats.step_count += 1;
  stats.ms_last_step = std::chrono::duration<double, std::milli>(StepContext::Clock::now() - ctx.start).count();
  commit(ctx);  // nothing throws from here on
  publish_force_models();
  cut_with_blades(ctx);
}

void World::follow_devices() {
  // A tool, or a grasp's handle, takes the pose (the handle only while it has one: a handle the
  // host dropped with mica_lpc_set_velocity is not brought back).
  auto adopt = [&](Id target, const Vec3& position, const Eigen::Quaterniond& orientation) {
    if (id_kind(target) == IdKind::Tool) {
      Tool& t = tool(target);
      t.position = position;
      t.orientation = orientation;
    } else if (Lpc* c = lpcs_.find(target); c && c->handle) {
      c->handle->position = position;
      c->handle->orientation = orientation;
    }
  };
  adopted_.clear();  // keeps its capacity
  if (replayed_) {  // a replay: the recorded poses stand in for the devices
    for (const AdoptedPose& p : *replayed_) adopt(p.target, p.position, p.orientation);
    adopted_ = *replayed_;
    return;
  }
  // Each device's newest pose moves its tool or its grasp's handle before the step (the servo
  // thread wrote it).
  devices_.for_each([&](Id, DeviceLink& link) {
    ScenePose pose;
    const Id target = link.settings().tool ? link.settings().tool : link.settings().lpc;
    // (The servo path publishes only finite unit poses; checked again: a tool never gets NaN. Not
    // require_rotation's check: a device's pose is taken as it is, not normalised as a host's is.)
    if (!target || !link.latest_pose(pose) || !pose.position.allFinite() || !pose.orientation.coeffs().allFinite() ||
        !(std::fabs(pose.orientation.norm() - 1) < 1e-6))
      return;
    adopt(target, pose.position, pose.orientation);
    if (recorder_) adopted_.push_back(AdoptedPose{target, pose.position, pose.orientation});
  });
}

void World::publish_force_models() {
  devices_.for_each([&](Id, DeviceLink& link) {
    ForceModel model;
    if (const Tool* t = link.settings().tool ? tools_.find(link.settings().tool) : nullptr) {
      model.f0 = t->force;
      model.x0 = t->position;
      model.in_contact = t->contact_count > 0;
      // The device can render only so stiff a spring: cap the model's stiffness at its nominal one.
      const double k = t->stiffness.norm(), k_max = link.info().nominal_stiffness;
      model.H = k > k_max ? Mat3(t->stiffness * (k_max / k)) : t->stiffness;
    } else if (const Lpc* c = link.settings().lpc ? lpcs_.find(link.settings().lpc) : nullptr) {
      model = grasp_force_model(link.last_published(), c->reaction,
                                c->handle ? c->handle->position : link.last_published().x0, link.info().nominal_stiffness);
    }
    model.step = last_.stats.step_count;
    link.publish(model);
  });
}

void World::apply_loads(Body& b) const {
  // Gravity through the mass matrix: M g has the node's mass share (row sum) times g.
  for (size_t i = 0; i < b.f_ext.size(); ++i) b.f_ext[i] = b.fem.node_mass[i] * settings_.gravity + b.node_forces[i];
}

void World::assemble_elements(const StepContext& ctx, Body& b) const {
  const double h = ctx.h;
  const bool damping = needs_damping(b);
  const double beta = damping ? b.settings.rayleigh_beta : 0.0;
  const double alpha = damping ? b.settings.rayleigh_alpha : 0.0;
  const SystemKey key{h, alpha, beta};
  if (b.settings.neo_hookean()) {
    // The projected Hessian at the linearisation point, the Newton iterate x_lin = x + h v_lin, with
    // f_int = f(x_lin) + h H v_lin (relinearise.cpp). Its SVDs give the rotations the factored
    // sweep warps its lagged factor with.
    set_scaled_mass(b.fem, 1.0, b.A, ctx.pool);
    NeoHookeanAssembly what;
    what.k_scale = h * h + h * beta;
    what.K = &b.A;
    what.R = &b.own_R;
    what.lin = &b.neo_hookean;
    what.v_lin = &b.relin.v_lin;
    what.h = h;
    assemble_neo_hookean(b.fem, b.relin.x_lin, what, b.f_int, &b.element_colours, ctx.pool);
    b.rotations_in = Body::RotationsIn::Own;
    b.matrix_key = key;
    b.matrix_current = false;
    ++b.matrix_version;
    b.matrix_rebuilt = true;
    add_contact_stiffness(ctx, b);
    return;
  }
  // A linear body keeps A while h and the damping stay: only its forces are recomputed.
  const bool rebuild = b.settings.corotational() || !b.matrix_current || !(key == b.matrix_key);
  const std::vector<Mat3>* R = b.settings.corotational() ? &b.rotations() : nullptr;
  if (rebuild) set_scaled_mass(b.fem, 1.0, b.A, ctx.pool);
  assemble_elastic(b.fem, b.x, R, h * h + h * beta, rebuild ? &b.A : nullptr, b.f_int, &b.element_colours, ctx.pool);
  if (rebuild) {
    b.matrix_key = key;
    b.matrix_current = !b.settings.corotational();
    ++b.matrix_version;
  }
  b.matrix_rebuilt = rebuild;
  add_contact_stiffness(ctx, b);
}

void World::add_contact_stiffness(const StepContext& ctx, Body& b) const {
  // h^2 K_c with K_c = F (-H)+ per contact of a rounded tool on a triangle, F the contact's force
  // in the last step (this step's force is the unknown: the lag keeps the system linear).
  const int32_t index = b.step_index;
  MICA_ASSERT(index >= 0, "the elements stage assembles dynamic bodies only");
  thread_local ToolCore core;  // kept: a step allocates nothing here
  int32_t core_of = -1;
  b.curvature_terms.clear();
  b.curvature_stiffness.clear();
  for (size_t k = 0; k < next_.contacts.size(); ++k) {
    const Contact& c = next_.contacts[k];
    if (c.tool < 0 || (c.core_corner < 0 && c.core_edge < 0) || c.a.body != index) continue;
    const auto last = warm_start_.find(ContactRows::normal_row_key(c.key));
    if (last == warm_start_.end() || !(last->second > 0)) continue;
    if (core_of != c.tool) tool_core(*ctx.tools[size_t(c.tool)], core);
    core_of = c.tool;
    const Tri& t = b.surface[size_t(c.triangle)];
    Mat9 K;
    if (!contact_curvature(core, c, t, b.x, K)) continue;
    K *= ctx.h * last->second;  // h^2 F
    // A rounded core's contact force passes through its core feature's closest point.
    Vec3 core_point;
    if (c.core_corner >= 0) {
      core_point = core.corners[size_t(c.core_corner)];
    } else {
      const auto& e = core.edges[size_t(c.core_edge)];
      const Vec3 &a = core.corners[size_t(e[0])], &b_end = core.corners[size_t(e[1])];
      core_point = a + closest_on_segment(c.point, a, b_end) * (b_end - a);
    }
    b.curvature_terms.push_back({int32_t(k), core_point});
    b.curvature_stiffness.push_back({{t[0], t[1], t[2]}, K});
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) b.A[size_t(b.fem.pattern.find(t[r], t[s]))] += K.block<3, 3>(3 * r, 3 * s);
    // A linear body keeps A between steps: this one is not its plain matrix any more.
    b.matrix_current = false;
    ++b.matrix_version;
  }
}

void World::add_damping(const StepContext& ctx, Body& b) const {
  // C = alpha M + beta K: beta K is folded into the stiffness scale above; alpha M here.
  if (b.matrix_rebuilt) add_scaled_mass(b.fem, ctx.h * b.settings.rayleigh_alpha, b.A);
}

void World::build_projection(const StepContext& ctx, Body& b) const {
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
      b.projection.constrain(c.nodes[k], c.constrained, (target - b.x[c.nodes[k]]) / ctx.h);
    }
  });
}

void World::form_rhs(const StepContext& ctx, Body& b) const {
  // b = M v + h (f_int + f_ext)
  mass_multiply(b.fem, b.v, b.b);
  const bool loads = needs_loads(b);
  for (size_t i = 0; i < b.b.size(); ++i) b.b[i] += ctx.h * (loads ? b.f_int[i] + b.f_ext[i] : b.f_int[i]);
}

void World::collide(StepContext& ctx) {
  const double h = ctx.h;
  // Tool velocities from the pose change the host made since the last step.
  tools_.for_each([&](Id, Tool& t) {
    t.velocity = (t.position - t.previous_position) / h;
    const Eigen::AngleAxisd turn(t.orientation * t.previous_orientation.inverse());
    t.angular_velocity = turn.axis() * (turn.angle() > M_PI ? turn.angle() - 2 * M_PI : turn.angle()) / h;
  });
  // Every body's surface as collision sees it; dynamic bodies' trees follow their nodes.
  std::vector<SurfaceView>& views = ctx.views;
  views.clear();  // keeps its capacity
  bodies_.for_each([&](Id id, Body& b) {
    const int32_t index = b.step_index;
    double speed = 0;
    if (index >= 0) {
      b.bvh.refit(b.x);
      for (int32_t i : b.surface_node_list) speed = std::max(speed, b.v[i].norm());
    }
    views.push_back(SurfaceView{index, id, &b.x, &b.surface, &b.surface_node_list, &b.bvh, &b.pseudo_normals,
                                b.surface_edge, h * speed, index >= 0 ? &b.v : nullptr});
  });
  tools_.for_each([&](Id tool_id, Tool& t) {
    ctx.tools.push_back(&t);
    next_.tools.push_back(tool_id);
    for (const SurfaceView& v : views)
      if (v.index >= 0) collide_tool(t, int32_t(ctx.tools.size() - 1), tool_id, v, h, next_.contacts);
  });
  if (!settings_.body_contact) return;
  for (const SurfaceView& a : views)
    for (const SurfaceView& b : views)
      if (a.index >= 0 && &a != &b && (b.index < 0 || bounds_overlap(a, b)) && !contacts_skipped(a.key, b.key))
        collide_bodies(a, b, settings_.body_margin, settings_.body_friction, next_.contacts);
}

bool World::bounds_overlap(const SurfaceView& a, const SurfaceView& b) const {
  if (a.bvh->empty() || b.bvh->empty()) return false;  // no surface (validate_topology refuses one): no contact
  const double reach = std::max(settings_.body_margin + a.travel + b.travel, b.depth);
  return a.bvh->bounds().inflated(reach).overlaps(b.bvh->bounds());
}

void World::solve(const StepContext& ctx) {
  solver_bodies_.resize(ctx.dynamic.size());
  const bool blades = std::any_of(ctx.tools.begin(), ctx.tools.end(), [](const Tool* t) { return t->blade; });
  for (size_t k = 0; k < ctx.dynamic.size(); ++k) {
    Body& b = *ctx.dynamic[k];
    form_rhs(ctx, b);
    // The warm start, extrapolated from the last two steps (MICA without warm start zeroes it):
    // about one CG iteration in twelve fewer on the nidus scene than starting from v.
    for (size_t i = 0; i < b.v.size(); ++i) b.v_next[i] = 2 * b.v[i] - b.v_previous[i];
    SolverBody& sb = solver_bodies_[k];
    sb.key = b.key;
    sb.fem = &b.fem;
    sb.A = &b.A;
    sb.b = &b.b;
    sb.projection = &b.projection;
    sb.v = &b.v_next;
    sb.contact_impulse = &b.contact_impulse;
    sb.colours = ctx.pool && !b.node_colours.empty() ? &b.node_colours : nullptr;
    // Neo-Hookean bodies too: their rotations warp the factored sweep's lagged factor, and mark A as
    // changing from step to step (its factor is refreshed every refactor_interval solves).
    sb.rotation = b.settings.corotational() || b.settings.neo_hookean() ? &b.rotations() : nullptr;
    sb.extra_stiffness = &b.curvature_stiffness;
    sb.system = b.matrix_key;
    sb.matrix_version = b.matrix_version;
    sb.constraint_version = b.lpc_version;
    sb.may_be_cut = blades || b.topology_version > 0;
  }
  // The impulses of contact rows that persist from the last step are the warm start.
  ContactRows& rows = next_.rows;
  std::vector<double>& lambda = next_.lambda;
  rows.build(next_.contacts, ctx.h, settings_.max_recovery_speed);
  lambda.assign(rows.size(), 0.0);
  for (size_t r = 0; settings_.warm_start && r < rows.size(); ++r) {
    const auto it = warm_start_.find(rows.key[r]);
    if (it != warm_start_.end()) lambda[r] = it->second;
  }
  if (rows.size() > kExactRowsWarning && settings_.solver != SolverKind::Mica && !warned_exact_rows_ && settings_.log) {
    warned_exact_rows_ = true;  // once per world
    settings_.log(LogLevel::Warning,
                  std::to_string(rows.size()) + " contact rows in one step: the exact solvers (DIRECT, PCG) form a dense "
                  "Delassus matrix with one linear solve per row, which takes seconds above some hundred rows "
                  "(docs/solvers.md); MICA_SOLVER_MICA scales to such contact sets");
  }
  try {
    add_to_stats(solver_->solve(ctx, solver_bodies_, rows, lambda));
  } catch (const Error& e) {
    if (e.code() != Errc::Numerical) throw;
    std::string bodies;  // the solve is of every dynamic body at once: name them
    for (const Body* b : ctx.dynamic) bodies += (bodies.empty() ? "" : ", ") + b->name;
    fail(Errc::Numerical, "the velocity solve of " + bodies + " failed: " + e.what() + "; the step was undone");
  }
}

void World::compute_forces(const StepContext& ctx) {
  tool_forces(ctx);
  curvature_forces(ctx);
  constraint_reactions(ctx);
}

void World::tool_forces(const StepContext& ctx) {
  // The force the tissue puts on a tool is -sum n lambda / h.
  const double h = ctx.h;
  const std::vector<double>& row_diagonal = solver_->row_diagonal();
  const ContactRows& rows = next_.rows;
  const std::vector<double>& lambda = next_.lambda;
  MICA_ASSERT(row_diagonal.size() == rows.size(), "the solver reports the compliance of each row it solved");
  for (Tool* t : ctx.tools) t->next = {};
  for (size_t r = 0; r < rows.size(); ++r) {
    const Contact& c = next_.contacts[rows.contact[r]];
    if (c.tool < 0) continue;
    auto& t = ctx.tools[c.tool]->next;
    const Vec3 f = -rows.direction[r] * lambda[r] / h;
    t.force += f;
    t.torque += (c.point - ctx.tools[c.tool]->position).cross(f);
    if (rows.normal_of[r] < 0 && lambda[r] > 0) {
      t.contact_count += 1;
      // Around the pose it used, pushing the tool in by dx along n raises this row's impulse by
      // n.dx / (h W_rr): the force changes by -n n^T dx / (h^2 W_rr).
      if (row_diagonal[r] > 0)
        t.stiffness -= rows.direction[r] * rows.direction[r].transpose() / (h * h * row_diagonal[r]);
    }
  }
}

void World::curvature_forces(const StepContext& ctx) {
  // The curvature terms in A push the triangles' corners by -h^2 F K_c v+ (add_contact_stiffness):
  // a contact force too, which the tool feels the other way round.
  for (Body* b : ctx.dynamic)
    for (size_t k = 0; k < b->curvature_terms.size(); ++k) {
      const Body::CurvatureTerm& term = b->curvature_terms[k];
      const TriangleStiffness& stiffness = b->curvature_stiffness[k];
      Vec3 impulse = Vec3::Zero();
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s)
          impulse -= stiffness.K.block<3, 3>(3 * r, 3 * s) * b->v_next[size_t(stiffness.nodes[s])];
      const Contact& c = next_.contacts[size_t(term.contact)];
      next_.curvature_impulse[size_t(term.contact)] = impulse;
      Tool& t = *ctx.tools[size_t(c.tool)];
      const Vec3 f = -impulse / ctx.h;
      t.next.force += f;
      t.next.torque += (term.core_point - t.position).cross(f);
    }
}

void World::constraint_reactions(const StepContext& ctx) {
  // The impulse r = (I - S)(A v - b - G^T lambda) holds the body; whoever holds the constraint
  // (the user's hand) feels the opposite force, -r / h. A node held by several groups gives each
  // group C_g its share C_g (sum_h C_h)^+ r, so that the shares add up to r (two groups fixing the
  // same node get half each; groups on perpendicular directions, each its own).
  lpcs_.for_each([&](Id, Lpc& c) {
    Body& b = bodies_.get(c.body, "body");
    for (int32_t i : c.nodes) b.constrained_sum[i].setZero();
  });
  lpcs_.for_each([&](Id, Lpc& c) {
    Body& b = bodies_.get(c.body, "body");
    for (int32_t i : c.nodes) b.constrained_sum[i] += c.constrained;
  });
  lpcs_.for_each([&](Id, Lpc& c) {
    Body& b = bodies_.get(c.body, "body");
    c.next_reaction.setZero();
    if (b.step_index < 0) return;
    for (int32_t i : c.nodes) {
      Vec3 Av = Vec3::Zero();
      for (int32_t k = b.fem.pattern.row_start[i]; k < b.fem.pattern.row_start[i + 1]; ++k)
        Av += b.A[k] * b.v_next[b.fem.pattern.col[k]];
      const Vec3 r = Av - b.b[i] - b.contact_impulse[i];
      const Mat3& sum = b.constrained_sum[i];
      const Vec3 share = sum == c.constrained ? Vec3(c.constrained * r) : Vec3(c.constrained * pseudo_inverse(sum) * r);
      c.next_reaction -= share / ctx.h;
    }
  });
}

int64_t World::factorizations(const StepContext& ctx) const {
  int64_t n = 0;
  for (const Body* b : ctx.dynamic) n += solver_->factorizations(b->key);
  return n;
}

int64_t World::factor_waits(const StepContext& ctx) const {
  int64_t n = 0;
  for (const Body* b : ctx.dynamic) n += solver_->factor_waits(b->key);
  return n;
}

void World::add_to_stats(const SolveReport& report) {
  WorldStats& stats = next_.stats;
  stats.solver_iterations += report.iterations;
  stats.solver_solves += std::max(1, report.solves);
  // A NaN residual must show, not vanish in a max.
  if (!(report.residual <= stats.solver_residual)) stats.solver_residual = report.residual;
  stats.converged = stats.converged && report.converged;
  stats.out_of_time = stats.out_of_time || report.out_of_time;
}

void World::check_finite(const StepContext& ctx) const {
  for (const Body* b : ctx.dynamic)
    if (!(flat(b->v_next).allFinite() && flat(b->x_next).allFinite()))
      fail(Errc::Numerical, b->name + ": the step produced non-finite velocities or positions; the step was undone");
  for (double l : next_.lambda)
    if (!std::isfinite(l)) fail(Errc::Numerical, "a contact impulse is not finite; the step was undone");
}

void World::check_forces() const {
  tools_.for_each([&](Id, const Tool& t) {
    if (!(t.next.force.allFinite() && t.next.torque.allFinite() && t.next.stiffness.allFinite()))
      fail(Errc::Numerical, "a tool force is not finite (the time step is too small, or the contact too stiff, "
                            "for double precision); the step was undone");
  });
  lpcs_.for_each([&](Id, const Lpc& c) {
    if (!c.next_reaction.allFinite())
      fail(Errc::Numerical, "a constraint reaction is not finite (the time step is too small for double "
                            "precision); the step was undone");
  });
}

void World::commit(const StepContext& ctx) {
  for (Body* b : ctx.dynamic) {
    std::swap(b->x, b->x_next);
    std::swap(b->v_previous, b->v);  // v_next keeps the old v_previous as scratch
    std::swap(b->v, b->v_next);
    std::swap(b->end, b->next_end);
    if (b->rotations_in == Body::RotationsIn::End) b->rotations_in = Body::RotationsIn::NextEnd;
  }
  std::swap(last_, next_);
  warm_start_.clear();
  for (size_t r = 0; r < last_.rows.size(); ++r) warm_start_[last_.rows.key[r]] = last_.lambda[r];
  tools_.for_each([&](Id, Tool& t) {
    t.previous_position = t.position;
    t.previous_orientation = t.orientation;
  });
  if (ctx.plan.forces) {  // else the last forces stand
    for (Tool* t : ctx.tools) {
      t->force = t->next.force;
      t->torque = t->next.torque;
      t->contact_count = t->next.contact_count;
      t->stiffness = t->next.stiffness;
    }
    lpcs_.for_each([&](Id, Lpc& c) { c.reaction = c.next_reaction; });
  }
  solver_->commit_step();
  if (!overlapping_.empty()) forget_parted_overlaps();  // by the bounds this step's collide refitted
}

}  // namespace mica
