// SPDX-License-Identifier: Apache-2.0
#include "collision/closest_point.hpp"

#include <algorithm>

namespace mica {

double closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (!(len2 > 0)) return 0;
  return std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
}

void closest_between_segments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, double& s, double& t) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  if (!(a > 0) && !(e > 0)) {
    s = t = 0;
    return;
  }
  if (!(a > 0)) {
    s = 0;
    t = std::clamp(f / e, 0.0, 1.0);
    return;
  }
  const double c = d1.dot(r);
  if (!(e > 0)) {
    t = 0;
    s = std::clamp(-c / a, 0.0, 1.0);
    return;
  }
  const double b = d1.dot(d2), denom = a * e - b * b;
  s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1) {
    t = 1;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
}

TrianglePoint closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();  // (2 area)^2
  const double edges2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  // Project onto the plane when the triangle has a well-defined one (not a needle or a point).
  if (area2 > 1e-20 * edges2 * edges2) {
    const Vec3 q = p - n * (n.dot(p - a) / area2);
    const double wa = n.dot((b - q).cross(c - q)) / area2;
    const double wb = n.dot((c - q).cross(a - q)) / area2;
    const double wc = 1.0 - wa - wb;
    if (wa >= 0 && wb >= 0 && wc >= 0) return {wa * a + wb * b + wc * c, Vec3(wa, wb, wc)};
  }
  // Outside the triangle's prism: the closest point is on an edge.
  const double tab = closest_on_segment(p, a, b);
  const double tbc = closest_on_segment(p, b, c);
  const double tca = closest_on_segment(p, c, a);
  const TrianglePoint candidates[3] = {
      {a + tab * (b - a), Vec3(1 - tab, tab, 0)},
      {b + tbc * (c - b), Vec3(0, 1 - tbc, tbc)},
      {c + tca * (a - c), Vec3(tca, 0, 1 - tca)},
  };
  int best = 0;
  for (int k = 1; k < 3; ++k)
    if ((candidates[k].point - p).squaredNorm() < (candidates[best].point - p).squaredNorm()) best = k;
  return candidates[best];
}

}  // namespace mica
