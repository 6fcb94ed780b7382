// Kinematic rigid tools: the host sets their pose every step; bodies cannot push them.
#pragma once
#include "core/types.hpp"

namespace mica {

enum class ToolShape { Sphere, Capsule, Box, Plane, ConvexHull };

// Shapes are given in the tool frame (origin `position`, rotation `orientation`).
struct Tool {
  ToolShape shape = ToolShape::Sphere;
  double radius = 0.01;          // m, sphere and capsule
  double half_length = 0.01;     // m, capsule: segment from -half_length to +half_length along local z
  Vec3 half_extents{0.01, 0.01, 0.01};  // m, box
  Vec3 plane_normal{0, 0, 1};    // unit, in the tool frame: the side the body stays on
  Vec3List hull_points;          // m, convex hull: the hull of these points (tool frame)
  Vec3 position = Vec3::Zero();  // m, the tool origin (sphere centre, a point of the plane)
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  double margin = 0.0;           // m, contacts are made for gaps below this
  double friction = 0.0;         // Coulomb coefficient between the tool and tissue

  // Results of the last step: the force and torque (about `position`) the bodies put on the tool.
  Vec3 force = Vec3::Zero();     // N
  Vec3 torque = Vec3::Zero();    // N m
  int32_t contact_count = 0;
};

// Signed distance of p to the tool surface (negative inside) and the outward unit normal there.
struct SurfacePoint {
  double distance;
  Vec3 normal;
};
SurfacePoint closest_surface_point(const Tool& tool, const Vec3& p);

}  // namespace mica
