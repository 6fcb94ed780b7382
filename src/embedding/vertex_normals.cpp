// SPDX-License-Identifier: Apache-2.0
#include "embedding/vertex_normals.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define MICA_NORMALS_AVX2 1
#endif

namespace mica {

namespace {

// Scales normals[3 i .. 3 i + 2] to unit length (or to 0 if it has none).
void normalize(double* n) {
  const double length2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const double scale = length2 > 0 ? 1 / std::sqrt(length2) : 0;
  n[0] *= scale;
  n[1] *= scale;
  n[2] *= scale;
}

}  // namespace

// Two vertices at a time where SSE2 is there: std::sqrt, which may set errno, is not vectorised
// by the compiler, and the square root and division were a quarter of the whole update (0.33 ->
// 0.17 ms for 114k vertices). Bit for bit what normalize() gives.
void normalize_listed(double* normals, const int32_t* vertices, int32_t count) {
  int32_t k = 0;
#if defined(__SSE2__)
  for (; k + 2 <= count; k += 2) {
    double* n = normals + 3 * size_t(vertices[k]);
    double* m = normals + 3 * size_t(vertices[k + 1]);
    const __m128d length2 =
        _mm_set_pd(m[0] * m[0] + m[1] * m[1] + m[2] * m[2], n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const __m128d scale = _mm_and_pd(_mm_cmpgt_pd(length2, _mm_setzero_pd()),
                                     _mm_div_pd(_mm_set1_pd(1), _mm_sqrt_pd(length2)));
    const double s0 = _mm_cvtsd_f64(scale), s1 = _mm_cvtsd_f64(_mm_unpackhi_pd(scale, scale));
    n[0] *= s0, n[1] *= s0, n[2] *= s0;
    m[0] *= s1, m[1] *= s1, m[2] *= s1;
  }
#endif
  for (; k < count; ++k) normalize(normals + 3 * size_t(vertices[k]));
}

namespace {

void add_one(const double* __restrict xyz, const int32_t* f, double* __restrict normals) {
  const double *a = xyz + f[0], *b = xyz + f[1], *c = xyz + f[2];
  const double u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
  const double v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
  const double n0 = u1 * v2 - u2 * v1, n1 = u2 * v0 - u0 * v2, n2 = u0 * v1 - u1 * v0;
  // Declared unaliased so the nine sums need not wait for each other: two corners can be the same
  // vertex only in a triangle with a repeated index, whose normal is zero (nothing is lost).
  double* __restrict p = normals + f[0];
  double* __restrict q = normals + f[1];
  double* __restrict r = normals + f[2];
  p[0] += n0, p[1] += n1, p[2] += n2;
  q[0] += n0, q[1] += n1, q[2] += n2;
  r[0] += n0, r[1] += n1, r[2] += n2;
}

#if MICA_NORMALS_AVX2
// A corner read as four doubles (x, y, z and the next vertex's x, unused): the cross product in
// three permutes, a multiply and an FMA where the generic loop takes nine multiplies and
// subtractions. The library is built for any x86-64, so this is compiled for AVX2 + FMA and called
// where the CPU has them; a triangle with the last vertex, whose fourth double is past the array,
// goes the generic way.
__attribute__((target("avx2,fma"))) void add_avx2(const double* xyz, const int32_t* corners, int32_t triangle_count,
                                                  int32_t end, double* normals) {
  const int32_t last = end - 3;
  for (int32_t t = 0; t < triangle_count; ++t) {
    const int32_t* f = corners + 3 * size_t(t);
    if (std::max(std::max(f[0], f[1]), f[2]) == last) {
      add_one(xyz, f, normals);
      continue;
    }
    const __m256d a = _mm256_loadu_pd(xyz + f[0]);
    const __m256d u = _mm256_sub_pd(_mm256_loadu_pd(xyz + f[1]), a);
    const __m256d v = _mm256_sub_pd(_mm256_loadu_pd(xyz + f[2]), a);
    // u x v = (u v.yzx - u.yzx v).yzx
    constexpr int kYzx = _MM_SHUFFLE(3, 0, 2, 1);
    const __m256d c = _mm256_fmsub_pd(u, _mm256_permute4x64_pd(v, kYzx), _mm256_mul_pd(_mm256_permute4x64_pd(u, kYzx), v));
    const __m256d n = _mm256_permute4x64_pd(c, kYzx);
    const __m128d xy = _mm256_castpd256_pd128(n), z = _mm256_extractf128_pd(n, 1);
    for (int k = 0; k < 3; ++k) {
      double* p = normals + f[k];
      _mm_storeu_pd(p, _mm_add_pd(_mm_loadu_pd(p), xy));
      _mm_store_sd(p + 2, _mm_add_sd(_mm_load_sd(p + 2), z));
    }
  }
}

bool avx2_supported() {
  static const bool supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return supported;
}
#endif

}  // namespace

void add_triangle_normals(const double* xyz, const int32_t* corners, int32_t triangle_count, int32_t end,
                          double* normals) {
#if MICA_NORMALS_AVX2
  if (avx2_supported()) return add_avx2(xyz, corners, triangle_count, end, normals);
#endif
  for (int32_t t = 0; t < triangle_count; ++t) add_one(xyz, corners + 3 * size_t(t), normals);
}

}  // namespace mica
