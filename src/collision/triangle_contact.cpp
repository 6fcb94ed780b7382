// SPDX-License-Identifier: Apache-2.0
#include "collision/triangle_contact.hpp"

#include <ccd/ccd.h>

#include <algorithm>

#include "collision/closest_point.hpp"
#include "collision/gjk.hpp"
#include "core/error.hpp"

namespace mica {

namespace {

double longest_edge(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
}

bool sphere_contact(const Tool& tool, const Vec3& a, const Vec3& b, const Vec3& c, double margin, TriangleHit& hit) {
  const TrianglePoint t = closest_on_triangle(tool.position, a, b, c);
  const Vec3 d = t.point - tool.position;
  const double r = d.norm();
  const double gap = r - tool.radius;
  if (!(gap < margin)) return false;
  // A centre on the triangle pushes it behind its winding: into a body whose surface is wound outwards.
  Vec3 normal = r > 0 ? Vec3(d / r) : Vec3(-(b - a).cross(c - a).normalized());
  if (!normal.allFinite()) normal = Vec3::UnitZ();  // ... unless the triangle is degenerate
  hit = {t.point, t.weights, normal, gap};
  return true;
}

bool plane_contact(const Tool& tool, const Vec3& a, const Vec3& b, const Vec3& c, double margin, TriangleHit& hit) {
  const Vec3 n = tool.orientation * tool.plane_normal;
  const Vec3 height(n.dot(a - tool.position), n.dot(b - tool.position), n.dot(c - tool.position));
  const double lowest = height.minCoeff();
  if (!(lowest < margin)) return false;
  // Vertices level with the lowest one (to rounding) share the contact: a flat triangle gets its centroid.
  const double level = lowest + 1e-10 * (height.cwiseAbs().maxCoeff() + longest_edge(a, b, c));
  Vec3 w = (height.array() <= level).cast<double>();
  w /= w.sum();
  hit = {w[0] * a + w[1] * b + w[2] * c, w, n, lowest};
  return true;
}

// --- Capsule, Box and ConvexHull: a polytope core (a point, a segment, a box, a hull) rounded by a radius

double rounding(const Tool& tool) {
  return tool.shape == ToolShape::Sphere || tool.shape == ToolShape::Capsule ? tool.radius : 0.0;
}

// The farthest point of the tool's core along direction d, both in the tool frame.
Vec3 core_support(const Tool& tool, const Vec3& d) {
  switch (tool.shape) {
    case ToolShape::Sphere: return Vec3::Zero();
    case ToolShape::Capsule: return Vec3(0, 0, d.z() >= 0 ? tool.half_length : -tool.half_length);
    case ToolShape::Box: {
      Vec3 corner = tool.half_extents;
      for (int k = 0; k < 3; ++k)
        if (d[k] < 0) corner[k] = -corner[k];
      return corner;
    }
    case ToolShape::ConvexHull: {
      const Vec3List& v = tool.hull->vertices;
      size_t best = 0;
      for (size_t k = 1; k < v.size(); ++k)
        if (v[k].dot(d) > v[best].dot(d)) best = k;
      return v[best];
    }
    case ToolShape::Plane: break;
  }
  fail(Errc::Internal, "no support function for this tool shape");
}

// The tool's core in world coordinates: its corners, edge directions and face normals (unit).
struct CorePolytope {
  Vec3List corners, edges, normals;
};

CorePolytope core_polytope(const Tool& tool, const Mat3& R) {
  CorePolytope p;
  switch (tool.shape) {
    case ToolShape::Sphere: p.corners = {tool.position}; break;
    case ToolShape::Capsule:
      p.corners = {tool.position + tool.half_length * R.col(2), tool.position - tool.half_length * R.col(2)};
      p.edges = {R.col(2)};
      break;
    case ToolShape::Box:
      for (int i = 0; i < 8; ++i) {
        Vec3 corner = tool.half_extents;
        for (int k = 0; k < 3; ++k)
          if (i >> k & 1) corner[k] = -corner[k];
        p.corners.push_back(tool.position + R * corner);
      }
      p.edges = {R.col(0), R.col(1), R.col(2)};
      p.normals = p.edges;
      break;
    case ToolShape::ConvexHull:
      for (const Vec3& v : tool.hull->vertices) p.corners.push_back(tool.position + R * v);
      for (const Vec3& e : tool.hull->edge_directions) p.edges.push_back(R * e);
      for (const HullFace& f : tool.hull->faces) p.normals.push_back(R * f.normal);
      break;
    case ToolShape::Plane: break;
  }
  return p;
}

struct Separation {
  double depth;  // m, the least translation of the triangle that separates it from the core
  Vec3 normal;   // unit, the direction of that translation
};

// Two polytopes are separated fastest along a face normal of their Minkowski difference, and
// those are among the face normals of each and the cross products of an edge of each.
Separation least_separation(const CorePolytope& core, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 sides[3] = {(b - a).normalized(), (c - b).normalized(), (a - c).normalized()};
  Vec3List axes = core.normals;
  axes.push_back(sides[0].cross(sides[1]));
  for (const Vec3& e : core.edges)
    for (const Vec3& f : sides) axes.push_back(e.cross(f));
  Separation best{HUGE_VAL, Vec3::UnitZ()};
  for (const Vec3& axis : axes) {
    const double length = axis.norm();
    if (!(length > 1e-9)) continue;  // parallel edges (or a degenerate triangle) give no axis
    for (double sign : {1.0, -1.0}) {
      const Vec3 n = sign * axis / length;
      double reach = -HUGE_VAL;  // how far the core extends along n
      for (const Vec3& x : core.corners) reach = std::max(reach, n.dot(x));
      const double depth = reach - std::min({n.dot(a), n.dot(b), n.dot(c)});
      if (depth < best.depth) best = {depth, n};
    }
  }
  return best;
}

// --- libccd's view of the tool inflated by the margin (object 1) and of the triangle (object 2)

// libccd's MPR bounds only its last phase (ccd_t::max_iterations); its portal discovery and
// refinement loop until their own tests pass, which on degenerate input they may never do: a
// triangle with a corner at 1e73 m (a body blown up by a grab handle posed 1e64 m away) against a
// 1 cm box cycled in the discovery, and the step never returned. So the support functions count
// their calls, and past kMprSupportCalls they describe shapes that are apart: the Minkowski
// difference's support lies behind the origin along whatever direction is asked, which every
// phase of MPR tests on each new support point, so MPR ends at its next one; the caller then
// discards its answer. An MPR that settles makes at most max_iterations + 2 calls for the depth
// after a few to find and refine its portal (fewer than 60 throughout the tests).
constexpr int32_t kMprMaxIterations = 200;
constexpr int32_t kMprSupportCalls = 4 * kMprMaxIterations;

struct MprBudget {
  int32_t calls = 0;
  bool spent() const { return calls > kMprSupportCalls; }
};

struct ToolObject {
  const Tool* tool;
  Mat3 R;          // tool frame to world
  double inflate;  // m, the margin: the tool is rounded by this radius
  Vec3 centre;     // a point strictly inside the tool, world
  MprBudget* budget = nullptr;  // set for MPR (penetration_contact)
};

struct TriangleObject {
  Vec3 v[3];
  Vec3 centre;  // any point of the triangle
  const MprBudget* budget = nullptr;  // set for MPR (penetration_contact)
};

Vec3 from_ccd(const ccd_vec3_t* v) { return {v->v[0], v->v[1], v->v[2]}; }
void to_ccd(const Vec3& x, ccd_vec3_t* v) { ccdVec3Set(v, x[0], x[1], x[2]); }

Vec3 triangle_support(const TriangleObject& t, const Vec3& d) {
  int best = 0;
  for (int k = 1; k < 3; ++k)
    if (t.v[k].dot(d) > t.v[best].dot(d)) best = k;
  return t.v[best];
}

Vec3 unit_or_x(const Vec3& d) {
  const double n = d.norm();
  return n > 0 ? Vec3(d / n) : Vec3::UnitX();
}

// libccd asks object 1 (the tool) first, then object 2 for the opposite direction; their
// difference is the support point of the Minkowski difference.
void tool_support(const void* object, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const ToolObject& o = *static_cast<const ToolObject*>(object);
  const Vec3 d = unit_or_x(from_ccd(dir));
  if (o.budget && (++o.budget->calls, o.budget->spent())) {
    to_ccd(-d, out);  // the triangle's is then the origin: the difference is 1 m behind it along d
    return;
  }
  const Vec3 core = o.tool->position + o.R * core_support(*o.tool, o.R.transpose() * d);
  to_ccd(core + (rounding(*o.tool) + o.inflate) * d, out);
}

void tool_centre(const void* object, ccd_vec3_t* out) { to_ccd(static_cast<const ToolObject*>(object)->centre, out); }

void triangle_support_ccd(const void* object, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const TriangleObject& t = *static_cast<const TriangleObject*>(object);
  if (t.budget && t.budget->spent()) {
    to_ccd(Vec3::Zero(), out);
    return;
  }
  to_ccd(triangle_support(t, from_ccd(dir)), out);
}

void triangle_centre(const void* object, ccd_vec3_t* out) {
  to_ccd(static_cast<const TriangleObject*>(object)->centre, out);
}

// The cores meet. libccd's MPR, run on the tool inflated by the margin, gives a point the shapes
// share: the contact point. Its depth is measured across the face of the Minkowski difference that
// the ray from the tool's centre leaves through, which is not always the shallowest one (a few
// percent of shallow contacts come out up to twice too deep), so the depth and normal come from
// the separating axes instead: exact for these polytope cores.
bool penetration_contact(ToolObject t, const Vec3& a, const Vec3& b, const Vec3& c, double margin,
                         TriangleHit& hit) {
  const Tool& tool = *t.tool;
  MprBudget budget;
  t.budget = &budget;
  const TriangleObject tri{{a, b, c}, closest_on_triangle(t.centre, a, b, c).point, &budget};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = tool_support;
  ccd.center1 = tool_centre;
  ccd.support2 = triangle_support_ccd;
  ccd.center2 = triangle_centre;
  ccd.max_iterations = kMprMaxIterations;
  // libccd's tolerance is absolute (in metres here): scale it to the shapes.
  const double size = tool_bounds(tool, margin).size().norm() + longest_edge(a, b, c);
  ccd.mpr_tolerance = 1e-10 * size;
  ccd_real_t depth = 0;
  ccd_vec3_t dir, pos;
  const int met = ccdMPRPenetration(&t, &tri, &ccd, &depth, &dir, &pos);
  if (budget.spent()) return false;  // MPR did not settle (degenerate shapes): no contact found
  // Depth 0 or no direction: the shapes merely touch, which is no contact at a zero margin.
  if (met != 0 || !(depth > 0)) return false;

  const Separation least = least_separation(core_polytope(tool, t.R), a, b, c);
  const double gap = -(least.depth + rounding(tool));
  if (!(gap < margin)) return false;
  const TrianglePoint on = closest_on_triangle(from_ccd(&pos), a, b, c);
  hit = {on.point, on.weights, least.normal, gap};
  return true;
}

bool convex_contact(const Tool& tool, const Vec3& a, const Vec3& b, const Vec3& c, double margin, TriangleHit& hit) {
  if (tool.shape == ToolShape::ConvexHull && !tool.hull)
    fail(Errc::WrongState, "the convex hull tool was not prepared (prepare_tool_shape)");
  // MPR runs on the tool inflated by the margin, so that near misses are found as overlaps.
  ToolObject t{&tool, tool.orientation.toRotationMatrix(), margin, tool.position};
  if (tool.shape == ToolShape::ConvexHull) t.centre = tool.position + t.R * tool.hull->centre;
  const TriangleObject tri{{a, b, c}, (a + b + c) / 3.0};

  // Exact distance between the tool's core and the triangle: when apart, the contact follows.
  const double size = tool_bounds(tool, 0).size().norm() + longest_edge(a, b, c);
  auto core = [&](const Vec3& d) -> Vec3 { return tool.position + t.R * core_support(tool, t.R.transpose() * d); };
  auto triangle = [&](const Vec3& d) -> Vec3 { return triangle_support(tri, d); };
  const GjkResult g = gjk_distance(core, triangle, t.centre - tri.centre, 1e-9 * size);
  if (!g.intersecting) {
    const double gap = g.distance - rounding(tool);
    if (!(gap < margin)) return false;
    const TrianglePoint on = closest_on_triangle(g.point_b, a, b, c);  // its weights
    hit = {on.point, on.weights, (g.point_b - g.point_a) / g.distance, gap};
    return true;
  }
  return penetration_contact(t, a, b, c, margin, hit);
}

}  // namespace

bool collide_triangle(const Tool& tool, const Vec3& a, const Vec3& b, const Vec3& c, double margin, TriangleHit& hit) {
  switch (tool.shape) {
    case ToolShape::Sphere: return sphere_contact(tool, a, b, c, margin, hit);
    case ToolShape::Plane: return plane_contact(tool, a, b, c, margin, hit);
    case ToolShape::Capsule:
    case ToolShape::Box:
    case ToolShape::ConvexHull: return convex_contact(tool, a, b, c, margin, hit);
  }
  fail(Errc::InvalidArgument, "tool shape " + std::to_string(int(tool.shape)) + " is not a ToolShape");
}

}  // namespace mica
