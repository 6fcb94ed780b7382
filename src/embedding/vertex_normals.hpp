// SPDX-License-Identifier: Apache-2.0
// Area-weighted vertex normals of a triangle mesh.
#pragma once
#include <cstdint>

namespace mica {

// Writes into normals (3 per vertex) the unit sum of the normals of each vertex's triangles, each
// weighted by its area (the sum of the triangles' cross products, normalised); a vertex whose
// triangles have no area, or that is in no triangle, gets (0, 0, 0). Triangles are counter-clockwise
// seen from the side the normals point to. Indices are not checked; `normals` must not overlap the
// other arrays. Allocates nothing.
void vertex_normals(const double* xyz, int32_t vertex_count, const int32_t* triangles, int32_t triangle_count,
                    double* normals);

}  // namespace mica
