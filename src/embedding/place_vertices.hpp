// SPDX-License-Identifier: Apache-2.0
// The embedding's inner loop: each bound vertex placed from its tet's current nodes.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "embedding/normals_plan.hpp"

namespace mica {

// A vertex's tet and barycentric weights: all the update reads of it, 32 bytes (the update is bound
// by reading these). The weights are of the tet's last three nodes; the first node's is
// 1 - (w1 + w2 + w3), as TetLocator::weights makes it.
struct VertexBinding {
  std::array<double, 3> weights;  // of nodes 1, 2, 3
  int32_t tet;                // -1: unbound
  int32_t vertex : 31;        // the host's index of the vertex
  uint32_t has_last_node : 1;  // the tet holds the body's last node (reading past it would leave the array)
};
static_assert(sizeof(VertexBinding) == 32, "a binding is half a cache line");

// For each of the `count` bindings b: vertex b.vertex (3 doubles at out_xyz + 3 b.vertex) placed at
// the weighted sum of the nodes x of its tet in tets, or left as it is if unbound. With `scratch`,
// its position also copied into scratch[slot[k]] for the k-th binding (an unbound vertex's as the
// host has it) and that slot's normal cleared. Indices are not checked. Allocates nothing.
void place_vertices(const VertexBinding* bindings, int32_t count, const std::vector<Tet>& tets, const Vec3List& x,
                    double* out_xyz, const int32_t* slot = nullptr, NormalSlot* scratch = nullptr);

}  // namespace mica
