// SPDX-License-Identifier: Apache-2.0
#include "embedding/vertex_normals.hpp"

#include <cmath>
#include <cstring>

namespace mica {

void vertex_normals(const double* xyz, int32_t vertex_count, const int32_t* triangles, int32_t triangle_count,
                    double* normals) {
  std::memset(normals, 0, sizeof(double) * 3 * size_t(vertex_count));
  for (int32_t t = 0; t < triangle_count; ++t) {
    const int32_t* f = triangles + 3 * size_t(t);
    const double *a = xyz + 3 * size_t(f[0]), *b = xyz + 3 * size_t(f[1]), *c = xyz + 3 * size_t(f[2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    // Twice the area times the unit normal: summing these weights each triangle by its area.
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    for (int k = 0; k < 3; ++k) {
      double* out = normals + 3 * size_t(f[k]);
      out[0] += n[0];
      out[1] += n[1];
      out[2] += n[2];
    }
  }
  for (int32_t i = 0; i < vertex_count; ++i) {
    double* n = normals + 3 * size_t(i);
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double scale = length > 0 ? 1 / length : 0;
    n[0] *= scale;
    n[1] *= scale;
    n[2] *= scale;
  }
}

}  // namespace mica
