// SPDX-License-Identifier: Apache-2.0
#include "collision/tool.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "collision/closest_point.hpp"
#include "core/error.hpp"

namespace mica {

namespace {

void require_positive(double value, const std::string& field) {
  if (!(value > 0 && std::isfinite(value)))
    fail(Errc::InvalidArgument, "tool " + field + " is " + std::to_string(value) + "; it must be finite and > 0 m");
}

// The shapes below work in the tool frame: q is the query point there, normals come back there.

SurfacePoint sphere_point(double radius, const Vec3& q) {
  const double r = q.norm();
  // At the very centre any direction is as good: push along +z.
  return {r - radius, r > 0 ? Vec3(q / r) : Vec3::UnitZ()};
}

SurfacePoint capsule_point(double radius, double half_length, const Vec3& q) {
  const Vec3 axis_point(0, 0, std::clamp(q.z(), -half_length, half_length));
  const Vec3 d = q - axis_point;
  const double r = d.norm();
  // On the axis every sideways direction is as good: push along local x.
  return {r - radius, r > 0 ? Vec3(d / r) : Vec3::UnitX()};
}

SurfacePoint box_point(const Vec3& h, const Vec3& q) {
  const Vec3 d = q - q.cwiseMax(-h).cwiseMin(h);
  const double outside = d.norm();
  if (outside > 0) return {outside, d / outside};
  // Inside or on the surface: the nearest face.
  int axis = 0;
  const double depth = (h - q.cwiseAbs()).minCoeff(&axis);
  Vec3 n = Vec3::Zero();
  n[axis] = q[axis] >= 0 ? 1 : -1;
  return {-depth, n};
}

SurfacePoint hull_point(const HullData& hull, const Vec3& q) {
  // Inside or on: the depth is the distance to the nearest face plane.
  const HullFace* nearest = &hull.faces[0];
  double height = -HUGE_VAL;
  for (const HullFace& f : hull.faces) {
    const double s = f.normal.dot(q) - f.offset;
    if (s > height) {
      height = s;
      nearest = &f;
    }
  }
  if (height <= 0) return {height, nearest->normal};

  // Outside: the closest hull point lies on a face whose plane q is in front of (the gap q - foot
  // is a non-negative mix of the normals of the faces through the foot, so one of them sees q).
  double best2 = HUGE_VAL;
  Vec3 foot = q;
  for (const HullFace& f : hull.faces) {
    if (f.normal.dot(q) - f.offset <= 0) continue;
    for (size_t k = 1; k + 1 < f.polygon.size(); ++k) {
      const Vec3 x = closest_on_triangle(q, f.polygon[0], f.polygon[k], f.polygon[k + 1]).point;
      const double d2 = (q - x).squaredNorm();
      if (d2 < best2) {
        best2 = d2;
        foot = x;
      }
    }
  }
  const double distance = std::sqrt(best2);
  if (!(distance > 0)) return {0, nearest->normal};
  return {distance, (q - foot) / distance};
}

// Sharp edges make a contact's normal jump as the surface turns under them, and a held tool
// chatters (docs/method.md); a tenth of the distance to the nearest face rounds them, at most 1 mm.
constexpr double kRoundingFraction = 0.1;
constexpr double kMaxRounding = 1e-3;  // m

// The box's or hull's rounded core: a box shrinks by the rounding along each axis (its faces stay
// where they are), a hull's corners move towards its centre until its nearest face is the
// rounding inside (its other faces move in a little more).
void prepare_core(Tool& tool) {
  const bool box = tool.shape == ToolShape::Box;
  double nearest = tool.half_extents.minCoeff();
  if (!box) {
    nearest = HUGE_VAL;
    for (const HullFace& f : tool.hull->faces) nearest = std::min(nearest, f.offset - f.normal.dot(tool.hull->centre));
  }
  tool.rounding = std::min(kMaxRounding, kRoundingFraction * nearest);
  Vec3List points;
  if (box) {
    const Vec3 c = tool.half_extents - Vec3::Constant(tool.rounding);
    for (int k = 0; k < 8; ++k)
      points.push_back(Vec3(k & 1 ? c.x() : -c.x(), k & 2 ? c.y() : -c.y(), k & 4 ? c.z() : -c.z()));
  } else {
    const double scale = 1 - tool.rounding / nearest;
    for (const Vec3& v : tool.hull->vertices) points.push_back(tool.hull->centre + scale * (v - tool.hull->centre));
  }
  tool.core = build_convex_hull(points, "tool core");
}

}  // namespace

void prepare_tool_shape(Tool& tool) {
  tool.hull.reset();
  tool.core.reset();
  tool.rounding = 0;
  switch (tool.shape) {
    case ToolShape::Sphere:
      require_positive(tool.radius, "radius");
      return;
    case ToolShape::Capsule:
      require_positive(tool.radius, "radius");
      require_positive(tool.half_length, "half_length");
      return;
    case ToolShape::Box:
      for (int k = 0; k < 3; ++k) require_positive(tool.half_extents[k], "half_extents[" + std::to_string(k) + "]");
      prepare_core(tool);
      return;
    case ToolShape::Plane:
      if (!(tool.plane_normal.allFinite() && tool.plane_normal.norm() > 1e-12))
        fail(Errc::InvalidArgument, "tool plane_normal must be a finite non-zero vector");
      tool.plane_normal.normalize();
      return;
    case ToolShape::ConvexHull:
      tool.hull = build_convex_hull(tool.hull_points, "tool hull_points");
      prepare_core(tool);
      return;
  }
  fail(Errc::InvalidArgument, "tool shape " + std::to_string(int(tool.shape)) + " is not a ToolShape");
}

SurfacePoint closest_surface_point(const Tool& tool, const Vec3& p) {
  const Vec3 q = tool.orientation.conjugate() * (p - tool.position);
  SurfacePoint s{HUGE_VAL, Vec3::UnitZ()};
  switch (tool.shape) {
    case ToolShape::Sphere: s = sphere_point(tool.radius, q); break;
    case ToolShape::Capsule: s = capsule_point(tool.radius, tool.half_length, q); break;
    case ToolShape::Box: s = box_point(tool.half_extents, q); break;
    case ToolShape::Plane: s = {tool.plane_normal.dot(q), tool.plane_normal}; break;
    case ToolShape::ConvexHull:
      if (!tool.hull) fail(Errc::WrongState, "the convex hull tool was not prepared (prepare_tool_shape)");
      s = hull_point(*tool.hull, q);
      break;
    default: fail(Errc::InvalidArgument, "tool shape " + std::to_string(int(tool.shape)) + " is not a ToolShape");
  }
  return {s.distance, tool.orientation * s.normal};
}

Aabb tool_bounds(const Tool& tool, double margin) {
  const Mat3 R = tool.orientation.toRotationMatrix();
  Aabb box;
  switch (tool.shape) {
    case ToolShape::Sphere:
      box.add(tool.position);
      return box.inflated(tool.radius + margin);
    case ToolShape::Capsule:
      box.add(tool.position + tool.half_length * R.col(2));
      box.add(tool.position - tool.half_length * R.col(2));
      return box.inflated(tool.radius + margin);
    case ToolShape::Box: {
      const Vec3 extent = R.cwiseAbs() * tool.half_extents;  // half-size of the rotated box
      box.add(tool.position - extent);
      box.add(tool.position + extent);
      return box.inflated(margin);
    }
    case ToolShape::Plane:
      return {Vec3::Constant(-kPlaneBound), Vec3::Constant(kPlaneBound)};
    case ToolShape::ConvexHull:
      for (const Vec3& v : tool.hull_points) box.add(tool.position + R * v);
      return box.inflated(margin);
  }
  fail(Errc::InvalidArgument, "tool shape " + std::to_string(int(tool.shape)) + " is not a ToolShape");
}

}  // namespace mica
