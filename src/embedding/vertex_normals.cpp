// SPDX-License-Identifier: Apache-2.0
#include "embedding/vertex_normals.hpp"

#include <cmath>
#include <cstring>

namespace mica {

void vertex_normals(const double* __restrict xyz, int32_t vertex_count, const int32_t* __restrict triangles,
                    int32_t triangle_count, double* __restrict normals) {
  std::memset(normals, 0, sizeof(double) * 3 * size_t(vertex_count));
  for (int32_t t = 0; t < triangle_count; ++t) {
    const int32_t* f = triangles + 3 * size_t(t);
    const double *a = xyz + 3 * size_t(f[0]), *b = xyz + 3 * size_t(f[1]), *c = xyz + 3 * size_t(f[2]);
    const double u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
    const double v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
    // Twice the area times the unit normal: summing these weights each triangle by its area.
    const double n0 = u1 * v2 - u2 * v1, n1 = u2 * v0 - u0 * v2, n2 = u0 * v1 - u1 * v0;
    // Declared unaliased so the nine sums need not wait for each other: two corners can be the same
    // vertex only in a triangle with a repeated index, whose normal is zero (nothing is lost).
    double* __restrict p = normals + 3 * size_t(f[0]);
    double* __restrict q = normals + 3 * size_t(f[1]);
    double* __restrict r = normals + 3 * size_t(f[2]);
    p[0] += n0, p[1] += n1, p[2] += n2;
    q[0] += n0, q[1] += n1, q[2] += n2;
    r[0] += n0, r[1] += n1, r[2] += n2;
  }
  for (int32_t i = 0; i < vertex_count; ++i) {
    double* n = normals + 3 * size_t(i);
    const double length2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    const double scale = length2 > 0 ? 1 / std::sqrt(length2) : 0;
    n[0] *= scale;
    n[1] *= scale;
    n[2] *= scale;
  }
}

}  // namespace mica
