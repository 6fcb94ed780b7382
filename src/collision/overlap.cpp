// SPDX-License-Identifier: Apache-2.0
#include "collision/overlap.hpp"

#include <algorithm>

#include "collision/nearest_surface_point.hpp"

namespace mica {

Penetration deepest_penetration(const SurfaceView& a, const SurfaceView& b) {
  Penetration deepest;
  if (a.bvh->empty() || b.bvh->empty()) return deepest;
  const Aabb& bounds = b.bvh->bounds();
  const double span = bounds.size().norm();  // no surface point is farther from a point within the bounds
  for (int32_t node : *a.nodes) {
    const Vec3& p = (*a.x)[node];
    if (!bounds.contains(p)) continue;  // outside b's bounds: outside b
    // The nearest surface point at any distance: widen the search until it finds one within its
    // reach (exact then), or covers all of b.
    NearestSurfacePoint n;
    double reach = std::max(b.depth, 1e-3 * span);
    for (int k = 0; k < 64; ++k, reach *= 2) {
      n = nearest_surface_point(b, p, reach);
      if ((n.tri >= 0 && n.distance <= reach) || reach > span) break;
    }
    if (n.tri < 0) continue;
    const bool inside = (p - n.point.point).dot(n.outward) < 0;
    if (inside && n.distance > deepest.depth) deepest = {n.distance, node};
  }
  return deepest;
}

}  // namespace mica
