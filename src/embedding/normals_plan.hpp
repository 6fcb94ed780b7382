// SPDX-License-Identifier: Apache-2.0
// The order in which the embedding's update places vertices and sums their normals, so that the
// sums never leave the cache. The triangles are taken in blocks. Before a block, the vertices it is
// the first to use are placed: their positions are written to the host's array and copied into a
// slot of a small scratch (one cache line: the position and the normal's sum). The block's triangles
// then read and add only scratch slots. After the block, the vertices it is the last to use are
// normalised from their slots into the host's array, and their slots are free for the next blocks.
// The host's arrays are written once each (a position when its vertex is placed, a normal when it
// is normalised); a whole-mesh pass for each of placing, clearing, summing and normalising moved
// every vertex through memory four times, and on a 114k-vertex mesh the passes cost more than the
// arithmetic.
//
// The scratch holds the vertices in use at once: on a mesh whose triangles come in a coherent
// order (neighbours near each other in the list, as meshing tools and subdivision write them) a
// block's worth and the few shared with far-away triangles; in the worst case (triangles in a random
// order) every vertex.
//
// Within a block, two triangles that share an edge, (a, b, c) and (a, c, d), are summed as a pair:
// a and c get both cross products at once, so a pair writes four sums where two triangles write
// six. The triangles are taken interleaved from four quarters of the block: neighbouring triangles
// share vertices, and the sums of one would wait on the last one's.
#pragma once
#include <cstdint>
#include <vector>

namespace mica {

// A vertex's position and normal sum while its triangles are summed (the 4th entries unused, so
// that four-wide loads stay within the line).
struct alignas(64) NormalSlot {
  double xyz[4];
  double normal[4];  // at xyz + 4 (the sums' kernel reaches it from the position)
};
static_assert(sizeof(NormalSlot) == 64, "a slot is one cache line");

struct NormalsPlan {
  // Every vertex once, in the order they are placed: those in no triangle (normal zero, no slot),
  // then block by block, ascending within a block, those the block uses first.
  std::vector<int32_t> order;
  std::vector<int32_t> first_start;  // block k's: order[first_start[k] .. first_start[k + 1])
  std::vector<int32_t> slot;         // per entry of order: its scratch slot (-1: in no triangle)
  // Per block, in the order they are summed: the pairs of triangles, 4 slots each (a, b, c, d for
  // (a, b, c) and (a, c, d)), and the triangles left single, 3 slots each.
  std::vector<int32_t> pairs, pair_start;      // block k's: [pair_start[k], pair_start[k + 1])
  std::vector<int32_t> singles, single_start;  // block k's: [single_start[k], single_start[k + 1])
  // Per block, ascending: the vertices it uses last, and their slots.
  std::vector<int32_t> last, last_slot, last_start;
  int32_t slots = 0;  // the scratch's size
  int32_t triangles = 0;
  int32_t blocks() const { return int32_t(pair_start.size()) - 1; }
};

// The plan for `triangle_count` triangles (3 vertex indices each) over `vertex_count` vertices
// (indices checked by the caller), in blocks of `block_size` triangles.
NormalsPlan plan_normals(const int32_t* triangles, int32_t triangle_count, int32_t vertex_count,
                         int32_t block_size = 2048);

}  // namespace mica
