// SPDX-License-Identifier: Apache-2.0
// The kernels of area-weighted vertex normals (sum the triangles, normalise), over the scratch
// slots of normals_plan.hpp.
// Triangles are counter-clockwise seen from the side the normals point to.
#pragma once
#include <cstdint>

#include "embedding/normals_plan.hpp"

namespace mica {

// Adds each triangle's cross product (twice its area times its unit normal) to the normal sums of
// its three corners; a triangle is the scratch slots of its three vertices. Allocates nothing.
void add_triangle_normals(NormalSlot* scratch, const int32_t* corners, int32_t triangle_count);

// The same for `pair_count` pairs of triangles sharing an edge, 4 slots each: a, b, c, d for the
// triangles (a, b, c) and (a, c, d).
void add_pair_normals(NormalSlot* scratch, const int32_t* pairs, int32_t pair_count);

// Writes the unit normal of each of the `count` vertices listed, from the sum in its slot
// (scratch[slots[k]]), to out_normals + 3 vertices[k] (a zero sum gives a zero normal).
void finish_normals(const NormalSlot* scratch, const int32_t* vertices, const int32_t* slots, int32_t count,
                    double* out_normals);

}  // namespace mica
