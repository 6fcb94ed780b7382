// SPDX-License-Identifier: Apache-2.0
// The two kernels of area-weighted vertex normals (the embedding's update runs them block by
// block: normals_plan.hpp). Triangles are counter-clockwise seen from the side the normals point to.
#pragma once
#include <cstdint>

namespace mica {

// Adds each triangle's cross product (twice its area times its unit normal) to the normals of its
// three corners. A triangle is three offsets, 3 v for its vertices v: its corners' coordinates
// start at xyz + 3 v, their normals at normals + 3 v; `end` is 3 times the vertex count. Offsets are
// not checked; normals must not overlap xyz. Allocates nothing.
void add_triangle_normals(const double* xyz, const int32_t* corners, int32_t triangle_count, int32_t end,
                          double* normals);

// Scales the normals (3 per vertex) of the `count` listed vertices to unit length (a zero normal
// stays zero).
void normalize_listed(double* normals, const int32_t* vertices, int32_t count);

}  // namespace mica
