// A rounded tool as its core (a sphere: its centre; a capsule: its axis) and radius, and the
// contacts between the core's features and a body's surface triangle.
//
// Why features: a tool smaller than a triangle touches it between its nodes, and the pairs of
// features cover every point: each core corner against the triangle (the triangle's closest
// point to it, on its face, an edge or a corner) and the core's edge against each triangle edge
// (their closest points, inside both). Because a triangle is flat, this covers it: a capsule
// lying across a face meets the face's edges where it enters and leaves. (Box and hull cores
// were tried with their sharp corners and edges as features, radius 0: a 6 mm box between the
// nodes of a 1 cm mesh drove the body unstable; they keep the triangle's deepest point.)
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

// The core of a sphere or capsule at its pose; reuses `core`'s storage. (Box and hull contacts
// are made from the triangle's deepest point instead: contact.hpp.)
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
