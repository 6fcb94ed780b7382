// SPDX-License-Identifier: Apache-2.0
#include "collision/pseudo_normals.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace mica {

namespace {

// The angle at corner a of triangle abc (0 for a degenerate corner).
double corner_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 u = b - a, v = c - a;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

}  // namespace

void SurfacePseudoNormals::build(const std::vector<Tri>& triangles, size_t node_count) {
  std::map<std::pair<int32_t, int32_t>, int32_t> ids;
  triangle_edges_.resize(triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int32_t i = triangles[f][k], j = triangles[f][(k + 1) % 3];
      const auto key = std::minmax(i, j);
      const auto found = ids.emplace(std::make_pair(key.first, key.second), int32_t(ids.size())).first;
      triangle_edges_[f][k] = found->second;
    }
  edge_.assign(ids.size(), Vec3::Zero());
  vertex_.assign(node_count, Vec3::Zero());
}

void SurfacePseudoNormals::update(const Vec3List& x, const std::vector<Tri>& triangles) {
  for (Vec3& n : edge_) n.setZero();
  for (const Tri& t : triangles)
    for (int32_t i : t) vertex_[i].setZero();
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    const double length = n.norm();
    if (!(length > 0)) continue;  // a collapsed triangle has no direction to give
    const Vec3 unit = n / length;
    for (int k = 0; k < 3; ++k) {
      edge_[triangle_edges_[f][k]] += unit;
      vertex_[t[k]] += corner_angle(x[t[k]], x[t[(k + 1) % 3]], x[t[(k + 2) % 3]]) * unit;
    }
  }
}

Vec3 SurfacePseudoNormals::at(int32_t tri, const Tri& t, const Vec3& w, const Vec3& face) const {
  const int zeros = int(w[0] == 0) + int(w[1] == 0) + int(w[2] == 0);
  if (zeros == 0) return face;
  if (zeros == 1) {
    int opposite = 0;
    while (w[opposite] != 0) ++opposite;
    return edge_[triangle_edges_[tri][(opposite + 1) % 3]];
  }
  int corner = 0;
  while (w[corner] == 0) ++corner;
  return vertex_[t[corner]];
}

}  // namespace mica
