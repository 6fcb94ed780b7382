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
  // The surface's topology (which triangles share an edge); allocates. node_count bounds the node ids.
  void build(const std::vector<Tri>& triangles, size_t node_count);

  // The normals of the surface at positions x (same triangles as at build); allocates nothing.
  void update(const Vec3List& x, const std::vector<Tri>& triangles);

  // The pseudo-normal (not unit) at the point of triangle `tri` (corners t) with barycentric
  // weights w, as closest_on_triangle returns them: a zero weight puts the point on the edge
  // opposite that corner, two zeros on the remaining corner; face is the triangle's unit normal.
  Vec3 at(int32_t tri, const Tri& t, const Vec3& w, const Vec3& face) const;

 private:
  std::vector<std::array<int32_t, 3>> triangle_edges_;  // edge k of a triangle joins its corners k and k+1
  Vec3List edge_;    // per edge: the sum of the unit normals of the faces on it
  Vec3List vertex_;  // per node: the sum over its faces of the face's angle there times its unit normal
};

}  // namespace mica
