// SPDX-License-Identifier: Apache-2.0
#include "collision/convex_hull.hpp"

#include <algorithm>
#include <numeric>

#include "core/error.hpp"

namespace mica {

namespace {

using Vec2 = Eigen::Vector2d;

// > 0 when o, a, b turn counter-clockwise.
double turn(const Vec2& o, const Vec2& a, const Vec2& b) {
  const Vec2 u = a - o, v = b - o;
  return u.x() * v.y() - u.y() * v.x();
}

// Indices of the corners of the 2D convex hull of `pts`, counter-clockwise, with collinear and
// repeated points dropped (Andrew's monotone chain).
std::vector<int> convex_polygon(const std::vector<Vec2>& pts) {
  const int n = int(pts.size());
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return pts[a].x() < pts[b].x() || (pts[a].x() == pts[b].x() && pts[a].y() < pts[b].y());
  });
  std::vector<int> ring;
  for (int pass = 0; pass < 2; ++pass) {  // lower chain left to right, then upper chain back
    const size_t start = ring.size();
    for (int k = 0; k < n; ++k) {
      const int i = order[pass == 0 ? k : n - 1 - k];
      while (ring.size() >= start + 2 && turn(pts[ring[ring.size() - 2]], pts[ring.back()], pts[i]) <= 0)
        ring.pop_back();
      ring.push_back(i);
    }
    ring.pop_back();  // each chain's last point starts the other one
  }
  return ring;
}

// Height of the thickest tetrahedron found greedily: 0 for coplanar points.
double thickness(const Vec3List& p) {
  auto farthest = [&](auto&& distance) {
    size_t best = 0;
    for (size_t i = 1; i < p.size(); ++i)
      if (distance(p[i]) > distance(p[best])) best = i;
    return best;
  };
  const Vec3 a = p[0];
  const Vec3 b = p[farthest([&](const Vec3& x) { return (x - a).norm(); })];
  const Vec3 ab = (b - a).normalized();
  auto off_line = [&](const Vec3& x) { return ((x - a) - ab * ab.dot(x - a)).norm(); };
  const Vec3 c = p[farthest(off_line)];
  const Vec3 n = ab.cross(c - a).normalized();
  if (!n.allFinite()) return 0;  // collinear
  auto off_plane = [&](const Vec3& x) { return std::abs(n.dot(x - a)); };
  return off_plane(p[farthest(off_plane)]);
}

}  // namespace

std::shared_ptr<const HullData> build_convex_hull(const Vec3List& points, const std::string& field) {
  const size_t n = points.size();
  if (n < 4)
    fail(Errc::InvalidArgument, field + " has " + std::to_string(n) + " points; a hull needs at least 4 that are not coplanar");
  if (n > kMaxHullPoints)
    fail(Errc::InvalidArgument, field + " has " + std::to_string(n) + " points; at most " +
                                    std::to_string(kMaxHullPoints) + " are supported");
  Vec3 lo = points[0], hi = points[0];
  for (size_t i = 0; i < n; ++i) {
    if (!points[i].allFinite()) fail(Errc::InvalidArgument, field + "[" + std::to_string(i) + "] is not finite");
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  const double size = (hi - lo).norm();
  if (!(size > 0) || !(thickness(points) > 1e-6 * size))
    fail(Errc::InvalidArgument, field + " are (nearly) coplanar: their hull has no volume");

  const double tol = 1e-9 * size;  // points this close to a plane lie on it
  auto hull = std::make_shared<HullData>();
  std::vector<uint64_t> seen;  // the set of points on each face found so far, one bit per point
  uint64_t corners = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      for (size_t k = j + 1; k < n; ++k) {
        Vec3 normal = (points[j] - points[i]).cross(points[k] - points[i]);
        const double length = normal.norm();
        if (!(length > 1e-12 * size * size)) continue;  // (nearly) collinear: no reliable plane
        normal /= length;
        double offset = normal.dot(points[i]);
        bool above = false, below = false;
        uint64_t on = 0;
        for (size_t m = 0; m < n; ++m) {
          const double s = normal.dot(points[m]) - offset;
          if (s > tol) above = true;
          else if (s < -tol) below = true;
          else on |= uint64_t(1) << m;
        }
        if (above && below) continue;  // the plane cuts the hull
        if (above) {
          normal = -normal;
          offset = -offset;
        }
        if (std::find(seen.begin(), seen.end(), on) != seen.end()) continue;
        seen.push_back(on);

        // The face is the 2D hull of the points on its plane, in a basis (u, v) with u x v = normal.
        const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
        std::vector<int> index;
        std::vector<Vec2> flat;
        for (size_t m = 0; m < n; ++m)
          if (on >> m & 1) {
            index.push_back(int(m));
            flat.emplace_back(u.dot(points[m]), v.dot(points[m]));
          }
        const std::vector<int> ring = convex_polygon(flat);
        if (ring.size() < 3) continue;
        HullFace face{normal, offset, {}, {}};
        for (int r : ring) {
          face.polygon.push_back(points[index[r]]);
          corners |= uint64_t(1) << index[r];
        }
        hull->faces.push_back(std::move(face));
      }

  hull->centre = Vec3::Zero();
  for (size_t m = 0; m < n; ++m) {
    const Vec3List& v = hull->vertices;
    const bool repeated = std::find(v.begin(), v.end(), points[m]) != v.end();  // faces may pick either copy
    if (corners >> m & 1 && !repeated) {
      hull->vertices.push_back(points[m]);
      hull->centre += points[m];
    }
  }
  if (hull->faces.size() < 4) fail(Errc::InvalidArgument, field + " span no solid hull");
  hull->centre /= double(hull->vertices.size());

  const Vec3List& v = hull->vertices;
  for (HullFace& f : hull->faces)
    for (size_t k = 0; k < f.polygon.size(); ++k)
      f.corners.push_back(int32_t(std::find(v.begin(), v.end(), f.polygon[k]) - v.begin()));
  for (const HullFace& f : hull->faces)
    for (size_t k = 0; k < f.corners.size(); ++k) {
      const int32_t a = f.corners[k], b = f.corners[(k + 1) % f.corners.size()];
      const std::array<int32_t, 2> e{std::min(a, b), std::max(a, b)};
      if (std::find(hull->edges.begin(), hull->edges.end(), e) == hull->edges.end()) hull->edges.push_back(e);
    }
  for (const HullFace& f : hull->faces)
    for (size_t k = 0; k < f.polygon.size(); ++k) {
      const Vec3 d = (f.polygon[(k + 1) % f.polygon.size()] - f.polygon[k]).normalized();
      bool known = false;
      for (const Vec3& e : hull->edge_directions) known = known || e.cross(d).norm() <= 1e-9;
      if (!known) hull->edge_directions.push_back(d);
    }
  return hull;
}

}  // namespace mica
