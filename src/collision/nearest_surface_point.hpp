// SPDX-License-Identifier: Apache-2.0
// The nearest point of a body's surface to a point, and which side of the surface the point is on.
#pragma once
#include <cmath>

#include "collision/closest_point.hpp"
#include "collision/contact.hpp"

namespace mica {

// The nearest point of a surface to p within reach (tri -1: none), and the outward
// pseudo-normal of the face, edge or vertex it lies on (which side of the surface p is on).
struct NearestSurfacePoint {
  int32_t tri = -1;
  TrianglePoint point{};
  double distance = HUGE_VAL;
  Vec3 face, outward;  // the triangle's normal, the pseudo-normal at the point
};

// Looks at the triangles whose boxes come within `reach` of p: the result is the nearest point of
// the surface whenever its distance is at most `reach` (a farther result may not be the nearest).
NearestSurfacePoint nearest_surface_point(const SurfaceView& s, const Vec3& p, double reach);

}  // namespace mica
