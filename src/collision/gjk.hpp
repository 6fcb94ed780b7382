// SPDX-License-Identifier: Apache-2.0
// Distance between two convex polytopes given by their support functions (GJK), with the closest
// points. Polytopes make it exact up to rounding, in a finite number of steps. Written here beside
// libccd because libccd answers whether two shapes intersect and how deep (MPR, GJK + EPA), not how
// far apart they are: a rounded tool's core and a triangle are separated by its rounding radius when
// they touch, and the contact needs that distance and its closest points (triangle_contact.cpp).
#pragma once
#include <array>

#include "core/types.hpp"

namespace mica {

struct GjkResult {
  bool intersecting = false;  // the shapes share a point (or are closer than `touch`)
  double distance = 0;        // m, between the shapes when not intersecting
  Vec3 point_a, point_b;      // the closest points of A and of B when not intersecting
};

// One corner of the simplex inside the Minkowski difference A - B, with the points it came from.
struct GjkVertex {
  Vec3 a, b;
  Vec3 w() const { return a - b; }
};

struct GjkSimplex {
  std::array<GjkVertex, 4> v;
  std::array<double, 4> weight{};  // barycentric weights of the point nearest the origin
  int size = 0;
};

// Shrinks the simplex to the vertex, edge or triangle holding its point nearest the origin and sets
// that point's weights; returns false when a full tetrahedron contains the origin.
bool reduce_to_nearest(GjkSimplex& s);

// support_a(d), support_b(d): a farthest point of A (of B) along d. `start` is a first guess of
// the direction from B to A; distances below `touch` (m) count as intersecting.
template <class SupportA, class SupportB>
GjkResult gjk_distance(const SupportA& support_a, const SupportB& support_b, const Vec3& start, double touch) {
  auto corner = [&](const Vec3& d) {
    const Vec3 back = -d;
    return GjkVertex{support_a(d), support_b(back)};
  };
  GjkSimplex s;
  const Vec3 first = start.squaredNorm() > 0 ? Vec3(-start) : Vec3(Vec3::UnitX());
  s.v[0] = corner(first);
  s.weight[0] = 1;
  s.size = 1;
  Vec3 v = s.v[0].w();  // the point of A - B nearest the origin found so far
  GjkResult r;
  for (int iteration = 0; iteration < 64; ++iteration) {
    if (v.norm() <= touch) {
      r.intersecting = true;
      return r;
    }
    const Vec3 towards_origin = -v;
    const GjkVertex next = corner(towards_origin);
    // Stop when the new support point gets no nearer the origin than v (relative to rounding) or repeats.
    bool repeated = false;
    for (int i = 0; i < s.size; ++i) repeated = repeated || next.w() == s.v[i].w();
    if (repeated || v.squaredNorm() - v.dot(next.w()) <= 1e-12 * v.squaredNorm()) break;
    s.v[s.size++] = next;
    if (!reduce_to_nearest(s)) {
      r.intersecting = true;
      return r;
    }
    v = Vec3::Zero();
    for (int i = 0; i < s.size; ++i) v += s.weight[i] * s.v[i].w();
  }
  r.distance = v.norm();
  r.point_a = r.point_b = Vec3::Zero();
  for (int i = 0; i < s.size; ++i) {
    r.point_a += s.weight[i] * s.v[i].a;
    r.point_b += s.weight[i] * s.v[i].b;
  }
  return r;
}

}  // namespace mica
