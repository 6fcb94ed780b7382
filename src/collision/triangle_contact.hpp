// SPDX-License-Identifier: Apache-2.0
// Narrow phase between a tool and one surface triangle of a body.
#pragma once
#include "collision/tool.hpp"

namespace mica {

struct TriangleHit {
  Vec3 point;    // m, on the triangle
  Vec3 weights;  // barycentric weights of `point` in (a, b, c): each in [0, 1], sum 1
  Vec3 normal;   // unit, from the tool into the body: the direction the triangle must move to separate
  double gap;    // m, signed distance: negative when penetrating
};

// The deepest contact between the tool and triangle abc when their gap is below margin; false
// (and `hit` untouched) otherwise. Sphere and Plane are closed forms. Capsule, Box and ConvexHull
// are polytope cores (segment, box, hull) rounded by a radius (the capsule's, or 0): while the core
// and the triangle are apart, GJK gives their distance and closest points; once they meet, the
// separating axes give the least translation (depth and normal) and libccd's MPR a point both
// shapes share (the contact point). Gaps and normals are exact to rounding for every shape.
bool collide_triangle(const Tool& tool, const Vec3& a, const Vec3& b, const Vec3& c, double margin, TriangleHit& hit);

}  // namespace mica
