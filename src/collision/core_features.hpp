// SPDX-License-Identifier: Apache-2.0
// A tool as a core rounded by a radius (a sphere: its centre; a capsule: its axis; a box or a
// hull: a polytope inside it, rounded by a little: tool.hpp), and the contacts between the
// core's features and a body's surface triangle or node.
//
// Why features: a tool smaller than a triangle touches it between its nodes, and the pairs of
// features cover every point: each core corner against the triangle (the triangle's closest
// point to it, on its face, an edge or a corner) and the core's edge against each triangle edge
// (their closest points, inside both). Because a triangle is flat, this covers it: a capsule
// lying across a face meets the face's edges where it enters and leaves. A polytope core's faces
// meet the body's nodes (node_core), and its edges a node that sticks out towards them.
#pragma once
#include <array>
#include <vector>

#include "collision/tool.hpp"

namespace mica {

struct ToolCore {
  Vec3List corners;                            // m, world
  std::vector<std::array<int32_t, 2>> edges;   // corner pairs
  double radius = 0;                           // m, the rounding
  // A box's or hull's core (tool frame; its corners are `corners` in the world) and the pose.
  const HullData* polytope = nullptr;
  Mat3 rotation = Mat3::Identity();
  Vec3 position = Vec3::Zero();
};

// The core of a sphere, capsule, box or hull at its pose (a plane has none: empty); reuses
// `core`'s storage.
void tool_core(const Tool& tool, ToolCore& core);

struct FeatureHit;
// A node at x against a polytope core (box, hull): the core face or edge (as in core.edges)
// nearest x, and the pair's hit; inside the core, its nearest face. False where a core corner
// is nearest: that pair is a corner's against the node's triangles (corner_triangle).
bool node_core(const ToolCore& core, const Vec3& x, FeatureHit& hit, int32_t& face, int32_t& edge);

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
