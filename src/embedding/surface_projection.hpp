// SPDX-License-Identifier: Apache-2.0
// The nearest point of a body's rest surface to a point outside it, within a radius, and the tet
// that surface triangle belongs to: the tet an outside vertex follows.
#pragma once
#include <vector>

#include "collision/bvh.hpp"
#include "core/types.hpp"

namespace mica {

// Used while binding: it refers to `rest` and `surface`, which must outlive it.
class SurfaceProjection {
 public:
  // `surface` are faces of `tets` (a body's boundary): throws Error(BadMesh) for a triangle that
  // is not a face of any tet.
  SurfaceProjection(const Vec3List& rest, const std::vector<Tet>& tets, const std::vector<Tri>& surface);

  // The tet under the surface point nearest to p if that point is at most `radius` away, else -1;
  // `distance` receives its distance (HUGE_VAL when none is within the radius).
  int32_t nearest_tet(const Vec3& p, double radius, double& distance) const;

 private:
  const Vec3List& rest_;
  const std::vector<Tri>& surface_;
  TriangleBvh bvh_;                 // over the surface at rest
  std::vector<int32_t> tet_of_;     // per surface triangle
};

}  // namespace mica
