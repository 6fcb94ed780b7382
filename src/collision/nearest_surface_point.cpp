// SPDX-License-Identifier: Apache-2.0
#include "collision/nearest_surface_point.hpp"

namespace mica {

NearestSurfacePoint nearest_surface_point(const SurfaceView& s, const Vec3& p, double reach) {
  const Vec3List& x = *s.x;
  NearestSurfacePoint n;
  s.bvh->query(Aabb{p, p}.inflated(reach), [&](int32_t tri) {
    const Tri& t = (*s.triangles)[tri];
    const TrianglePoint q = closest_on_triangle(p, x[t[0]], x[t[1]], x[t[2]]);
    const double d = (p - q.point).norm();
    if (d < n.distance) {
      n.distance = d;
      n.tri = tri;
      n.point = q;
    }
  });
  if (n.tri < 0) return n;
  const Tri& t = (*s.triangles)[n.tri];
  n.face = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).normalized();
  n.outward = s.normals->at(n.tri, n.point.weights, n.face, x, *s.triangles);
  return n;
}

}  // namespace mica
