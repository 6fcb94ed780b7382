// SPDX-License-Identifier: Apache-2.0
// A host's fine mesh embedded in a body's tets: each vertex bound once, at the body's rest shape,
// to a tet and four barycentric weights, then placed from the tet's current nodes after each step
// (SOFA's barycentric mapping, iMSTK's PointToTetMap). The triangles give area-weighted normals.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace mica {

// How a vertex was bound (the values of MICA_EMBED_*).
enum class VertexKind : int32_t {
  Inside = 0,     // in a tet (or on its boundary): its weights are in [0, 1]
  Projected = 1,  // outside the body, its nearest surface point within the radius: it follows the tet
                  // under that point, its weights extrapolated (some negative), so it keeps its offset
  Unbound = 2     // outside the body and farther than the radius: update() leaves it as it is
};

class Embedding {
 public:
  // Binds `vertex_count` vertices (3 doubles each, m, in the body's rest frame) to the tets of a
  // body (its rest positions, tets and surface); vertices outside it within `radius` (m) of its
  // surface are projected, the others unbound. `triangles` (3 vertex indices each, may be null
  // when triangle_count is 0) are copied for the normals. Throws Error(InvalidArgument) for a
  // vertex that is not finite (naming it) or a radius not finite or negative, Error(OutOfRange)
  // for a triangle naming a vertex outside 0..vertex_count-1 (naming the triangle).
  Embedding(uint64_t body, const Vec3List& rest, const std::vector<Tet>& tets, const std::vector<Tri>& surface,
            const double* xyz, int32_t vertex_count, const int32_t* triangles, int32_t triangle_count,
            double radius);

  uint64_t body() const { return body_; }
  int32_t node_count() const { return node_count_; }  // the body's, at binding
  int32_t vertex_count() const { return int32_t(kinds_.size()); }
  int32_t triangle_count() const { return int32_t(triangles_.size() / 3); }
  const std::vector<int32_t>& kinds() const { return kinds_; }  // VertexKind values, per vertex
  int32_t count(VertexKind kind) const { return counts_[size_t(kind)]; }

  // Writes each bound vertex's position, interpolated from the body's current node positions x, into
  // out_xyz (3 per vertex); an unbound vertex's entries are left as they are. With out_normals,
  // then the area-weighted normals of the triangles at out_xyz (3 per vertex). Allocates nothing.
  // Throws Error(WrongState) if x is not of the body's node count.
  void update(const Vec3List& x, double* out_xyz, double* out_normals) const;

 private:
  struct Binding {
    std::array<int32_t, 4> nodes;  // the tet's nodes; nodes[0] < 0: unbound
    std::array<double, 4> weights;
  };

  uint64_t body_;
  int32_t node_count_;
  std::vector<Binding> bindings_;  // per vertex
  std::vector<int32_t> kinds_;
  std::array<int32_t, 3> counts_{};
  std::vector<int32_t> triangles_;
};

}  // namespace mica
