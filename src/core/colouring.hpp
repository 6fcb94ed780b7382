// SPDX-License-Identifier: Apache-2.0
// A colouring of blocks of consecutive items (nodes, elements) for parallel loops: the items
// are cut into blocks of consecutive indices, and blocks that share nothing may take one colour.
// A loop runs colour by colour; the blocks of a colour go to different threads, and each block
// is run in index order by one thread. Blocks keep the memory locality of the serial loop (a
// colouring of single items scatters each colour over the whole mesh, which on a multi-core
// machine costs more in cache misses than a second core brings); with blocks of one item it is
// the plain colouring of the items.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mica {

struct Colouring {
  std::vector<int32_t> block_start;  // blocks() + 1 offsets: block b holds items [block_start[b], block_start[b + 1])
  std::vector<int32_t> order;        // every block once, grouped by colour, ascending within a colour
  std::vector<int32_t> start;        // colours() + 1 offsets into order

  int32_t blocks() const { return block_start.empty() ? 0 : int32_t(block_start.size()) - 1; }
  int32_t colours() const { return start.empty() ? 0 : int32_t(start.size()) - 1; }
  int32_t items() const { return block_start.empty() ? 0 : block_start.back(); }
  bool empty() const { return order.empty(); }
};

// A block size for `items` items: about 128 blocks (enough to share among threads at any
// colour), within [min_size, max_size]. It depends on the mesh only, not on the thread count.
inline int32_t block_size_for(int32_t items, int32_t min_size, int32_t max_size) {
  return std::clamp(items / 128, min_size, max_size);
}

// Blocks [0, size), [size, 2 size), ... over `items` items.
inline std::vector<int32_t> uniform_blocks(int32_t items, int32_t size) {
  std::vector<int32_t> start;
  for (int32_t i = 0; i < items; i += size) start.push_back(i);
  start.push_back(items);
  return start;
}

// Groups blocks by their colour (0..) into `c.order` and `c.start`, ascending within a colour.
inline void group_by_colour(const std::vector<int32_t>& colour_of, Colouring& c) {
  int32_t colours = 0;
  for (int32_t k : colour_of) colours = std::max(colours, k + 1);
  c.start.assign(size_t(colours) + 1, 0);
  for (int32_t k : colour_of) ++c.start[size_t(k) + 1];
  for (int32_t k = 0; k < colours; ++k) c.start[k + 1] += c.start[k];
  c.order.resize(colour_of.size());
  std::vector<int32_t> next(c.start.begin(), c.start.end() - 1);
  for (int32_t b = 0; b < int32_t(colour_of.size()); ++b) c.order[next[colour_of[b]]++] = b;
}

// Greedy first-fit colouring of blocks 0..blocks-1 in order; neighbours(b, mark) calls mark(c)
// for every block c that conflicts with b (b itself may be among them).
template <class N>
std::vector<int32_t> greedy_colours(int32_t blocks, N&& neighbours) {
  std::vector<int32_t> colour(size_t(blocks), -1), taken;  // taken[k] == b: a neighbour of b has colour k
  for (int32_t b = 0; b < blocks; ++b) {
    neighbours(b, [&](int32_t c) {
      const int32_t k = colour[c];
      if (k < 0) return;
      if (size_t(k) >= taken.size()) taken.resize(size_t(k) + 1, -1);
      taken[k] = b;
    });
    int32_t k = 0;
    while (size_t(k) < taken.size() && taken[k] == b) ++k;
    colour[b] = k;
  }
  return colour;
}

}  // namespace mica
