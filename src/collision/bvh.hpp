// SPDX-License-Identifier: Apache-2.0
// An AABB tree over a body's surface triangles: built once from the rest shape, refitted to the
// deformed positions every step (the topology of the tree stays; only the boxes move).
#pragma once
#include <array>
#include <vector>

#include "collision/aabb.hpp"
#include "core/types.hpp"

namespace mica {

class TriangleBvh {
 public:
  // Median split on the longest axis of the triangle centroids, leaves of at most kLeafSize
  // triangles. Throws Error(OutOfRange) if a triangle refers to a node outside x.
  void build(const Vec3List& x, const std::vector<Tri>& tris);

  // Recomputes every box bottom-up from new positions of the same nodes; allocates nothing.
  // Throws Error(OutOfRange) if x is shorter than at build.
  void refit(const Vec3List& x);

  // Calls visit(triangle index) once for each triangle whose own box overlaps `box`.
  template <class F>
  void query(const Aabb& box, F&& visit) const;

  bool empty() const { return nodes_.empty(); }
  const Aabb& bounds() const { return nodes_.front().box; }  // of the whole tree; not for an empty one
  size_t node_count() const { return nodes_.size(); }

  static constexpr int32_t kLeafSize = 4;

 private:
  struct Node {
    Aabb box;
    int32_t left = -1, right = -1;  // children, inner nodes only
    int32_t first = 0, count = 0;   // range in order_, leaves only (count > 0)
  };

  int32_t build_node(int32_t first, int32_t count, const Vec3List& centroids);
  void fit_leaf(Node& node) const;

  std::vector<Tri> tris_;
  int32_t nodes_needed_ = 0;    // 1 + the largest node index the triangles use
  std::vector<Aabb> tri_boxes_;  // per triangle, refreshed by refit
  std::vector<int32_t> order_;   // triangle indices grouped by leaf
  std::vector<Node> nodes_;      // a parent always precedes its children: refit runs backwards
};

template <class F>
void TriangleBvh::query(const Aabb& box, F&& visit) const {
  if (nodes_.empty()) return;
  // Median splits halve the triangle count at each level, so 64 levels are never reached.
  std::array<int32_t, 64> stack;
  int depth = 0;
  stack[depth++] = 0;
  while (depth > 0) {
    const Node& node = nodes_[stack[--depth]];
    if (!node.box.overlaps(box)) continue;
    if (node.count > 0) {
      for (int32_t k = node.first; k < node.first + node.count; ++k)
        if (tri_boxes_[order_[k]].overlaps(box)) visit(order_[k]);
    } else {
      stack[depth++] = node.right;
      stack[depth++] = node.left;
    }
  }
}

}  // namespace mica
