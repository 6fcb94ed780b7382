// SPDX-License-Identifier: Apache-2.0
#include "collision/tool_sweep.hpp"

#include <algorithm>

#include "collision/segment_entry.hpp"

namespace mica {

namespace {

// The turn of the tool's shape in the step, new * previous^-1, less what the shape cannot show:
// a sphere looks the same turned any way, a capsule turned about its axis. (Each body point's
// path is the chord of its arc: a sphere spun about its centre once swept every node across it,
// and a half turn pushed the tissue 10 N into the tool.)
Mat3 shape_turn(const Tool& tool) {
  switch (tool.shape) {
    case ToolShape::Sphere: return Mat3::Identity();
    case ToolShape::Capsule: {
      const Vec3 before = tool.previous_orientation * Vec3::UnitZ(), after = tool.orientation * Vec3::UnitZ();
      if ((after - before).norm() <= 1e-12) return Mat3::Identity();  // a spin: the axis moved by round-off
      return Eigen::Quaterniond::FromTwoVectors(before, after).toRotationMatrix();  // the axis's swing
    }
    case ToolShape::Box:
    case ToolShape::ConvexHull:
    case ToolShape::Plane: break;
  }
  return (tool.orientation * tool.previous_orientation.conjugate()).toRotationMatrix();
}

}  // namespace

ToolSweep::ToolSweep(const Tool& tool)
    : start_(tool.previous_position), end_(tool.position), turn_(shape_turn(tool)),
      moved_(tool.position != tool.previous_position || turn_ != Mat3::Identity()) {}

bool node_start_side(const Tool& tool, const ToolSweep& sweep, const Vec3& x, SideContact& side) {
  const Vec3 y0 = sweep.start_relative(x);
  const SurfacePoint s0 = closest_surface_point(tool, y0);
  if (s0.distance <= 0) {
    // Inside at the start: the side of its nearest surface point then, y0 - d n.
    side = {s0.normal, s0.distance + s0.normal.dot(x - y0)};
    return true;
  }
  SegmentEntry e;
  if (!segment_entry(tool, y0, x, e)) return false;
  side = {e.normal, e.normal.dot(x - e.point)};
  return true;
}

bool edge_start_side(const Tool& tool, const ToolSweep& sweep, const Vec3& xi, const Vec3& xj, double& wj,
                     SideContact& side) {
  if (!node_start_side(tool, sweep, xi, side)) return false;
  double meets = 0, misses = 1;  // weights of xj: the point at `meets` meets the tool, at `misses` not
  for (int k = 0; k < kBisections; ++k) {
    const double w = 0.5 * (meets + misses);
    SideContact s;
    if (node_start_side(tool, sweep, (1 - w) * xi + w * xj, s)) {
      meets = w;
      side = s;
    } else {
      misses = w;
    }
  }
  wj = meets;
  return true;
}

bool triangle_start_side(const Tool& tool, const ToolSweep& sweep, const Vec3& a, const Vec3& b, const Vec3& c,
                         TriangleHit& hit, double& t) {
  const Vec3 end[3] = {a, b, c};
  Vec3 start[3];
  double speed = 0;  // the longest path of a corner, hence of any point of the triangle
  for (int k = 0; k < 3; ++k) {
    start[k] = sweep.start_relative(end[k]);
    speed = std::max(speed, (end[k] - start[k]).norm());
  }
  if (!(speed > 0)) return false;
  // Touching means within this of the tool: close enough for the normal at the touch, far enough
  // that the distance query still has a direction to give.
  const double touch = 1e-3 * speed;
  t = 0;
  for (int k = 0; k < kMaxAdvances; ++k) {
    Vec3 at[3];
    for (int j = 0; j < 3; ++j) at[j] = start[j] + t * (end[j] - start[j]);
    TriangleHit h;
    // Farther than the rest of the path can close: it never touches.
    if (!collide_triangle(tool, at[0], at[1], at[2], (1 - t) * speed + touch, h)) return false;
    if (h.gap <= touch) {
      const Vec3 point = h.weights[0] * a + h.weights[1] * b + h.weights[2] * c;
      hit = {point, h.weights, h.normal, h.gap + h.normal.dot(point - h.point)};
      return true;
    }
    t += (h.gap - 0.5 * touch) / speed;
    if (t > 1) return false;
  }
  return false;
}

}  // namespace mica
