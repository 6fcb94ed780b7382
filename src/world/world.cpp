// SPDX-License-Identifier: Apache-2.0
#include "world/world.hpp"

#include <cmath>

#include "fem/element_colouring.hpp"
#include "world/recording.hpp"
#include "solver/node_colouring.hpp"

namespace mica {

namespace {
void require_finite(const Vec3& v, const std::string& what) {
  if (!v.allFinite()) fail(Errc::InvalidArgument, what + " must be finite");
}

// A rotation as a host gives it: any finite non-zero quaternion (it is normalised).
void require_rotation(const Eigen::Quaterniond& q, const std::string& what) {
  if (!q.coeffs().allFinite() || !(q.norm() > 1e-12))
    fail(Errc::InvalidArgument, what + " must be a finite non-zero quaternion");
}

void require_nodes_of(const Body& b, const std::vector<int32_t>& nodes) {
  for (size_t k = 0; k < nodes.size(); ++k)
    if (nodes[k] < 0 || nodes[k] >= b.fem.node_count())
      fail(Errc::OutOfRange, b.name + ": node index " + std::to_string(nodes[k]) + " at position " +
                                 std::to_string(k) + " is outside 0.." + std::to_string(b.fem.node_count() - 1));
}

// A tool or grasp a device moves outlives the device (destroying it first keeps the device from
// moving what is gone), and the host does not move it behind the device's back.
template <class Devices>
void refuse_if_driven(const Devices& devices, Id target, const char* advice = "destroy the device first") {
  devices.for_each([&](Id, const DeviceLink& link) {
    if (link.settings().lpc == target || link.settings().tool == target)
      fail(Errc::WrongState, std::string("a device drives this ") +
                                 (id_kind(target) == IdKind::Tool ? "tool" : "grasp") + ": " + advice);
  });
}
}  // namespace

void validate(const WorldSettings& s) {
  auto require = [](bool ok, const std::string& message) {
    if (!ok) fail(Errc::InvalidArgument, message);
  };
  require_finite(s.gravity, "gravity");
  require(s.tolerance > 0 && std::isfinite(s.tolerance), "tolerance must be finite and > 0, got " + number_text(s.tolerance));
  require(s.max_iterations >= 1, "max_iterations must be >= 1");
  require(s.pgs_sweeps >= 1, "pgs_sweeps must be >= 1");
  require(s.max_recovery_speed > 0 && std::isfinite(s.max_recovery_speed),
          "max_recovery_speed must be finite and > 0 m/s");
  require(s.relaxation > 0 && s.relaxation < 2, "relaxation must be in (0, 2), got " + std::to_string(s.relaxation));
  require(s.time_budget_ms >= 0 && std::isfinite(s.time_budget_ms),
          "time_budget_ms must be finite and >= 0 (0: no budget)");
  require(s.refactor_interval >= 0, "refactor_interval must be >= 0 (0: no background refresh), got " +
                                        std::to_string(s.refactor_interval));
  require(s.body_margin >= 0 && std::isfinite(s.body_margin), "the body contact margin must be finite and >= 0 m");
  require(s.body_friction >= 0 && std::isfinite(s.body_friction),
          "the body friction coefficient must be finite and >= 0");
  require(s.threads >= 0 && s.threads <= kMaxThreads, "threads must be in 0.." + std::to_string(kMaxThreads) +
                                                          " (0: every CPU), got " + std::to_string(s.threads));
  require(!s.tasks.enqueue == !s.tasks.finish, "a host's job system needs both enqueue and finish");
  require(!s.tasks.enqueue || s.threads >= 1, "threads must be >= 1 on a host's job system (its worker count)");
  require(s.relinearise_tolerance >= 0 && std::isfinite(s.relinearise_tolerance),
          "relinearise_tolerance must be finite and >= 0");
}

World::World(const WorldSettings& settings) : settings_(settings) {
  validate(settings);
  const int32_t threads = ThreadPool::resolve(settings.threads);
  if (threads > 1) pool_ = std::make_unique<ThreadPool>(threads, settings.tasks);
  solver_ = make_velocity_solver(settings.solver, settings.mica_sweep, settings);
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

void World::set_gravity(const Vec3& g) {
  require_finite(g, "gravity");
  settings_.gravity = g;
  if (recorder_) recorder_->write(RecordKind::SetGravity, g);
}

Id World::add_body(const TetMesh& mesh, const BodySettings& settings, const Vec3& translation, const Vec3& velocity) {
  require_finite(translation, "translation");
  require_finite(velocity, "initial velocity");
  const double alpha = settings.rayleigh_alpha, beta = settings.rayleigh_beta;
  if (!(alpha >= 0) || !std::isfinite(alpha)) fail(Errc::InvalidArgument, "rayleigh_alpha must be finite and >= 0");
  if (!(beta >= 0) || !std::isfinite(beta)) fail(Errc::InvalidArgument, "rayleigh_beta must be finite and >= 0");
  TetMesh placed = mesh;  // the rest shape sits where the body is placed
  for (Vec3& p : placed.nodes) p += translation;
  // Named by its id once it has one (messages name what the host holds); until then, while it is made.
  auto body = std::make_unique<Body>(placed, settings, "the new body", uint64_t(bodies_created_));
  if (!settings.is_static)
    for (Vec3List* w : {&body->v, &body->v_previous})
      for (Vec3& u : *w) u = velocity;
  colour_for_threads(*body);
  std::vector<BodyOverlap> overlaps = find_overlaps(*body);  // may throw: nothing changed yet
  overlapping_.reserve(overlapping_.size() + overlaps.size());
  Body& created = *body;
  const Id id = bodies_.insert(std::move(body));
  ++bodies_created_;
  created.name = "body " + SlotMap<Body, IdKind::Body>::hex(id);
  const QualityReport& q = created.fem.quality;
  if (!q.slivers.empty() && settings_.log)
    settings_.log(LogLevel::Warning, created.name + ": " + std::to_string(q.slivers.size()) +
                                         " sliver elements (aspect ratio above 100), the first is tet " +
                                         std::to_string(q.slivers.front()) + "; worst aspect " +
                                         std::to_string(q.worst_aspect) + ". They slow iterative solvers.");
  last_overlaps_ = std::move(overlaps);
  for (const BodyOverlap& o : last_overlaps_) {
    overlapping_.emplace_back(id, o.other);
    if (settings_.log) {
      try {
        settings_.log(LogLevel::Warning, overlap_message(id, o));
      } catch (...) {
        // Out of memory for the message: the body exists, overlaps_at_creation() still says it.
      }
    }
  }
  if (recorder_) recorder_->write(RecordKind::AddBody, mesh, settings, translation, velocity, id);
  return id;
}

void World::colour_for_threads(Body& b) const {
  if (!pool_ || !b.is_dynamic()) return;
  b.element_colours = colour_elements(b.tets, b.fem.node_count(), block_size_for(int32_t(b.tets.size()), 16, 1024));
  b.node_colours = colour_nodes(b.fem.pattern, block_size_for(b.fem.node_count(), 8, 512));
}

void World::remove_body(Id id) {
  body(id);  // throws for a stale id
  std::vector<Id> doomed;
  lpcs_.for_each([&](Id lpc, const Lpc& c) {
    if (c.body == id) doomed.push_back(lpc);
  });
  for (Id lpc : doomed) refuse_if_driven(devices_, lpc);
  for (Id lpc : doomed) lpcs_.erase(lpc);
  solver_->forget(body(id).key);  // its factors (one may be in the making on the body's pattern) first
  bodies_.erase(id);
  if (recorder_) recorder_->write(RecordKind::RemoveBody, id);
}

int64_t World::factorizations(Id id) const { return solver_->factorizations(body(id).key); }

void World::set_node_forces(Id id, const std::vector<int32_t>& nodes, const Vec3List& forces) {
  Body& b = body(id);
  if (nodes.size() != forces.size())  // the C API passes one count for both; a corrupt recording may not
    fail(Errc::InvalidArgument, b.name + ": " + std::to_string(nodes.size()) + " node indices and " +
                                    std::to_string(forces.size()) + " forces");
  require_nodes_of(b, nodes);
  for (size_t k = 0; k < nodes.size(); ++k) require_finite(forces[k], "force " + std::to_string(k));
  for (size_t k = 0; k < nodes.size(); ++k) b.node_forces[nodes[k]] = forces[k];
  b.has_node_forces = false;
  for (const Vec3& f : b.node_forces) b.has_node_forces = b.has_node_forces || !f.isZero(0);
  if (recorder_) recorder_->write(RecordKind::SetNodeForces, id, nodes, forces);
}

void World::set_body_materials(Id id, const std::vector<Material>& materials) {
  Body& b = body(id);
  TetMesh mesh{b.fem.rest, b.tets, b.regions};
  FemModel rebuilt = build_fem_model(mesh, materials, b.settings.mass, b.name);  // may throw: nothing changed yet
  rebuilt.pattern.fill_ordering = b.fem.pattern.fill_ordering;  // a cut body's stays AMD's
  solver_->forget(b.key);  // its factors (one may be in the making on the body's pattern) first
  b.fem = std::move(rebuilt);
  b.matrix_current = false;  // A and everything factored from it belong to the old materials
  ++b.matrix_version;
  b.end.x.clear();  // the end energy cached for the next step is of the old materials
  b.relin.modes.clear();
  if (recorder_) recorder_->write(RecordKind::SetMaterials, id, materials);
}

void World::set_cutting_resistance(Id id, const std::vector<double>& per_tet) {
  Body& b = body(id);
  if (per_tet.size() != b.tets.size())
    fail(Errc::InvalidArgument, std::to_string(per_tet.size()) + " cutting resistances for the " +
                                    std::to_string(b.tets.size()) + " tets of " + b.name);
  for (size_t e = 0; e < per_tet.size(); ++e)
    if (!(per_tet[e] >= 0) || !std::isfinite(per_tet[e]))
      fail(Errc::InvalidArgument, b.name + ": the cutting resistance of tet " + std::to_string(e) + " is " +
                                      number_text(per_tet[e]) + " N/m, must be finite and >= 0");
  b.cutting_resistance = per_tet;
  if (recorder_) recorder_->write(RecordKind::SetCuttingResistance, id, per_tet);
}

void World::set_tool_blade(Id id, bool blade) {
  Tool& t = tools_.get(id, "tool");
  if (blade && t.shape != ToolShape::Capsule) fail(Errc::InvalidArgument, "only a capsule tool can be a blade (its segment is the edge)");
  t.blade = blade;
  if (recorder_) recorder_->write(RecordKind::SetBlade, id, blade);
}

Mat3 constrained_projector(const LpcSpec& spec) {
  auto unit = [](const Vec3& d, const char* what) {
    const double n = d.norm();
    if (!(n > 1e-12) || !std::isfinite(n)) fail(Errc::InvalidArgument, std::string(what) + " must be a finite non-zero vector");
    return Vec3(d / n);
  };
  switch (spec.kind) {
    case LpcKind::Fixed: return Mat3::Identity();
    case LpcKind::Plane: return line_projector(unit(spec.directions[0], "the plane normal"));
    case LpcKind::Line: return Mat3::Identity() - line_projector(unit(spec.directions[0], "the line direction"));
    case LpcKind::TwoDirections: {
      const Vec3 p = unit(spec.directions[0], "direction 0");
      const Vec3 q0 = spec.directions[1] - p * p.dot(spec.directions[1]);  // orthogonalise
      if (!(q0.norm() > 1e-6 * spec.directions[1].norm()))
        fail(Errc::InvalidArgument, "the two constrained directions are parallel");
      return line_projector(p) + line_projector(unit(q0, "direction 1"));
    }
  }
  fail(Errc::InvalidArgument, "unknown constraint kind");
}

Id World::add_lpc(Id body_id, const std::vector<int32_t>& nodes, const LpcSpec& spec) {
  const Id id = insert_lpc(body_id, nodes, spec);
  if (recorder_) recorder_->write(RecordKind::AddLpc, body_id, nodes, spec, id);
  return id;
}

Id World::insert_lpc(Id body_id, const std::vector<int32_t>& nodes, const LpcSpec& spec) {
  Body& b = body(body_id);
  if (nodes.empty()) fail(Errc::InvalidArgument, "a constraint needs at least one node");
  require_nodes_of(b, nodes);
  require_finite(spec.velocity, "the prescribed velocity");
  auto lpc = std::make_unique<Lpc>(Lpc{body_id, nodes, constrained_projector(spec), spec.velocity, nullptr});
  const Id id = lpcs_.insert(std::move(lpc));
  ++b.lpc_version;
  return id;
}

void check_tool_pose(const Vec3& position, const Eigen::Quaterniond& orientation) {
  require_finite(position, "the tool position");
  require_rotation(orientation, "the tool orientation");
}

Id World::add_tool(const Tool& tool) {
  check_tool_pose(tool.position, tool.orientation);
  if (!(tool.margin >= 0 && std::isfinite(tool.margin))) fail(Errc::InvalidArgument, "the contact margin must be finite and >= 0 m");
  if (!(tool.friction >= 0 && std::isfinite(tool.friction))) fail(Errc::InvalidArgument, "the friction coefficient must be finite and >= 0");
  Tool t = tool;
  prepare_tool_shape(t);  // validates the shape's own fields and builds a hull's faces
  t.orientation.normalize();
  t.previous_position = t.position;
  t.previous_orientation = t.orientation;
  const Id id = tools_.insert(std::make_unique<Tool>(t));
  if (recorder_) recorder_->write(RecordKind::AddTool, tool, id);
  warn_if_inside_a_body(id);
  return id;
}

void World::check_device_target(const DeviceSettings& settings) const {
  if (settings.tool && settings.lpc)
    fail(Errc::InvalidArgument, "a device drives a tool or a grasp, not both: set one of tool and lpc to 0");
  if (settings.tool) tool(settings.tool);  // throws for a stale tool id
  if (!settings.lpc) return;
  const Lpc& c = lpc(settings.lpc);  // throws for a stale constraint id
  if (!c.handle)
    fail(Errc::InvalidArgument, "the constraint has no handle for the device to move: make it with a grab (or set its targets)");
  if (c.handle->tool)
    fail(Errc::InvalidArgument, "the grasp's handle follows a tool: drive that tool with the device instead");
}

Id World::add_device(std::unique_ptr<Device> device, const DeviceSettings& settings) {
  check_device_target(settings);
  if (!(settings.scale > 0) || !std::isfinite(settings.scale)) fail(Errc::InvalidArgument, "the workspace scale must be finite and > 0");
  require_finite(settings.offset, "the workspace offset");
  require_rotation(settings.rotation, "the workspace rotation");
  // (The window's samples are allocated: INT32_MAX of them asked for 51 GB.)
  if (settings.filter_window < 1 || settings.filter_window > kMaxFilterWindow)
    fail(Errc::InvalidArgument, "the filter window must be 1.." + std::to_string(kMaxFilterWindow) +
                                    " samples (10 s at 1 kHz), got " + std::to_string(settings.filter_window));
  const SafetySettings& s = settings.safety;
  if (!(s.max_force >= 0) || !(s.max_rate > 0) || !(s.stall_timeout > 0) || !(s.stall_ramp > 0) ||
      !std::isfinite(s.max_force + s.max_rate + s.stall_timeout + s.stall_ramp))
    fail(Errc::InvalidArgument, "the safety limits must be finite: max_force >= 0, max_force_rate, stall_timeout and stall_ramp > 0");
  if (!(settings.coupling_stiffness >= 0) || !(settings.coupling_damping >= 0) ||
      !std::isfinite(settings.coupling_stiffness + settings.coupling_damping))
    fail(Errc::InvalidArgument, "the coupling stiffness and damping must be finite and >= 0");
  DeviceSettings normalised = settings;
  normalised.rotation.normalize();
  const Id id = devices_.insert(std::make_unique<DeviceLink>(std::move(device), normalised));
  if (recorder_) recorder_->write(RecordKind::AddDevice, settings, id);
  return id;
}

void World::remove_device(Id id) {
  device(id).stop();
  devices_.erase(id);
  if (recorder_) recorder_->write(RecordKind::RemoveDevice, id);
}

void World::remove_tool(Id id) {
  tool(id);
  refuse_if_driven(devices_, id);
  // Grabs that followed this tool stay where the tool left them.
  lpcs_.for_each([&](Id, Lpc& c) {
    if (c.handle && c.handle->tool == id) {
      c.handle->position = tools_.get(id, "tool").position;
      c.handle->orientation = tools_.get(id, "tool").orientation;
      c.handle->tool = 0;
    }
  });
  tools_.erase(id);
  if (recorder_) recorder_->write(RecordKind::RemoveTool, id);
}

void World::set_tool_pose(Id id, const Vec3& position, const Eigen::Quaterniond& orientation) {
  Tool& t = tool(id);
  check_tool_pose(position, orientation);
  t.position = position;
  t.orientation = orientation.normalized();
  if (recorder_) recorder_->write(RecordKind::SetToolPose, id, position, orientation);
}

void World::teleport_tool(Id id, const Vec3& position, const Eigen::Quaterniond& orientation) {
  Tool& t = tool(id);
  check_tool_pose(position, orientation);
  t.position = t.previous_position = position;
  t.orientation = t.previous_orientation = orientation.normalized();
  // Its contacts' impulses are of another place: no warm start, no curvature term from them.
  for (uint64_t key : contact_row_keys(id)) warm_start_.erase(key);
  if (recorder_) recorder_->write(RecordKind::TeleportTool, id, position, orientation);
}

void World::set_lpc_velocity(Id id, const Vec3& velocity) {
  Lpc& c = lpcs_.get(id, "constraint");
  require_finite(velocity, "the prescribed velocity");
  c.velocity = velocity;
  c.handle.reset();
  if (recorder_) recorder_->write(RecordKind::SetLpcVelocity, id, velocity);
}

void World::set_lpc_targets(Id id, const Vec3List& targets) {
  Lpc& c = lpcs_.get(id, "constraint");
  if (targets.size() != c.nodes.size())
    fail(Errc::InvalidArgument, "the constraint holds " + std::to_string(c.nodes.size()) + " nodes, got " +
                                    std::to_string(targets.size()) + " targets");
  for (size_t k = 0; k < targets.size(); ++k) require_finite(targets[k], "target " + std::to_string(k));
  auto handle = std::make_unique<Handle>();
  handle->offsets = targets;
  c.handle = std::move(handle);
  if (recorder_) recorder_->write(RecordKind::SetLpcTargets, id, targets);
}

Id World::grab(Id body_id, const Vec3& center, double radius, Id tool_id) {
  const Body& b = body(body_id);
  require_finite(center, "the grab centre");
  if (!(radius > 0) || !std::isfinite(radius)) fail(Errc::InvalidArgument, "the grab radius must be finite and > 0 m");
  if (tool_id) tool(tool_id);  // throws for a stale tool id
  std::vector<int32_t> nodes;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if ((b.x[i] - center).norm() <= radius) nodes.push_back(i);
  if (nodes.empty())
    fail(Errc::InvalidArgument, b.name + ": no node within " + std::to_string(radius) + " m of the grab centre");
  auto handle = std::make_unique<Handle>();
  handle->tool = tool_id;
  // The handle starts at the tool's pose (or the centre) and carries the nodes where they are.
  handle->position = tool_id ? tool(tool_id).position : center;
  handle->orientation = tool_id ? tool(tool_id).orientation : Eigen::Quaterniond::Identity();
  for (int32_t i : nodes) handle->offsets.push_back(handle->orientation.inverse() * (b.x[i] - handle->position));
  const Id id = insert_lpc(body_id, nodes, LpcSpec{});
  lpcs_.get(id, "constraint").handle = std::move(handle);
  if (recorder_) recorder_->write(RecordKind::Grab, body_id, center, radius, tool_id, id);
  return id;
}

void World::set_handle_pose(Id id, const Vec3& position, const Eigen::Quaterniond& orientation) {
  Lpc& c = lpcs_.get(id, "constraint");
  if (!c.handle) fail(Errc::WrongState, "the constraint has no handle: create it with a grab or set its targets");
  if (c.handle->tool) fail(Errc::WrongState, "the handle follows a tool: move the tool instead");
  refuse_if_driven(devices_, id, "move the device instead");
  require_finite(position, "the handle position");
  require_rotation(orientation, "the handle orientation");
  c.handle->position = position;
  c.handle->orientation = orientation.normalized();
  if (recorder_) recorder_->write(RecordKind::SetHandlePose, id, position, orientation);
}

std::vector<Id> World::ids(IdKind kind) const {
  std::vector<Id> out;
  auto add = [&](Id id, const auto&) { out.push_back(id); };
  switch (kind) {
    case IdKind::Body: bodies_.for_each(add); break;
    case IdKind::Lpc: lpcs_.for_each(add); break;
    case IdKind::Tool: tools_.for_each(add); break;
    case IdKind::Device: devices_.for_each(add); break;
    case IdKind::Embedding: break;  // held by the C layer's world (capi/embedding.cpp), not here
  }
  return out;
}

void World::remove_lpc(Id id) {
  const Lpc& c = lpcs_.get(id, "constraint");
  refuse_if_driven(devices_, id);
  Body* b = bodies_.find(c.body);
  lpcs_.erase(id);
  if (recorder_) recorder_->write(RecordKind::RemoveLpc, id);
  if (!b) return;
  ++b->lpc_version;
  b->projection.reset(b->fem.node_count());  // the constraints stage rebuilds what remains
}

}  // namespace mica
