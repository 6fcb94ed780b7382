#include "collision/tool_sweep.hpp"

#include <algorithm>

#include "collision/segment_entry.hpp"

namespace mica {

ToolSweep::ToolSweep(const Tool& tool)
    : start_(tool.previous_position), end_(tool.position),
      turn_((tool.orientation * tool.previous_orientation.conjugate()).toRotationMatrix()),
      moved_(tool.position != tool.previous_position ||
             tool.orientation.coeffs() != tool.previous_orientation.coeffs()) {}

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
