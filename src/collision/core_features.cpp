// SPDX-License-Identifier: Apache-2.0
#include "collision/core_features.hpp"

#include <algorithm>
#include <cmath>

#include "collision/closest_point.hpp"
#include "core/error.hpp"

namespace mica {

namespace {

// Below this distance (m) a pair touches and its direction comes from the surface instead.
constexpr double kTouching = 1e-12;

void set_direction(const Vec3& d, double radius, FeatureHit& hit) {
  const double dist = d.norm();
  hit.normal = dist > kTouching ? Vec3(d / dist) : Vec3::Zero();
  hit.gap = dist - radius;
}

}  // namespace

void tool_core(const Tool& tool, ToolCore& core) {
  const Mat3 R = tool.orientation.toRotationMatrix();
  core.corners.clear();
  core.edges.clear();
  core.radius = 0;
  core.polytope = nullptr;
  switch (tool.shape) {
    case ToolShape::Sphere:
      core.corners.push_back(tool.position);
      core.radius = tool.radius;
      return;
    case ToolShape::Capsule:
      core.corners.push_back(tool.position + tool.half_length * R.col(2));
      core.corners.push_back(tool.position - tool.half_length * R.col(2));
      core.edges.push_back({0, 1});
      core.radius = tool.radius;
      return;
    case ToolShape::Box:
    case ToolShape::ConvexHull:
      if (!tool.core) break;
      core.polytope = tool.core.get();
      core.rotation = R;
      core.position = tool.position;
      for (const Vec3& v : tool.core->vertices) core.corners.push_back(tool.position + R * v);
      core.edges.assign(tool.core->edges.begin(), tool.core->edges.end());
      core.radius = tool.rounding;
      return;
    case ToolShape::Plane: return;  // no core: a plane meets each node
  }
  fail(Errc::Internal, "a box or hull without its core (prepare_tool_shape makes it)");
}

bool node_core(const ToolCore& core, const Vec3& x, FeatureHit& hit, int32_t& face, int32_t& edge) {
  const HullData& P = *core.polytope;
  const Vec3 p = core.rotation.transpose() * (x - core.position);  // in the tool frame
  face = edge = -1;
  hit.weights = Vec3(1, 0, 0);
  hit.point = x;
  // Inside the core: its nearest face (the node is deeper than the rounding).
  double highest = -HUGE_VAL;
  for (size_t f = 0; f < P.faces.size(); ++f) {
    const double height = P.faces[f].normal.dot(p) - P.faces[f].offset;
    if (height > highest) {
      highest = height;
      face = int32_t(f);
    }
  }
  Vec3 from = P.faces[size_t(face)].normal;  // the direction from the core's nearest point to p
  double distance = highest;
  if (highest > 0) {
    // Outside: the nearest of the faces p projects into, the edges and the corners.
    distance = HUGE_VAL;
    face = -1;
    bool corner = false;
    auto consider = [&](double d, const Vec3& direction, int32_t f, int32_t e) {
      if (d >= distance) return;
      distance = d;
      from = direction;
      face = f;
      edge = e;
      corner = f < 0 && e < 0;
    };
    for (size_t f = 0; f < P.faces.size(); ++f) {
      const HullFace& F = P.faces[f];
      const double height = F.normal.dot(p) - F.offset;
      if (!(height > 0)) continue;
      const Vec3 foot = p - height * F.normal;
      bool within = true;
      for (size_t k = 0; within && k < F.polygon.size(); ++k)
        within = (F.polygon[(k + 1) % F.polygon.size()] - F.polygon[k]).cross(foot - F.polygon[k]).dot(F.normal) >= 0;
      if (within) consider(height, F.normal, int32_t(f), -1);
    }
    for (size_t e = 0; e < P.edges.size(); ++e) {
      const Vec3 &a = P.vertices[size_t(P.edges[e][0])], &b = P.vertices[size_t(P.edges[e][1])];
      const double t = closest_on_segment(p, a, b);
      if (!(t > 0 && t < 1)) continue;  // at an end: a corner's
      const Vec3 off = p - (a + t * (b - a));
      consider(off.norm(), off.normalized(), -1, int32_t(e));
    }
    for (const Vec3& v : P.vertices) consider((p - v).norm(), (p - v).normalized(), -1, -1);
    if (corner) return false;
  }
  hit.normal = core.rotation * from;
  hit.gap = distance - core.radius;
  return hit.normal.allFinite();
}

bool corner_triangle(const Vec3& corner, double radius, const Vec3& a, const Vec3& b, const Vec3& c, FeatureHit& hit) {
  const TrianglePoint q = closest_on_triangle(corner, a, b, c);
  hit.weights = q.weights;
  hit.point = q.point;
  set_direction(q.point - corner, radius, hit);
  return hit.point.allFinite();
}

bool edge_edge(const Vec3& p0, const Vec3& p1, double radius, const Vec3& e0, const Vec3& e1, FeatureHit& hit) {
  double s = 0, t = 0;
  closest_between_segments(p0, p1, e0, e1, s, t);
  // At an end of either edge the pair is a corner's or a node's (made elsewhere).
  if (!(s > 0 && s < 1 && t > 0 && t < 1)) return false;
  hit.weights = Vec3(1 - t, t, 0);
  hit.point = e0 + t * (e1 - e0);
  set_direction(hit.point - (p0 + s * (p1 - p0)), radius, hit);
  return hit.point.allFinite();
}

void orient_by_surface(const Vec3& outward, double radius, double depth, FeatureHit& hit) {
  const double dist = hit.gap + radius;
  if (hit.normal.isZero()) {  // touching: the body point moves in along the surface's normal
    hit.normal = -outward.normalized();
    hit.gap = -radius;
  } else if (dist + radius <= depth && hit.normal.dot(outward) > 0) {
    // A core point just behind the surface is inside the body: the body point must move past it.
    hit.normal = -hit.normal;
    hit.gap = -dist - radius;
  }
}

}  // namespace mica
