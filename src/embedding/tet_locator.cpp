// SPDX-License-Identifier: Apache-2.0
#include "embedding/tet_locator.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "collision/aabb.hpp"
#include "core/error.hpp"

namespace mica {

namespace {

// Cells per tet on average: a few tets per cell keep a look-up short without a huge grid.
constexpr double kCellsPerTet = 1.0;

Aabb tet_box(const Vec3List& x, const Tet& t) {
  Aabb box = Aabb::of(x[t[0]], x[t[1]], x[t[2]]);
  box.add(x[t[3]]);
  return box;
}

}  // namespace

TetLocator::TetLocator(const Vec3List& rest, const std::vector<Tet>& tets) {
  const int32_t n = int32_t(rest.size());
  Aabb all;
  tets_.resize(tets.size());
  for (size_t e = 0; e < tets.size(); ++e) {
    for (int32_t v : tets[e])
      if (v < 0 || v >= n)
        fail(Errc::OutOfRange, "tet " + std::to_string(e) + " refers to node " + std::to_string(v) +
                                   ", outside 0.." + std::to_string(n - 1));
    const Tet& t = tets[e];
    Mat3 edges;
    edges << rest[t[1]] - rest[t[0]], rest[t[2]] - rest[t[0]], rest[t[3]] - rest[t[0]];
    if (edges.determinant() == 0) fail(Errc::BadMesh, "tet " + std::to_string(e) + " has zero rest volume");
    tets_[e] = {rest[t[0]], edges.inverse()};
    all.add(tet_box(rest, t));
  }
  if (tets.empty()) return;

  // Cubic cells, about kCellsPerTet per tet over the bounding box.
  lo_ = all.lo;
  const Vec3 size = all.size().cwiseMax(1e-300);
  cell_size_ = std::cbrt(size.prod() / (kCellsPerTet * double(tets.size())));
  cell_size_ = std::max(cell_size_, size.maxCoeff() / 1024);  // at most 1024 cells along an axis
  for (int a = 0; a < 3; ++a) dims_[a] = std::max(1, int32_t(std::ceil(size[a] / cell_size_)));

  // Two passes over each tet's cell range: count, then fill (compressed rows).
  const size_t cells = size_t(dims_.prod());
  cell_start_.assign(cells + 1, 0);
  auto for_cells = [&](const Tet& t, auto&& f) {
    const Aabb box = tet_box(rest, t);
    for (int32_t k = cell(box.lo.z(), 2); k <= cell(box.hi.z(), 2); ++k)
      for (int32_t j = cell(box.lo.y(), 1); j <= cell(box.hi.y(), 1); ++j)
        for (int32_t i = cell(box.lo.x(), 0); i <= cell(box.hi.x(), 0); ++i)
          f((size_t(k) * size_t(dims_[1]) + size_t(j)) * size_t(dims_[0]) + size_t(i));
  };
  for (const Tet& t : tets) for_cells(t, [&](size_t c) { ++cell_start_[c + 1]; });
  for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_tets_.resize(size_t(cell_start_[cells]));
  std::vector<int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t e = 0; e < tets.size(); ++e) for_cells(tets[e], [&](size_t c) { cell_tets_[size_t(fill[c]++)] = int32_t(e); });
}

int32_t TetLocator::cell(double c, int a) const {
  const double f = std::floor((c - lo_[a]) / cell_size_);
  return int32_t(std::clamp(f, 0.0, double(dims_[a] - 1)));
}

Weights TetLocator::weights(int32_t e, const Vec3& p) const {
  const Vec3 w = tets_[size_t(e)].inverse * (p - tets_[size_t(e)].origin);
  return {1 - (w[0] + w[1] + w[2]), w[0], w[1], w[2]};  // the first as VertexBinding makes it
}

int32_t TetLocator::locate(const Vec3& p, double tolerance, Weights& w) const {
  if (cell_start_.empty()) return -1;
  for (int a = 0; a < 3; ++a)  // outside the grid: in no tet (clamping would test a border cell)
    if (p[a] < lo_[a] || p[a] > lo_[a] + dims_[a] * cell_size_) return -1;
  const size_t c = (size_t(cell(p.z(), 2)) * size_t(dims_[1]) + size_t(cell(p.y(), 1))) * size_t(dims_[0]) +
                   size_t(cell(p.x(), 0));
  int32_t best = -1;
  double best_min = -HUGE_VAL;
  for (int32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
    const Weights candidate = weights(cell_tets_[size_t(k)], p);
    if (candidate.minCoeff() > best_min) {
      best_min = candidate.minCoeff();
      best = cell_tets_[size_t(k)];
      w = candidate;
    }
  }
  return best_min >= -tolerance ? best : -1;
}

}  // namespace mica
