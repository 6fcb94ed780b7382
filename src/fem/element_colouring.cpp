// SPDX-License-Identifier: Apache-2.0
#include "fem/element_colouring.hpp"

namespace mica {

Colouring colour_elements(const std::vector<Tet>& tets, int32_t node_count, int32_t block_size) {
  Colouring c;
  const int32_t size = std::max(block_size, 1);
  c.block_start = uniform_blocks(int32_t(tets.size()), size);
  // The blocks around each node (CSR), each once: tets come in block order.
  std::vector<int32_t> first(size_t(node_count) + 1, 0), last_block(size_t(node_count), -1);
  for (int32_t e = 0; e < int32_t(tets.size()); ++e)
    for (int32_t n : tets[e])
      if (last_block[n] != e / size) {
        last_block[n] = e / size;
        ++first[size_t(n) + 1];
      }
  for (int32_t i = 0; i < node_count; ++i) first[i + 1] += first[i];
  std::vector<int32_t> around(size_t(first.back())), next(first.begin(), first.end() - 1);
  last_block.assign(size_t(node_count), -1);
  for (int32_t e = 0; e < int32_t(tets.size()); ++e)
    for (int32_t n : tets[e])
      if (last_block[n] != e / size) {
        last_block[n] = e / size;
        around[next[n]++] = e / size;
      }
  const std::vector<int32_t> colour = greedy_colours(c.blocks(), [&](int32_t b, auto&& mark) {
    for (int32_t e = c.block_start[b]; e < c.block_start[b + 1]; ++e)
      for (int32_t n : tets[e])
        for (int32_t k = first[n]; k < first[n + 1]; ++k) mark(around[k]);
  });
  group_by_colour(colour, c);
  return c;
}

bool is_valid_element_colouring(const std::vector<Tet>& tets, int32_t node_count, const Colouring& c) {
  const int32_t nb = c.blocks();
  if (nb < 0 || c.items() != int32_t(tets.size()) || (nb > 0 && c.block_start.front() != 0) ||
      c.order.size() != size_t(nb) || c.start.empty() || c.start.front() != 0 || c.start.back() != nb)
    return false;
  std::vector<int32_t> seen(size_t(nb), 0), owner(size_t(node_count), -1), owner_colour(size_t(node_count), -1);
  for (int32_t k = 0; k < c.colours(); ++k) {
    if (c.start[k] > c.start[k + 1]) return false;
    for (int32_t n = c.start[k]; n < c.start[k + 1]; ++n) {
      const int32_t b = c.order[n];
      if (b < 0 || b >= nb || seen[b]++) return false;
      if (c.block_start[b] > c.block_start[b + 1]) return false;
      for (int32_t e = c.block_start[b]; e < c.block_start[b + 1]; ++e)
        for (int32_t node : tets[e]) {
          if (owner_colour[node] == k && owner[node] != b) return false;  // a node in two blocks of colour k
          owner_colour[node] = k;
          owner[node] = b;
        }
    }
  }
  return true;
}

}  // namespace mica
