// SPDX-License-Identifier: Apache-2.0
// Kinematic tools and the forces on them.
#include "capi_internal.hpp"

using namespace mica_capi;

namespace {

mica_tool_def tool_defaults() {
  mica_tool_def d{};
  d.struct_size = sizeof d;
  d.shape = MICA_TOOL_SPHERE;
  d.radius = 0.01;
  d.normal[2] = 1;
  d.orientation[0] = 1;
  d.margin = 0.001;
  d.half_length = 0.01;
  d.half_extents[0] = d.half_extents[1] = d.half_extents[2] = 0.01;
  return d;
}

}  // namespace

extern "C" {

MICA_API mica_status mica_tool_def_init(mica_tool_def* def, uint32_t struct_size) {
  return init_def(def, struct_size, tool_defaults(), "mica_tool_def_init");
}

MICA_API mica_status mica_tool_create(mica_world* world, const mica_tool_def* def, mica_tool_id* out_tool) {
  return guarded(world, "mica_tool_create", [&] {
    require(world, "world");
    require(out_tool, "out_tool");
    const mica_tool_def d = read_def(def, tool_defaults(), "def");
    mica::Tool t;
    switch (d.shape) {
      case MICA_TOOL_SPHERE: t.shape = mica::ToolShape::Sphere; break;
      case MICA_TOOL_PLANE: t.shape = mica::ToolShape::Plane; break;
      case MICA_TOOL_CAPSULE: t.shape = mica::ToolShape::Capsule; break;
      case MICA_TOOL_BOX: t.shape = mica::ToolShape::Box; break;
      case MICA_TOOL_HULL: t.shape = mica::ToolShape::ConvexHull; break;
      default: refuse(MICA_ERR_INVALID_ARGUMENT, "def->shape is " + std::to_string(d.shape) + ", not a MICA_TOOL_* value");
    }
    t.radius = d.radius;
    t.half_length = d.half_length;
    t.half_extents = vec3(d.half_extents, "def->half_extents");
    if (t.shape == mica::ToolShape::ConvexHull) {
      require(d.hull_points, "def->hull_points");
      if (d.hull_point_count < 4 || d.hull_point_count > 64)
        refuse(MICA_ERR_INVALID_ARGUMENT, "def->hull_point_count is " + std::to_string(d.hull_point_count) + ", must be 4..64");
      for (int32_t k = 0; k < d.hull_point_count; ++k)
        t.hull_points.emplace_back(d.hull_points[3 * k], d.hull_points[3 * k + 1], d.hull_points[3 * k + 2]);
    }
    t.plane_normal = vec3(d.normal, "def->normal");
    t.position = vec3(d.position, "def->position");
    t.orientation = quaternion(d.orientation, "def->orientation");
    t.margin = d.margin;
    t.friction = d.friction;
    if (d.blade != 0 && d.blade != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "def->blade must be 0 or 1");
    if (d.blade && t.shape != mica::ToolShape::Capsule)
      refuse(MICA_ERR_INVALID_ARGUMENT, "def->blade is 1 for a tool that is not a capsule (a blade's edge is a capsule's segment)");
    *out_tool = world->world.add_tool(t);
    if (d.blade) world->world.set_tool_blade(*out_tool, true);
    return MICA_OK;
  });
}

MICA_API mica_status mica_tool_destroy(mica_world* world, mica_tool_id tool) {
  return guarded(world, "mica_tool_destroy", [&] {
    require(world, "world");
    world->world.remove_tool(tool);
    return MICA_OK;
  });
}

MICA_API mica_status mica_tool_set_pose(mica_world* world, mica_tool_id tool, const double position[3],
                                        const double orientation[4]) {
  return guarded(world, "mica_tool_set_pose", [&] {
    require(world, "world");
    world->world.set_tool_pose(tool, vec3(position, "position"), quaternion(orientation, "orientation"));
    return MICA_OK;
  });
}

MICA_API mica_status mica_tool_teleport(mica_world* world, mica_tool_id tool, const double position[3],
                                        const double orientation[4]) {
  return guarded(world, "mica_tool_teleport", [&] {
    require(world, "world");
    world->world.teleport_tool(tool, vec3(position, "position"), quaternion(orientation, "orientation"));
    return MICA_OK;
  });
}

MICA_API mica_status mica_tool_get_pose(const mica_world* world, mica_tool_id tool, double out_position[3],
                                        double out_orientation[4]) {
  return guarded(world, "mica_tool_get_pose", [&] {
    require(world, "world");
    const mica::Tool& t = world->world.tool(tool);
    if (out_position)
      for (int k = 0; k < 3; ++k) out_position[k] = t.position[k];
    if (out_orientation) {
      out_orientation[0] = t.orientation.w();
      out_orientation[1] = t.orientation.x();
      out_orientation[2] = t.orientation.y();
      out_orientation[3] = t.orientation.z();
    }
    return MICA_OK;
  });
}

MICA_API mica_status mica_tool_get_force(const mica_world* world, mica_tool_id tool, double out_force[3],
                                         double out_torque[3], int32_t* out_contacts) {
  return guarded(world, "mica_tool_get_force", [&] {
    require(world, "world");
    const mica::Tool& t = world->world.tool(tool);
    for (int k = 0; k < 3; ++k) {
      if (out_force) out_force[k] = t.force[k];
      if (out_torque) out_torque[k] = t.torque[k];
    }
    if (out_contacts) *out_contacts = t.contact_count;
    return MICA_OK;
  });
}

}  // extern "C"
