// SPDX-License-Identifier: Apache-2.0
// Angle-weighted pseudo-normals of a closed, outward-wound triangle surface (Baerentzen & Aanaes,
// "Signed distance computation using the angle weighted pseudonormal", IEEE TVCG 2005). With q the
// surface point nearest to p, p is outside exactly when (p - q) . n > 0, n the pseudo-normal of
// the face, edge or vertex q lies on. The face normal of one triangle at q is not enough where q
// is on an edge or a vertex: beside a box, level with its top, the nearest point is the top edge,
// and p is above the top face's plane but below the side face's.
#pragma once
#include <array>
#include <vector>

#include "core/types.hpp"

namespace mica {

class SurfacePseudoNormals {
 public:
  // The surface's topology (which triangles share an edge, which meet at a node); allocates.
  // node_count bounds the node ids.
  void build(const std::vector<Tri>& triangles, size_t node_count);

  // The pseudo-normal (not unit) at the point of triangle `tri` with barycentric weights w, as
  // closest_on_triangle returns them, for the surface at positions x (the triangles of build): a
  // zero weight puts the point on the edge opposite that corner, two zeros on the remaining
  // corner; face is the triangle's unit normal. Made from the few triangles around
  // that edge or corner when asked, not for the whole surface every step (the collision queries
  // ask for a few dozen a step); the sums run in triangle order, as a pass over the surface
  // would add them. Allocates nothing.
  Vec3 at(int32_t tri, const Vec3& w, const Vec3& face, const Vec3List& x, const std::vector<Tri>& triangles) const;

 private:
  std::vector<std::array<int32_t, 3>> triangle_edges_;  // edge k of a triangle joins its corners k and k+1
  // Per edge, the triangles on it; per node, the triangles at it and which corner it is there
  // (CSR: start per edge or node, then the entries, in triangle order).
  std::vector<int32_t> edge_start_, edge_triangle_;
  std::vector<int32_t> node_start_;
  std::vector<std::array<int32_t, 2>> node_corner_;  // (triangle, corner)
};

}  // namespace mica
