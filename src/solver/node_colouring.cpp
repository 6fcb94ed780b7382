#include "solver/node_colouring.hpp"

namespace mica {

Colouring colour_nodes(const BlockPattern& p) {
  std::vector<int32_t> colour(size_t(p.rows), -1);
  std::vector<int32_t> taken;  // taken[c] == i: a neighbour of node i has colour c
  for (int32_t i = 0; i < p.rows; ++i) {
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) {
      const int32_t c = colour[p.col[k]];
      if (c < 0) continue;
      if (size_t(c) >= taken.size()) taken.resize(size_t(c) + 1, -1);
      taken[c] = i;
    }
    int32_t c = 0;
    while (size_t(c) < taken.size() && taken[c] == i) ++c;
    colour[i] = c;
  }
  return group_by_colour(colour);
}

bool is_valid_node_colouring(const BlockPattern& p, const Colouring& c) {
  if (int32_t(c.order.size()) != p.rows || c.start.empty() || c.start.front() != 0 ||
      c.start.back() != int32_t(c.order.size()))
    return false;
  std::vector<int32_t> colour(size_t(p.rows), -1);
  for (int32_t k = 0; k < c.colours(); ++k) {
    if (c.start[k] > c.start[k + 1]) return false;
    for (int32_t n = c.start[k]; n < c.start[k + 1]; ++n) {
      const int32_t i = c.order[n];
      if (i < 0 || i >= p.rows || colour[i] >= 0) return false;  // out of range or listed twice
      colour[i] = k;
    }
  }
  for (int32_t i = 0; i < p.rows; ++i)
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k)
      if (p.col[k] != i && colour[p.col[k]] == colour[i]) return false;
  return true;
}

}  // namespace mica
