// SPDX-License-Identifier: Apache-2.0
// Linear projection constraints.
#include "capi_internal.hpp"

using namespace mica_capi;

namespace {
mica_lpc_def lpc_defaults() {
  mica_lpc_def d{};
  d.struct_size = sizeof d;
  d.kind = MICA_LPC_FIXED;
  d.direction[0][0] = 1;
  d.direction[1][1] = 1;
  return d;
}
}  // namespace

extern "C" {

MICA_API mica_status mica_lpc_def_init(mica_lpc_def* def, uint32_t struct_size) {
  return init_def(def, struct_size, lpc_defaults(), "mica_lpc_def_init");
}

MICA_API mica_status mica_add_lpc(mica_world* world, mica_body_id body, const int32_t* nodes, int32_t count,
                                  const mica_lpc_def* def, mica_lpc_id* out_lpc) {
  return guarded(world, "mica_add_lpc", [&] {
    require(world, "world");
    require(nodes, "nodes");
    require(out_lpc, "out_lpc");
    if (count < 1) refuse(MICA_ERR_INVALID_ARGUMENT, "count is " + std::to_string(count) + ", must be >= 1");
    const mica_lpc_def d = read_def(def, lpc_defaults(), "def");
    mica::LpcSpec spec;
    switch (d.kind) {
      case MICA_LPC_FIXED: spec.kind = mica::LpcKind::Fixed; break;
      case MICA_LPC_PLANE: spec.kind = mica::LpcKind::Plane; break;
      case MICA_LPC_LINE: spec.kind = mica::LpcKind::Line; break;
      case MICA_LPC_TWO_DIRS: spec.kind = mica::LpcKind::TwoDirections; break;
      default: refuse(MICA_ERR_INVALID_ARGUMENT, "def->kind is " + std::to_string(d.kind) + ", not a MICA_LPC_* value");
    }
    spec.directions[0] = vec3(d.direction[0], "def->direction[0]");
    spec.directions[1] = vec3(d.direction[1], "def->direction[1]");
    spec.velocity = vec3(d.velocity, "def->velocity");
    *out_lpc = world->world.add_lpc(body, std::vector<int32_t>(nodes, nodes + count), spec);
    return MICA_OK;
  });
}

MICA_API mica_status mica_lpc_set_velocity(mica_world* world, mica_lpc_id lpc, const double velocity[3]) {
  return guarded(world, "mica_lpc_set_velocity", [&] {
    require(world, "world");
    world->world.set_lpc_velocity(lpc, vec3(velocity, "velocity"));
    return MICA_OK;
  });
}

MICA_API mica_status mica_lpc_set_targets(mica_world* world, mica_lpc_id lpc, const double* targets, int32_t count) {
  return guarded(world, "mica_lpc_set_targets", [&] {
    require(world, "world");
    require(targets, "targets");
    if (count < 0) refuse(MICA_ERR_INVALID_ARGUMENT, "count is " + std::to_string(count) + ", must be >= 0");
    mica::Vec3List t(static_cast<size_t>(count));
    for (int32_t k = 0; k < count; ++k) t[k] = {targets[3 * k], targets[3 * k + 1], targets[3 * k + 2]};
    world->world.set_lpc_targets(lpc, t);
    return MICA_OK;
  });
}

MICA_API mica_status mica_lpc_grab(mica_world* world, mica_body_id body, const double center[3], double radius,
                                   mica_tool_id tool, mica_lpc_id* out_lpc) {
  return guarded(world, "mica_lpc_grab", [&] {
    require(world, "world");
    require(out_lpc, "out_lpc");
    *out_lpc = world->world.grab(body, vec3(center, "center"), radius, tool);
    return MICA_OK;
  });
}

MICA_API mica_status mica_lpc_set_handle_pose(mica_world* world, mica_lpc_id lpc, const double position[3],
                                              const double orientation[4]) {
  return guarded(world, "mica_lpc_set_handle_pose", [&] {
    require(world, "world");
    world->world.set_handle_pose(lpc, vec3(position, "position"), quaternion(orientation, "orientation"));
    return MICA_OK;
  });
}

MICA_API mica_status mica_lpc_get_nodes(const mica_world* world, mica_lpc_id lpc, int32_t* out, int32_t capacity,
                                        int32_t* out_count) {
  return guarded(world, "mica_lpc_get_nodes", [&] {
    require(world, "world");
    const std::vector<int32_t>& nodes = world->world.lpc(lpc).nodes;
    return copy_out(nodes.data(), int32_t(nodes.size()), 1, out, capacity, out_count);
  });
}

MICA_API mica_status mica_lpc_get_reaction(const mica_world* world, mica_lpc_id lpc, double out_force[3]) {
  return guarded(world, "mica_lpc_get_reaction", [&] {
    require(world, "world");
    require(out_force, "out_force");
    const mica::Vec3& f = world->world.lpc(lpc).reaction;
    for (int k = 0; k < 3; ++k) out_force[k] = f[k];
    return MICA_OK;
  });
}

MICA_API mica_status mica_lpc_remove(mica_world* world, mica_lpc_id lpc) {
  return guarded(world, "mica_lpc_remove", [&] {
    require(world, "world");
    world->world.remove_lpc(lpc);
    return MICA_OK;
  });
}

}  // extern "C"
