// SPDX-License-Identifier: Apache-2.0
// Contacts: where a body touches a tool or another body, with the normal, the gap and a
// persistent key. Each contact gives one normal row of G (and two tangent rows with friction).
#pragma once
#include <array>
#include <vector>

#include "collision/bvh.hpp"
#include "collision/pseudo_normals.hpp"
#include "collision/tool.hpp"

namespace mica {

// A point of a body: a node (one weight of 1) or a point of a surface triangle (barycentric).
// BodyPoint and Contact have no padding: saved states copy them as bytes (state_io.cpp pins it).
struct BodyPoint {
  int32_t body = -1;  // index in the step's dynamic-body list
  int32_t count = 0;
  std::array<int32_t, 3> nodes{};
  int32_t unused = 0;
  std::array<double, 3> weights{};
};

struct Contact {
  uint64_t key;      // persistent while the same features touch: warm starts
  BodyPoint a;       // pushed along +normal
  BodyPoint b;       // between two bodies: pushed along -normal (count 0 for tools)
  Vec3 normal;       // unit, the direction that separates a from the other side
  Vec3 point;        // m, the contact point when detected
  double gap;        // m, signed distance at the start of the step (negative: penetrating)
  double friction;   // Coulomb coefficient, 0 for none
  Vec3 other_velocity = Vec3::Zero();  // m/s: a tool's velocity at the point (friction sticks to it)
  int32_t tool = -1;  // index in the step's tool list, or -1 between two bodies
  // A tool's contact between a feature of its core and of a body triangle (core_features.hpp):
  // the triangle, and the core's corner (against the triangle) or edge (against a triangle edge,
  // the body point's two nodes); -1 for a node's contact and between bodies.
  int32_t triangle = -1;
  int32_t core_corner = -1;
  int32_t core_edge = -1;
  uint64_t other = 0;  // the tool's id, or the other body's id (a static obstacle's too)
};

inline BodyPoint node_point(int32_t body, int32_t node) {
  BodyPoint p;
  p.body = body;
  p.count = 1;
  p.nodes[0] = node;
  p.weights[0] = 1.0;
  return p;
}

// Mixes ids into a contact key that survives reordering of tools, bodies and nodes.
inline uint64_t contact_key(uint64_t a, uint64_t b, uint64_t feature) {
  return (a * 0x9E3779B97F4A7C15ull) ^ (b * 0xC2B2AE3D27D4EB4Full) ^ (feature * 0x165667B19E3779F9ull);
}

// The surface of a body as collision sees it.
struct SurfaceView {
  int32_t index;                    // in the step's dynamic-body list, -1 for a static body
  uint64_t key;                     // the body's id
  const Vec3List* x;
  const std::vector<Tri>* triangles;
  const std::vector<int32_t>* nodes;  // surface nodes
  const TriangleBvh* bvh;
  const SurfacePseudoNormals* normals;  // of the triangles at x: which side of the surface a point is on
  double depth;                     // m, the deepest penetration looked for
  double travel;                    // m, how far a node may move this step (h times the top speed; 0 when static)
  const Vec3List* v = nullptr;      // the nodes' velocities (null: every node may move `travel`)
};

// Tool against a body: a contact for each pair of a feature of the tool's rounded core and of
// the body's surface closer than the margin (core_features.hpp: core corners against triangles,
// core edges against triangle edges, a box's or hull's core faces and edges against nodes), so
// that no point of the surface goes uncovered; a pair reached from two triangles is made once; a
// plane meets each node. Speculative: the margin grows by how
// far the tool and the body can travel in the step (h), so a fast approach is caught before it
// crosses; the constraint keeps the true gap, so the sides may close it but not cross it.
// Swept: the tool is at its new pose, and where it moved past a node or a triangle in the step
// (the nearest-point normal would push it on along its path relative to the tool, through to the
// far side), the contact keeps it on the side it was on at the start instead (tool_sweep.hpp):
// the tangent plane where the tool met it in the step, or at its nearest point at the start when
// it was inside then. An edge gets a contact too (its two nodes share it) where the tool met it in
// the step or lies across it now, or where it runs from a node the tool went past to one whose
// path misses the tool; otherwise edges are left to their nodes.
void collide_tool(const Tool& tool, int32_t tool_index, uint64_t tool_key, const SurfaceView& body, double h,
                  std::vector<Contact>& out);

// Surface nodes of body a against the surface triangles of body b (b may be static: an
// obstacle). Call it for (a, b) and (b, a). Speculative like collide_tool. Inside and outside come
// from b's pseudo-normal at the nearest point (a face, an edge or a vertex): b's surface must be
// closed and wound outwards.
void collide_bodies(const SurfaceView& a, const SurfaceView& b, double margin, double friction,
                    std::vector<Contact>& out);

}  // namespace mica
