#include "collision/core_features.hpp"

#include <algorithm>

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
    case ToolShape::Plane: break;
  }
  fail(Errc::Internal, "only a sphere's and a capsule's contacts are made from their core");
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
