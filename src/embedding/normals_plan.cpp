// SPDX-License-Identifier: Apache-2.0
#include "embedding/normals_plan.hpp"

#include <algorithm>

namespace mica {

namespace {

// Lists per block (CSR) from each vertex's block (-1: none), ascending within a block.
void bucket(const std::vector<int32_t>& block_of, int32_t blocks, std::vector<int32_t>& list,
            std::vector<int32_t>& start) {
  start.assign(size_t(blocks) + 1, 0);
  for (int32_t b : block_of)
    if (b >= 0) ++start[size_t(b) + 1];
  for (int32_t k = 0; k < blocks; ++k) start[size_t(k) + 1] += start[size_t(k)];
  list.resize(size_t(start.back()));
  std::vector<int32_t> next(start.begin(), start.end() - 1);
  for (size_t v = 0; v < block_of.size(); ++v)
    if (block_of[v] >= 0) list[size_t(next[size_t(block_of[v])]++)] = int32_t(v);
}

// The triangles of `sequence` (3 vertices each) in blocks of `block_size`, as pairs sharing an edge
// and singles, block by block in the sequence's order: each triangle paired at most once, with the
// first free neighbour in its block found across its edges (a vertex repeated in the four leaves
// the triangle single).
void pair_up(const std::vector<int32_t>& sequence, int32_t vertex_count, int32_t block_size, NormalsPlan& plan) {
  const int32_t count = int32_t(sequence.size() / 3);
  const auto corner = [&](int32_t t, int32_t c) { return sequence[3 * size_t(t) + size_t(c % 3)]; };
  // The triangles' corners by vertex (CSR): the triangles an edge a -> c can be in start at a.
  std::vector<int32_t> start(size_t(vertex_count) + 1, 0), at(sequence.size());
  for (int32_t v : sequence) ++start[size_t(v) + 1];
  for (int32_t v = 0; v < vertex_count; ++v) start[size_t(v) + 1] += start[size_t(v)];
  std::vector<int32_t> next(start.begin(), start.end() - 1);
  for (size_t c = 0; c < sequence.size(); ++c) at[size_t(next[size_t(sequence[c])]++)] = int32_t(c);
  std::vector<uint8_t> used(size_t(count), 0);
  const int32_t blocks = (count + block_size - 1) / block_size;
  plan.pair_start.assign(size_t(blocks) + 1, 0);
  plan.single_start.assign(size_t(blocks) + 1, 0);
  for (int32_t k = 0; k < blocks; ++k) {
    const int32_t begin = k * block_size, end = std::min(count, begin + block_size);
    for (int32_t t = begin; t < end; ++t) {
      if (used[size_t(t)]) continue;
      used[size_t(t)] = 1;
      bool paired = false;
      for (int32_t r = 0; r < 3 && !paired; ++r) {
        const int32_t a = corner(t, r), b = corner(t, r + 1), c = corner(t, r + 2);
        // The neighbour across c -> a runs a -> c: (a, c, d). a's corners are in the sequence's
        // order: those of this block are a run of them.
        const auto first = at.begin() + start[size_t(a)], last = at.begin() + start[size_t(a) + 1];
        for (auto j = std::lower_bound(first, last, 3 * begin); j != last && *j < 3 * end && !paired; ++j) {
          const int32_t u = *j / 3, from = *j % 3;
          if (used[size_t(u)] || corner(u, from + 1) != c) continue;
          const int32_t d = corner(u, from + 2);
          if (a == b || a == c || a == d || b == c || b == d || c == d) continue;
          used[size_t(u)] = 1;
          plan.pairs.insert(plan.pairs.end(), {a, b, c, d});
          paired = true;
        }
      }
      if (!paired) plan.singles.insert(plan.singles.end(), {corner(t, 0), corner(t, 1), corner(t, 2)});
    }
    plan.pair_start[size_t(k) + 1] = int32_t(plan.pairs.size() / 4);
    plan.single_start[size_t(k) + 1] = int32_t(plan.singles.size() / 3);
  }
}

}  // namespace

NormalsPlan plan_normals(const int32_t* triangles, int32_t triangle_count, int32_t vertex_count,
                         int32_t block_size) {
  NormalsPlan plan;
  plan.triangles = triangle_count;
  const int32_t blocks = (triangle_count + block_size - 1) / block_size;
  std::vector<int32_t> sequence(3 * size_t(triangle_count));  // the triangles' vertices, interleaved
  std::vector<int32_t> first(size_t(vertex_count), -1), last(size_t(vertex_count), -1);
  int32_t out = 0;
  for (int32_t k = 0; k < blocks; ++k) {
    const int32_t begin = k * block_size, size = std::min(block_size, triangle_count - begin);
    const int32_t quarter = (size + 3) / 4;
    for (int32_t i = 0; i < quarter; ++i)
      for (int32_t q = 0; q < 4; ++q) {
        const int32_t t = begin + q * quarter + i;
        if (t >= begin + size) continue;
        for (int c = 0; c < 3; ++c) {
          const int32_t v = triangles[3 * size_t(t) + size_t(c)];
          sequence[3 * size_t(out) + size_t(c)] = v;
          if (first[size_t(v)] < 0) first[size_t(v)] = k;
          last[size_t(v)] = k;
        }
        ++out;
      }
  }
  pair_up(sequence, vertex_count, block_size, plan);
  // The vertices in no triangle as a block before the first.
  for (int32_t& b : first) ++b;
  bucket(first, blocks + 1, plan.order, plan.first_start);
  plan.first_start.erase(plan.first_start.begin());
  bucket(last, blocks, plan.last, plan.last_start);
  // Slots given out block by block and taken back after each: the last freed is given first (its
  // line is the likeliest to be in the cache).
  std::vector<int32_t> slot_of(size_t(vertex_count), -1), free;
  plan.slot.assign(plan.order.size(), -1);
  plan.last_slot.resize(plan.last.size());
  for (int32_t k = 0; k < blocks; ++k) {
    for (int32_t j = plan.first_start[size_t(k)]; j < plan.first_start[size_t(k) + 1]; ++j) {
      int32_t s = plan.slots;
      if (free.empty()) ++plan.slots;
      else s = free.back(), free.pop_back();
      slot_of[size_t(plan.order[size_t(j)])] = s;
      plan.slot[size_t(j)] = s;
    }
    for (int32_t j = plan.last_start[size_t(k)]; j < plan.last_start[size_t(k) + 1]; ++j) {
      plan.last_slot[size_t(j)] = slot_of[size_t(plan.last[size_t(j)])];
      free.push_back(plan.last_slot[size_t(j)]);
    }
  }
  for (int32_t& v : plan.pairs) v = slot_of[size_t(v)];
  for (int32_t& v : plan.singles) v = slot_of[size_t(v)];
  return plan;
}

}  // namespace mica
