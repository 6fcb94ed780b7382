// SPDX-License-Identifier: Apache-2.0
// The embedding's inner loop: each bound vertex placed from its tet's current nodes.
#pragma once
#include <array>
#include <cstdint>

#include "core/types.hpp"

namespace mica {

// A vertex's tet and barycentric weights: all the update reads of it, 48 bytes.
struct VertexBinding {
  std::array<int32_t, 4> nodes;  // the tet's nodes; nodes[0] < 0: unbound
  std::array<double, 4> weights;
};

// For j in [begin, end): vertex order[j] (3 doubles at out_xyz + 3 order[j]) placed at the weighted
// sum of the nodes x of bindings[j], or left as it is if unbound; with clear_normals, its 3 entries
// there set to 0. Node indices are not checked. Allocates nothing.
void place_vertices(const VertexBinding* bindings, const int32_t* order, int32_t begin, int32_t end,
                    const Vec3List& x, double* out_xyz, double* clear_normals);

// Asks the cache for what place_vertices() over [begin, end) will read and write (the bindings,
// the vertices' positions and normals), so that fetching them overlaps other work.
void prefetch_placement(const VertexBinding* bindings, const int32_t* order, int32_t begin, int32_t end,
                        const double* out_xyz, const double* normals);

}  // namespace mica
