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

// The unit normal of triangle t at x, false for a collapsed one (no direction to give).
bool unit_normal(const Vec3List& x, const Tri& t, Vec3& unit) {
  const Vec3 n = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
  const double length = n.norm();
  if (!(length > 0)) return false;
  unit = n / length;
  return true;
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
  // The incidence lists, by counting then filling in triangle order.
  edge_start_.assign(ids.size() + 1, 0);
  node_start_.assign(node_count + 1, 0);
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      ++edge_start_[size_t(triangle_edges_[f][k]) + 1];
      ++node_start_[size_t(triangles[f][k]) + 1];
    }
  for (size_t e = 0; e < ids.size(); ++e) edge_start_[e + 1] += edge_start_[e];
  for (size_t i = 0; i < node_count; ++i) node_start_[i + 1] += node_start_[i];
  edge_triangle_.resize(size_t(edge_start_.back()));
  node_corner_.resize(size_t(node_start_.back()));
  std::vector<int32_t> edge_at(edge_start_.begin(), edge_start_.end() - 1), node_at(node_start_.begin(), node_start_.end() - 1);
  for (size_t f = 0; f < triangles.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      edge_triangle_[size_t(edge_at[size_t(triangle_edges_[f][k])]++)] = int32_t(f);
      node_corner_[size_t(node_at[size_t(triangles[f][k])]++)] = {int32_t(f), k};
    }
}

Vec3 SurfacePseudoNormals::at(int32_t tri, const Vec3& w, const Vec3& face, const Vec3List& x,
                              const std::vector<Tri>& triangles) const {
  const int zeros = int(w[0] == 0) + int(w[1] == 0) + int(w[2] == 0);
  if (zeros == 0) return face;
  Vec3 sum = Vec3::Zero(), unit;
  if (zeros == 1) {  // on an edge: the sum of its faces' unit normals
    int opposite = 0;
    while (w[opposite] != 0) ++opposite;
    const int32_t e = triangle_edges_[tri][(opposite + 1) % 3];
    for (int32_t q = edge_start_[e]; q < edge_start_[e + 1]; ++q)
      if (unit_normal(x, triangles[edge_triangle_[q]], unit)) sum += unit;
    return sum;
  }
  int corner = 0;  // on a corner: its faces' unit normals weighted by their angles there
  while (w[corner] == 0) ++corner;
  const int32_t i = triangles[tri][corner];
  for (int32_t q = node_start_[i]; q < node_start_[i + 1]; ++q) {
    const Tri& u = triangles[node_corner_[q][0]];
    const int k = node_corner_[q][1];
    if (unit_normal(x, u, unit)) sum += corner_angle(x[u[k]], x[u[(k + 1) % 3]], x[u[(k + 2) % 3]]) * unit;
  }
  return sum;
}

}  // namespace mica
