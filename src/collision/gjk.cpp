// SPDX-License-Identifier: Apache-2.0
#include "collision/gjk.hpp"

#include <cmath>
#include <initializer_list>

#include "collision/closest_point.hpp"

namespace mica {

namespace {

// Keeps the vertices listed in `keep` with the given weights, dropping those of zero weight.
void keep_only(GjkSimplex& s, std::initializer_list<int> keep, const double* weights) {
  GjkSimplex out;
  int k = 0;
  for (int i : keep) {
    if (weights[k] > 0) {
      out.v[out.size] = s.v[i];
      out.weight[out.size] = weights[k];
      ++out.size;
    }
    ++k;
  }
  s = out;
}

// Whether the origin lies on the same side of plane (p, q, r) as point o (or on the plane).
bool same_side(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& o) {
  const Vec3 n = (q - p).cross(r - p);
  return n.dot(-p) * n.dot(o - p) >= 0;
}

}  // namespace

bool reduce_to_nearest(GjkSimplex& s) {
  const Vec3 origin = Vec3::Zero();
  const Vec3 w0 = s.v[0].w();
  switch (s.size) {
    case 1:
      s.weight[0] = 1;
      return true;
    case 2: {
      const double t = closest_on_segment(origin, w0, s.v[1].w());
      const double w[2] = {1 - t, t};
      keep_only(s, {0, 1}, w);
      return true;
    }
    case 3: {
      const Vec3 w = closest_on_triangle(origin, w0, s.v[1].w(), s.v[2].w()).weights;
      keep_only(s, {0, 1, 2}, w.data());
      return true;
    }
    default: {
      const Vec3 p[4] = {w0, s.v[1].w(), s.v[2].w(), s.v[3].w()};
      const bool flat = std::abs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0])) == 0;
      if (!flat && same_side(p[1], p[2], p[3], p[0]) && same_side(p[0], p[2], p[3], p[1]) &&
          same_side(p[0], p[1], p[3], p[2]) && same_side(p[0], p[1], p[2], p[3]))
        return false;
      // Outside: the nearest point is on one of the four faces.
      const int faces[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
      int best = 0;
      TrianglePoint nearest[4];
      for (int f = 0; f < 4; ++f) {
        nearest[f] = closest_on_triangle(origin, p[faces[f][0]], p[faces[f][1]], p[faces[f][2]]);
        if (nearest[f].point.squaredNorm() < nearest[best].point.squaredNorm()) best = f;
      }
      keep_only(s, {faces[best][0], faces[best][1], faces[best][2]}, nearest[best].weights.data());
      return true;
    }
  }
}

}  // namespace mica
