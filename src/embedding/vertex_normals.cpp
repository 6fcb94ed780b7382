// SPDX-License-Identifier: Apache-2.0
#include "embedding/vertex_normals.hpp"

#include <cmath>

#include "core/cpu_features.hpp"
#include "embedding/stream_store.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define MICA_NORMALS_AVX2 1
#endif

namespace mica {

namespace {

void add_one(NormalSlot* scratch, const int32_t* f) {
  const double *a = scratch[f[0]].xyz, *b = scratch[f[1]].xyz, *c = scratch[f[2]].xyz;
  const double u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
  const double v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
  const double n[3] = {u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) scratch[f[k]].normal[i] += n[i];
}

void add_pair(NormalSlot* scratch, const int32_t* q) {
  const int32_t first[3] = {q[0], q[1], q[2]}, second[3] = {q[0], q[2], q[3]};
  add_one(scratch, first);
  add_one(scratch, second);
}

void finish_one(const double* sum, double* out) {
  const double length2 = sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2];
  const double scale = length2 > 0 ? 1 / std::sqrt(length2) : 0;
  for (int i = 0; i < 3; ++i) out[i] = sum[i] * scale;
}

#if MICA_NORMALS_AVX2
// The cross product in three permutes, a multiply and an FMA where the generic loop takes nine
// multiplies and subtractions, and the sums four wide (their fourth entries are never read); the
// normals four at a time, one square root and one division for the four. The library is built for
// any x86-64, so these are compiled for AVX2 + FMA and called where the CPU has them.
__attribute__((target("avx2,fma"))) void add_avx2(NormalSlot* scratch, const int32_t* corners,
                                                  int32_t triangle_count) {
  constexpr int kYzx = _MM_SHUFFLE(3, 0, 2, 1);
  for (int32_t t = 0; t < triangle_count; ++t) {
    double* const a = scratch[corners[3 * size_t(t)]].xyz;  // each slot's normal follows its position
    double* const b = scratch[corners[3 * size_t(t) + 1]].xyz;
    double* const c = scratch[corners[3 * size_t(t) + 2]].xyz;
    const __m256d p = _mm256_load_pd(a);
    // (a - b) x (a - c) = (b - a) x (c - a) = u x v = (u v.yzx - u.yzx v).yzx
    const __m256d u = _mm256_sub_pd(p, _mm256_load_pd(b)), v = _mm256_sub_pd(p, _mm256_load_pd(c));
    const __m256d w =
        _mm256_fmsub_pd(u, _mm256_permute4x64_pd(v, kYzx), _mm256_mul_pd(_mm256_permute4x64_pd(u, kYzx), v));
    const __m256d n = _mm256_permute4x64_pd(w, kYzx);
    _mm256_store_pd(a + 4, _mm256_add_pd(_mm256_load_pd(a + 4), n));
    _mm256_store_pd(b + 4, _mm256_add_pd(_mm256_load_pd(b + 4), n));
    _mm256_store_pd(c + 4, _mm256_add_pd(_mm256_load_pd(c + 4), n));
  }
}

// Two triangles (a, b, c) and (a, c, d): with u = a - b, v = a - c, w = a - d, their cross
// products are u x v and v x w; a and c get their sum.
__attribute__((target("avx2,fma"))) void add_pairs_avx2(NormalSlot* scratch, const int32_t* pairs, int32_t pair_count) {
  constexpr int kYzx = _MM_SHUFFLE(3, 0, 2, 1);
  for (int32_t k = 0; k < pair_count; ++k) {
    double* const a = scratch[pairs[4 * size_t(k)]].xyz;
    double* const b = scratch[pairs[4 * size_t(k) + 1]].xyz;
    double* const c = scratch[pairs[4 * size_t(k) + 2]].xyz;
    double* const d = scratch[pairs[4 * size_t(k) + 3]].xyz;
    const __m256d p = _mm256_load_pd(a);
    const __m256d u = _mm256_sub_pd(p, _mm256_load_pd(b)), v = _mm256_sub_pd(p, _mm256_load_pd(c)),
                  w = _mm256_sub_pd(p, _mm256_load_pd(d));
    const __m256d u_ = _mm256_permute4x64_pd(u, kYzx), v_ = _mm256_permute4x64_pd(v, kYzx),
                  w_ = _mm256_permute4x64_pd(w, kYzx);
    const __m256d m1 = _mm256_fmsub_pd(u, v_, _mm256_mul_pd(u_, v)), m2 = _mm256_fmsub_pd(v, w_, _mm256_mul_pd(v_, w));
    const __m256d n1 = _mm256_permute4x64_pd(m1, kYzx), n2 = _mm256_permute4x64_pd(m2, kYzx);
    const __m256d both = _mm256_add_pd(n1, n2);
    _mm256_store_pd(a + 4, _mm256_add_pd(_mm256_load_pd(a + 4), both));
    _mm256_store_pd(b + 4, _mm256_add_pd(_mm256_load_pd(b + 4), n1));
    _mm256_store_pd(c + 4, _mm256_add_pd(_mm256_load_pd(c + 4), both));
    _mm256_store_pd(d + 4, _mm256_add_pd(_mm256_load_pd(d + 4), n2));
  }
}

__attribute__((target("avx2,fma"))) void finish_avx2(const NormalSlot* scratch, const int32_t* vertices,
                                                     const int32_t* slots, int32_t count, double* out_normals) {
  int32_t k = 0;
  for (; k + 4 <= count; k += 4) {
    __m256d s[4];
    for (int l = 0; l < 4; ++l) s[l] = _mm256_load_pd(scratch[slots[k + l]].normal);
    const __m256d t0 = _mm256_unpacklo_pd(s[0], s[1]), t1 = _mm256_unpackhi_pd(s[0], s[1]);
    const __m256d t2 = _mm256_unpacklo_pd(s[2], s[3]), t3 = _mm256_unpackhi_pd(s[2], s[3]);
    const __m256d x = _mm256_permute2f128_pd(t0, t2, 0x20), y = _mm256_permute2f128_pd(t1, t3, 0x20);
    const __m256d z = _mm256_permute2f128_pd(t0, t2, 0x31);
    // x*x + y*y + z*z without FMA, rounded as finish_one() rounds it.
    const __m256d length2 = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y)), _mm256_mul_pd(z, z));
    const __m256d scale = _mm256_and_pd(_mm256_cmp_pd(length2, _mm256_setzero_pd(), _CMP_GT_OQ),
                                        _mm256_div_pd(_mm256_set1_pd(1), _mm256_sqrt_pd(length2)));
    stream3(out_normals + 3 * size_t(vertices[k]), _mm256_mul_pd(s[0], _mm256_permute4x64_pd(scale, 0x00)));
    stream3(out_normals + 3 * size_t(vertices[k + 1]), _mm256_mul_pd(s[1], _mm256_permute4x64_pd(scale, 0x55)));
    stream3(out_normals + 3 * size_t(vertices[k + 2]), _mm256_mul_pd(s[2], _mm256_permute4x64_pd(scale, 0xaa)));
    stream3(out_normals + 3 * size_t(vertices[k + 3]), _mm256_mul_pd(s[3], _mm256_permute4x64_pd(scale, 0xff)));
  }
  for (; k < count; ++k) finish_one(scratch[slots[k]].normal, out_normals + 3 * size_t(vertices[k]));
  _mm_sfence();  // the streamed normals ordered before what the caller writes next
}

bool avx2_supported() { return cpu::avx2_fma(); }
#endif

}  // namespace

void add_triangle_normals(NormalSlot* scratch, const int32_t* corners, int32_t triangle_count) {
#if MICA_NORMALS_AVX2
  if (avx2_supported()) return add_avx2(scratch, corners, triangle_count);
#endif
  for (int32_t t = 0; t < triangle_count; ++t) add_one(scratch, corners + 3 * size_t(t));
}

void add_pair_normals(NormalSlot* scratch, const int32_t* pairs, int32_t pair_count) {
#if MICA_NORMALS_AVX2
  if (avx2_supported()) return add_pairs_avx2(scratch, pairs, pair_count);
#endif
  for (int32_t k = 0; k < pair_count; ++k) add_pair(scratch, pairs + 4 * size_t(k));
}

void finish_normals(const NormalSlot* scratch, const int32_t* vertices, const int32_t* slots, int32_t count,
                    double* out_normals) {
#if MICA_NORMALS_AVX2
  if (avx2_supported()) return finish_avx2(scratch, vertices, slots, count, out_normals);
#endif
  for (int32_t k = 0; k < count; ++k) finish_one(scratch[slots[k]].normal, out_normals + 3 * size_t(vertices[k]));
}

}  // namespace mica
