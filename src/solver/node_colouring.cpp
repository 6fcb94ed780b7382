// SPDX-License-Identifier: Apache-2.0
#include "solver/node_colouring.hpp"

namespace mica {

Colouring colour_nodes(const BlockPattern& p, int32_t block_size) {
  Colouring c;
  c.block_start = uniform_blocks(p.rows, std::max(block_size, 1));
  const int32_t size = std::max(block_size, 1);
  const std::vector<int32_t> colour = greedy_colours(c.blocks(), [&](int32_t b, auto&& mark) {
    for (int32_t i = c.block_start[b]; i < c.block_start[b + 1]; ++i)
      for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) mark(p.col[k] / size);
  });
  group_by_colour(colour, c);
  return c;
}

bool is_valid_node_colouring(const BlockPattern& p, const Colouring& c) {
  const int32_t nb = c.blocks();
  if (nb < 0 || c.items() != p.rows || (nb > 0 && c.block_start.front() != 0) ||
      c.order.size() != size_t(nb) || c.start.empty() || c.start.front() != 0 || c.start.back() != nb)
    return false;
  std::vector<int32_t> block_of(size_t(p.rows), -1), colour(size_t(nb), -1);
  for (int32_t b = 0; b < nb; ++b) {
    if (c.block_start[b] > c.block_start[b + 1]) return false;
    for (int32_t i = c.block_start[b]; i < c.block_start[b + 1]; ++i) block_of[i] = b;
  }
  for (int32_t k = 0; k < c.colours(); ++k) {
    if (c.start[k] > c.start[k + 1]) return false;
    for (int32_t n = c.start[k]; n < c.start[k + 1]; ++n) {
      const int32_t b = c.order[n];
      if (b < 0 || b >= nb || colour[b] >= 0) return false;  // out of range or listed twice
      colour[b] = k;
    }
  }
  for (int32_t i = 0; i < p.rows; ++i)
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) {
      const int32_t a = block_of[i], b = block_of[p.col[k]];
      if (a != b && colour[a] == colour[b]) return false;
    }
  return true;
}

}  // namespace mica
