// SPDX-License-Identifier: Apache-2.0
// Which rest tet holds a point, and its barycentric weights there: a uniform grid over the tets'
// rest bounding boxes, so a look-up tests the few tets of one cell instead of every tet.
#pragma once
#include <vector>

#include "core/types.hpp"

namespace mica {

// Barycentric weights w of p in a tet (p = sum w_k corner_k, sum w_k = 1); outside the tet some
// are negative (the affine extension of the tet's interpolation).
using Weights = Eigen::Vector4d;

class TetLocator {
 public:
  // Throws Error(OutOfRange) for a tet naming a node outside `rest`, Error(BadMesh) for a flat tet.
  TetLocator(const Vec3List& rest, const std::vector<Tet>& tets);

  // The weights of p in tet e (any point: extrapolated outside it).
  Weights weights(int32_t e, const Vec3& p) const;

  // The tet of the grid cell of p whose smallest weight is the largest, if that weight is at least
  // -tolerance (p inside it, or on its boundary up to round-off); else -1.
  int32_t locate(const Vec3& p, double tolerance, Weights& w) const;

 private:
  // The cell of coordinate c along axis a, clamped to the grid.
  int32_t cell(double c, int a) const;

  struct Affine {  // weights 1..3 of p are inverse * (p - origin)
    Vec3 origin;
    Mat3 inverse;
  };
  std::vector<Affine> tets_;
  Vec3 lo_ = Vec3::Zero();
  double cell_size_ = 1;
  Eigen::Vector3i dims_ = Eigen::Vector3i::Ones();
  std::vector<int32_t> cell_start_;  // cell c holds cell_tets_[cell_start_[c] .. cell_start_[c + 1])
  std::vector<int32_t> cell_tets_;
};

}  // namespace mica
