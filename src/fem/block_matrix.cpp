// SPDX-License-Identifier: Apache-2.0
#include "fem/block_matrix.hpp"

#include <algorithm>

namespace mica {

int32_t BlockPattern::find(int32_t i, int32_t j) const {
  const auto first = col.begin() + row_start[i], last = col.begin() + row_start[i + 1];
  const auto it = std::lower_bound(first, last, j);
  return (it != last && *it == j) ? int32_t(it - col.begin()) : -1;
}

BlockPattern build_block_pattern(int32_t node_count, const std::vector<Tet>& tets) {
  std::vector<std::vector<int32_t>> adjacency(static_cast<size_t>(node_count));
  for (const Tet& t : tets)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) adjacency[t[a]].push_back(t[b]);
  BlockPattern p;
  p.rows = node_count;
  p.row_start.assign(size_t(node_count) + 1, 0);
  p.diag.assign(size_t(node_count), -1);
  for (int32_t i = 0; i < node_count; ++i) {
    auto& row = adjacency[i];
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    p.row_start[i + 1] = p.row_start[i] + int32_t(row.size());
  }
  p.col.reserve(size_t(p.row_start.back()));
  for (int32_t i = 0; i < node_count; ++i) {
    for (int32_t j : adjacency[i]) {
      if (j == i) p.diag[i] = int32_t(p.col.size());
      p.col.push_back(j);
    }
  }
  return p;
}

std::vector<std::array<int32_t, 16>> element_block_slots(const BlockPattern& p, const std::vector<Tet>& tets) {
  std::vector<std::array<int32_t, 16>> slots(tets.size());
  for (size_t e = 0; e < tets.size(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) slots[e][4 * a + b] = p.find(tets[e][a], tets[e][b]);
  return slots;
}

void block_multiply(const BlockPattern& p, const BlockValues& A, const Vec3List& x, Vec3List& y) {
  for (int32_t i = 0; i < p.rows; ++i) {
    Vec3 sum = Vec3::Zero();
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) sum += A[k] * x[p.col[k]];
    y[i] = sum;
  }
}

}  // namespace mica
