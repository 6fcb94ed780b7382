// SPDX-License-Identifier: Apache-2.0
// Closest points on segments and triangles, with the barycentric weights of the result.
#pragma once
#include "core/types.hpp"

namespace mica {

// Parameter t in [0, 1] of the point of segment a + t (b - a) closest to p (0 for a point-like segment).
double closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b);

// Parameters s, t in [0, 1] of the closest points p0 + s (p1 - p0) and q0 + t (q1 - q0) of two
// segments (Ericson, Real-Time Collision Detection, 5.1.9); parallel segments get one pair of
// the many.
void closest_between_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, double& s, double& t);

struct TrianglePoint {
  Vec3 point;    // on the triangle
  Vec3 weights;  // barycentric: point = w0 a + w1 b + w2 c, each in [0, 1], sum 1
};

// The point of triangle abc closest to p; degenerate (flat or point-like) triangles are handled
// as their edges.
TrianglePoint closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace mica
