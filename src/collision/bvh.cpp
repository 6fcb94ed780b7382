// SPDX-License-Identifier: Apache-2.0
#include "collision/bvh.hpp"

#include <algorithm>
#include <numeric>
#include <string>

#include "core/error.hpp"

namespace mica {

void TriangleBvh::build(const Vec3List& x, const std::vector<Tri>& tris) {
  const int32_t n = int32_t(x.size());
  for (size_t t = 0; t < tris.size(); ++t)
    for (int32_t v : tris[t])
      if (v < 0 || v >= n)
        fail(Errc::OutOfRange, "triangle " + std::to_string(t) + " refers to node " + std::to_string(v) +
                                   ", outside 0.." + std::to_string(n - 1));
  tris_ = tris;
  nodes_needed_ = 0;
  for (const Tri& f : tris) nodes_needed_ = std::max({nodes_needed_, f[0] + 1, f[1] + 1, f[2] + 1});
  tri_boxes_.resize(tris.size());
  order_.resize(tris.size());
  std::iota(order_.begin(), order_.end(), 0);
  nodes_.clear();
  if (tris.empty()) return;

  Vec3List centroids(tris.size());
  for (size_t t = 0; t < tris.size(); ++t) {
    const Tri& f = tris[t];
    tri_boxes_[t] = Aabb::of(x[f[0]], x[f[1]], x[f[2]]);
    centroids[t] = (x[f[0]] + x[f[1]] + x[f[2]]) / 3.0;
  }
  nodes_.reserve(tris.size());  // splits leave 2+ triangles per leaf: never more nodes than triangles
  build_node(0, int32_t(tris.size()), centroids);
}

int32_t TriangleBvh::build_node(int32_t first, int32_t count, const Vec3List& centroids) {
  const int32_t index = int32_t(nodes_.size());
  nodes_.emplace_back();
  if (count <= kLeafSize) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    fit_leaf(nodes_[index]);
    return index;
  }
  Aabb spread;  // of the centroids: the axis along which they are farthest apart is split
  for (int32_t k = first; k < first + count; ++k) spread.add(centroids[order_[k]]);
  int axis = 0;
  spread.size().maxCoeff(&axis);
  const auto begin = order_.begin() + first;
  const int32_t half = count / 2;
  std::nth_element(begin, begin + half, begin + count,
                   [&](int32_t a, int32_t b) { return centroids[a][axis] < centroids[b][axis]; });
  // Children are built after their parent, so they always sit at larger indices.
  const int32_t left = build_node(first, half, centroids);
  const int32_t right = build_node(first + half, count - half, centroids);
  Node& node = nodes_[index];  // re-fetched: the recursion may have reallocated nodes_
  node.left = left;
  node.right = right;
  node.box = nodes_[left].box;
  node.box.add(nodes_[right].box);
  return index;
}

void TriangleBvh::fit_leaf(Node& node) const {
  node.box = Aabb();
  for (int32_t k = node.first; k < node.first + node.count; ++k) node.box.add(tri_boxes_[order_[k]]);
}

void TriangleBvh::refit(const Vec3List& x) {
  if (int32_t(x.size()) < nodes_needed_)
    fail(Errc::OutOfRange, "refit with " + std::to_string(x.size()) + " nodes; the triangles use " +
                               std::to_string(nodes_needed_));
  for (size_t t = 0; t < tris_.size(); ++t) {
    const Tri& f = tris_[t];
    tri_boxes_[t] = Aabb::of(x[f[0]], x[f[1]], x[f[2]]);
  }
  for (size_t i = nodes_.size(); i-- > 0;) {
    Node& node = nodes_[i];
    if (node.count > 0) {
      fit_leaf(node);
    } else {
      node.box = nodes_[node.left].box;
      node.box.add(nodes_[node.right].box);
    }
  }
}

}  // namespace mica
