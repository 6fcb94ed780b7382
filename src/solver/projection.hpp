// SPDX-License-Identifier: Apache-2.0
// Linear projection constraints (LPC) on one body's nodes. Node i keeps the velocity
// components in the range of S_i (a symmetric projector) free and prescribes the rest:
// (I - S_i) v_i = z_i. Fixed: S_i = 0; slide on a plane with normal p: S_i = I - p p^T.
#pragma once
#include <vector>

#include "core/types.hpp"

namespace mica {

struct Projection {
  std::vector<Mat3> S;          // per node; identity where free
  Vec3List z;                   // per node; in the range of I - S_i, zero where free
  std::vector<int32_t> nodes;   // constrained nodes, in the order first constrained
  std::vector<uint8_t> is_constrained;

  bool active() const { return !nodes.empty(); }
  // S_i v, the part of v free at node i (v itself at a free node).
  Vec3 free_part(int32_t i, const Vec3& v) const { return active() && is_constrained[i] ? Vec3(S[i] * v) : v; }
  // S_i (the identity at a free node).
  const Mat3& projector(int32_t i) const;
  // Frees every node of a body with `node_count` nodes (allocates only on a size change).
  void reset(int32_t node_count);
  // Adds the constrained directions `C` (a projector, I - S of the new constraint) at `node`
  // with prescribed velocity `velocity`: constrained subspaces add up; the new velocity wins
  // on the new directions, the old one is kept on the others.
  void constrain(int32_t node, const Mat3& C, const Vec3& velocity);
};

// Projector onto span{d} (I minus it projects onto the orthogonal complement), for building C.
inline Mat3 line_projector(const Vec3& d) { return d * d.transpose() / d.squaredNorm(); }

}  // namespace mica
