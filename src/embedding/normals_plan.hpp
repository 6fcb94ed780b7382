// SPDX-License-Identifier: Apache-2.0
// The order in which the embedding's update places vertices and sums their normals, so that each
// vertex is placed, summed and normalised while it is still in the cache: the triangles are taken
// in blocks; before a block, the vertices it is the first to use are placed and their sums
// cleared; after it, those it is the last to use are normalised. A whole-mesh pass for each of the
// four (place, clear, sum, normalise) moved every vertex through memory four times, and on a
// 114k-vertex mesh the passes cost more than the arithmetic.
//
// Within a block the triangles are interleaved from four quarters of it: neighbouring triangles
// share vertices, and the sums of one would wait on the last one's.
#pragma once
#include <cstdint>
#include <vector>

namespace mica {

struct NormalsPlan {
  std::vector<int32_t> corners;      // per triangle, in the order they are summed: 3 v for each vertex v
  std::vector<int32_t> block_start;  // block k's triangles: [block_start[k], block_start[k + 1])
  // Every vertex once, in the order they are placed: those in no triangle (normal zero), then
  // block by block, ascending within a block, those the block uses first.
  std::vector<int32_t> order;
  std::vector<int32_t> first_start;  // block k's: order[first_start[k] .. first_start[k + 1])
  std::vector<int32_t> last;         // per block, ascending: the vertices it uses last
  std::vector<int32_t> last_start;
  int32_t blocks() const { return int32_t(block_start.size()) - 1; }
};

// The plan for `triangle_count` triangles (3 vertex indices each) over `vertex_count` vertices
// (indices checked by the caller, 3 vertex_count within int32), in blocks of `block_size` triangles.
NormalsPlan plan_normals(const int32_t* triangles, int32_t triangle_count, int32_t vertex_count,
                         int32_t block_size = 2048);

}  // namespace mica
