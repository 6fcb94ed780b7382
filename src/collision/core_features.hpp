// A tool as a core rounded by a radius (a sphere: its centre; a capsule: its axis; a box or a
// hull: its corners and edges, radius 0), and the contacts between the core's features and a
// body's surface triangle.
//
// Why features: a triangle's single deepest point against a flat tool face is any point of the
// triangle (it jumps between corners from one step to the next, and a box punch chatters), and
// a tool smaller than a triangle touches it between its nodes. The pairs that cannot jump are
// those of the features: each core corner against the triangle (the triangle's closest point to
// it), each core edge against each triangle edge (their closest points, inside both), and each
// body node against the tool (made apart, collide_tool's node loop). Because a triangle is flat,
// these cover it: a tool edge lying across a face meets its edges where it enters and leaves.
#pragma once
#include <array>
#include <vector>

#include "collision/tool.hpp"

namespace mica {

struct ToolCore {
  Vec3List corners;                            // m, world
  std::vector<std::array<int32_t, 2>> edges;   // corner pairs
  double radius = 0;                           // m, the rounding
};

// The core of a tool at its pose (not for a Plane, which has none); reuses `core`'s storage.
void tool_core(const Tool& tool, ToolCore& core);

// A feature pair in contact: the body's point (barycentric weights over the body feature's
// corners), the direction the body point must move to separate (unit), the signed gap (m).
struct FeatureHit {
  Vec3 weights;
  Vec3 point;
  Vec3 normal;
  double gap;
};

// The pair's closest points, the normal from the core point to the body point and the gap of
// the rounded core, as if the core point were outside the body; false when undefined.
bool corner_triangle(const Vec3& corner, double radius, const Vec3& a, const Vec3& b, const Vec3& c, FeatureHit& hit);
bool edge_edge(const Vec3& p0, const Vec3& p1, double radius, const Vec3& e0, const Vec3& e1, FeatureHit& hit);
// Orients a hit by the body's outward pseudo-normal at its point. A core point behind the
// surface is inside the body, and the body point must move past it, when the tool's penetration
// there (the distance plus the rounding) is within `depth`; the sign test is the triangle's own,
// not the whole surface's, and holds only that near it. Deeper, the core point is taken to be
// outside (a tool that went that deep in a step is the tool sweep's to sort out). Touching
// pairs take the surface's normal.
void orient_by_surface(const Vec3& outward, double radius, double depth, FeatureHit& hit);

}  // namespace mica
