// SPDX-License-Identifier: Apache-2.0
// A tool's motion within a step, for contacts that keep a body on the side of the tool it was on
// at the step's start. The contacts are made against the tool at its new pose; a tool that moves
// farther in a step than its own size can end past a thin body, whose nodes are then nearer its
// far side, and the nearest-point contact would push them through (or, beyond the margin, not at
// all). Seen from the tool at its new pose, the body moves instead: a point x of the body goes
// from start_relative(x) (where it was relative to the tool at the start) to x, along the
// straight segment between them (exact for a translation; the chord of the arc for a turn).
#pragma once
#include "collision/tool.hpp"
#include "collision/triangle_contact.hpp"

namespace mica {

class ToolSweep {
 public:
  explicit ToolSweep(const Tool& tool);  // from previous_position/orientation to position/orientation

  bool moved() const { return moved_; }
  // Where x was relative to the tool at the step's start, carried to the tool's new pose.
  Vec3 start_relative(const Vec3& x) const { return end_ + turn_ * (x - start_); }

 private:
  Vec3 start_, end_;
  Mat3 turn_;  // the shape's turn, new * previous^-1 (none for a sphere, the axis's swing for a capsule)
  bool moved_;
};

// The contact that keeps a point on its start side: the tangent plane of the tool's surface (new
// pose) where the point's relative path first meets the surface, or, for a point already inside
// at the start, at its nearest surface point then. gap is the point's signed distance to that
// plane at x (negative: across it), normal the plane's normal (away from the tool).
struct SideContact {
  Vec3 normal;
  double gap;
};

// For a node at x: false when its path never meets the tool (nothing to keep it from). Exact
// (segment_entry). Not for a Plane tool.
bool node_start_side(const Tool& tool, const ToolSweep& sweep, const Vec3& x, SideContact& side);

// For an edge from xi to xj whose node i the tool passed while node j's path misses the tool
// (node_start_side true for i, false for j): the edge crosses the boundary of the tool's sweep,
// and however far the tool pushes node i ahead, the edge from it back to node j must not end
// across the tool. The contact at the last point of the edge whose path still meets the tool
// (found by bisection to kBisections halvings of the edge): side holds it, the point is
// (1 - wj) xi + wj xj. False if no point of the edge meets the tool (i did not either).
constexpr int kBisections = 30;
bool edge_start_side(const Tool& tool, const ToolSweep& sweep, const Vec3& xi, const Vec3& xj, double& wj,
                     SideContact& side);

// For the triangle abc of a body: its first touch along the relative path (every point of the
// triangle moves on its own segment), found by conservative advancement of collide_triangle's
// gap, which no point can close faster than the longest of those segments. On success `hit`
// holds the touch's normal and barycentric weights, the triangle's point with those weights at
// its end position and its gap to the tangent plane there. False when the path never touches the
// tool, and for a path that grazes it for more than kMaxAdvances advances (undecided: the caller
// keeps only what the triangle's nodes say).
constexpr int kMaxAdvances = 40;
bool triangle_start_side(const Tool& tool, const ToolSweep& sweep, const Vec3& a, const Vec3& b, const Vec3& c,
                         TriangleHit& hit, double& t);  // t: where on the path it touched (0: at the start)

}  // namespace mica
