// SPDX-License-Identifier: Apache-2.0
// Kinematic rigid tools: the host sets their pose every step; bodies cannot push them.
#pragma once
#include <memory>

#include "collision/aabb.hpp"
#include "collision/convex_hull.hpp"
#include "core/types.hpp"

namespace mica {

enum class ToolShape { Sphere, Capsule, Box, Plane, ConvexHull };

// A kinematic tool in three parts, like Body (world/body.hpp): the model it was made with (never
// changed after World::add_tool), the state the host and the steps leave, and what a step derives
// from the pose change. Tool is the three together; a function that needs one part takes that part.

// What the tool is. Shapes are given in the tool frame (origin `position`, rotation `orientation`).
struct ToolModel {
  ToolShape shape = ToolShape::Sphere;
  double radius = 0.01;          // m, sphere and capsule
  double half_length = 0.01;     // m, capsule: segment from -half_length to +half_length along local z
  Vec3 half_extents{0.01, 0.01, 0.01};  // m, box
  Vec3 plane_normal{0, 0, 1};    // unit, in the tool frame: the side the body stays on
  Vec3List hull_points;          // m, convex hull: the hull of these points (tool frame)
  double margin = 0.0;           // m, contacts are made for gaps below this
  double friction = 0.0;         // Coulomb coefficient between the tool and tissue
  bool blade = false;            // a capsule whose segment cuts (world/blade.cpp)

  // Derived from hull_points by prepare_tool_shape (null for other shapes); shared by copies.
  std::shared_ptr<const HullData> hull;
  // A box's or hull's contact core (tool frame) and rounding (m), by prepare_tool_shape: the shape
  // shrunk so that, rounded by `rounding`, it fits inside the shape and touches its nearest face.
  // Contacts are made with the rounded core (core_features.hpp); null for the other shapes.
  std::shared_ptr<const HullData> core;
  double rounding = 0;
};

// Where the tool is and what the last step put on it.
struct ToolState {
  Vec3 position = Vec3::Zero();  // m, the tool origin (sphere centre, a point of the plane)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  // The pose at the start of the step (the end of the last one).
  Vec3 previous_position = Vec3::Zero();
  Eigen::Quaterniond previous_orientation = Eigen::Quaterniond::Identity();

  // Results of the last step: the force and torque (about `position`) the bodies put on the tool.
  Vec3 force = Vec3::Zero();     // N
  Vec3 torque = Vec3::Zero();    // N m
  int32_t contact_count = 0;
  Mat3 stiffness = Mat3::Zero(); // N/m, dF/dx of the force on the tool around its pose (negative semidefinite)
};

// What a step derives from the state: the velocities the step's pose change implies (its
// contacts move with them), and the step's results, ToolState's once the step commits.
struct ToolScratch {
  Vec3 velocity = Vec3::Zero();          // m/s
  Vec3 angular_velocity = Vec3::Zero();  // rad/s
  struct {
    Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
    int32_t contact_count = 0;
    Mat3 stiffness = Mat3::Zero();
  } next;
};

struct Tool : ToolModel, ToolState, ToolScratch {
  const ToolModel& model() const { return *this; }
};

// Checks the parameters the shape uses (finite; radius, half_length, half_extents > 0; a plane
// normal that is not zero; 4..kMaxHullPoints hull points that are not coplanar) and throws
// Error(InvalidArgument) naming the field; normalises plane_normal and builds the hull data.
// Call it again after changing any shape field.
void prepare_tool_shape(Tool& tool);

// Signed distance of p to the tool surface (negative inside) and the outward unit normal there.
// A ConvexHull tool must have been through prepare_tool_shape (WrongState otherwise).
struct SurfacePoint {
  double distance;
  Vec3 normal;
};
SurfacePoint closest_surface_point(const Tool& tool, const Vec3& p);

// World-space bounds of the tool inflated by margin; a Plane gets a huge box (+-kPlaneBound).
constexpr double kPlaneBound = 1e30;  // m
Aabb tool_bounds(const Tool& tool, double margin);

}  // namespace mica
