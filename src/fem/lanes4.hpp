// SPDX-License-Identifier: Apache-2.0
// Four elements side by side in AVX2 lanes: the loads, stores and 3x3 products the four-wide
// element kernels share (tet_element.cpp, neo_hookean_elements4.cpp). Written by hand for the
// reason half_products.hpp gives: the library is built for any x86-64, so these are compiled for
// AVX2 + FMA and called only where the CPU has them (lanes4::supported()). Matrices are lane
// vectors in column-major order, as Mat3 stores them: M[3j + i] holds the four entries (i, j).
#pragma once
#include "core/cpu_features.hpp"
#include "core/types.hpp"
#include "fem/tet_element.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>

#define MICA_LANES4 1
#define MICA_AVX2 __attribute__((target("avx2,fma")))

namespace mica::lanes4 {

inline bool supported() { return cpu::avx2_fma(); }

// The 4x4 transpose of rows v[0..3]: afterwards v[i] holds the old rows' entries i.
MICA_AVX2 inline void transpose4(__m256d v[4]) {
  const __m256d t0 = _mm256_unpacklo_pd(v[0], v[1]), t1 = _mm256_unpackhi_pd(v[0], v[1]);
  const __m256d t2 = _mm256_unpacklo_pd(v[2], v[3]), t3 = _mm256_unpackhi_pd(v[2], v[3]);
  v[0] = _mm256_permute2f128_pd(t0, t2, 0x20);
  v[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  v[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
  v[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}

// out[i] = (p[0][i], p[1][i], p[2][i], p[3][i]) for i < 4.
MICA_AVX2 inline void load_lanes4(const double* const p[4], __m256d out[4]) {
  for (int l = 0; l < 4; ++l) out[l] = _mm256_loadu_pd(p[l]);
  transpose4(out);
}

// Four 3x3 matrices as lanes: out[3j + i] holds their entries (i, j) (Mat3 is column-major).
MICA_AVX2 inline void load_matrices(const Mat3* const M[4], __m256d out[9]) {
  const double* p[4] = {M[0]->data(), M[1]->data(), M[2]->data(), M[3]->data()};
  load_lanes4(p, out);
  for (int l = 0; l < 4; ++l) p[l] += 4;
  load_lanes4(p, out + 4);
  out[8] = _mm256_setr_pd((*M[0])(8), (*M[1])(8), (*M[2])(8), (*M[3])(8));
}

// Four 3-vectors, (x, y) in xy[l] and z in z[l], as lanes: out[i] holds their entries i.
MICA_AVX2 inline void vectors_to_lanes(const __m128d xy[4], const double z[4], __m256d out[3]) {
  const __m256d v02 = _mm256_insertf128_pd(_mm256_castpd128_pd256(xy[0]), xy[2], 1);
  const __m256d v13 = _mm256_insertf128_pd(_mm256_castpd128_pd256(xy[1]), xy[3], 1);
  out[0] = _mm256_unpacklo_pd(v02, v13);
  out[1] = _mm256_unpackhi_pd(v02, v13);
  out[2] = _mm256_setr_pd(z[0], z[1], z[2], z[3]);
}

// *v[l] += lane l of the 3-vector in lanes s, one after the other (two may be the same vector).
MICA_AVX2 inline void add_vectors(Vec3* const v[4], const __m256d s[3]) {
  const __m256d lo = _mm256_unpacklo_pd(s[0], s[1]), hi = _mm256_unpackhi_pd(s[0], s[1]);
  const __m128d xy[4] = {_mm256_castpd256_pd128(lo), _mm256_castpd256_pd128(hi), _mm256_extractf128_pd(lo, 1),
                         _mm256_extractf128_pd(hi, 1)};
  alignas(32) double z[4];
  _mm256_store_pd(z, s[2]);
  for (int l = 0; l < 4; ++l) {
    double* out = v[l]->data();
    _mm_storeu_pd(out, _mm_add_pd(_mm_loadu_pd(out), xy[l]));
    out[2] += z[l];
  }
}

// *block[l] += lane l of the column-major entries k[0..8], one block after the other (two may be the
// same block: no lane's sum is read before the previous lane's is stored).
MICA_AVX2 inline void add_blocks(Mat3* const block[4], const __m256d (&k)[9]) {
  __m256d lo[4] = {k[0], k[1], k[2], k[3]}, hi[4] = {k[4], k[5], k[6], k[7]};
  transpose4(lo);  // lo[l]: element l's entries 0-3
  transpose4(hi);
  alignas(32) double last[4];
  _mm256_store_pd(last, k[8]);
  for (int l = 0; l < 4; ++l) {
    double* out = block[l]->data();
    _mm256_storeu_pd(out, _mm256_add_pd(_mm256_loadu_pd(out), lo[l]));
    _mm256_storeu_pd(out + 4, _mm256_add_pd(_mm256_loadu_pd(out + 4), hi[l]));
    out[8] += last[l];
  }
}

// *M[l] = lane l of the column-major entries k[0..8] (load_matrices' inverse).
MICA_AVX2 inline void store_matrices(Mat3* const M[4], const __m256d k[9]) {
  __m256d lo[4] = {k[0], k[1], k[2], k[3]}, hi[4] = {k[4], k[5], k[6], k[7]};
  transpose4(lo);
  transpose4(hi);
  alignas(32) double last[4];
  _mm256_store_pd(last, k[8]);
  for (int l = 0; l < 4; ++l) {
    double* out = M[l]->data();
    _mm256_storeu_pd(out, lo[l]);
    _mm256_storeu_pd(out + 4, hi[l]);
    out[8] = last[l];
  }
}

MICA_AVX2 inline __m256d all(double v) { return _mm256_set1_pd(v); }

// Entry (i, j) of A B, of A^T B and of A B^T, for 3x3 matrices in lanes (column-major).
MICA_AVX2 inline __m256d product(const __m256d* A, const __m256d* B, int i, int j) {
  const __m256d s = _mm256_fmadd_pd(A[3 + i], B[3 * j + 1], _mm256_mul_pd(A[i], B[3 * j]));
  return _mm256_fmadd_pd(A[6 + i], B[3 * j + 2], s);
}
MICA_AVX2 inline __m256d transposed_product(const __m256d* A, const __m256d* B, int i, int j) {
  const __m256d s = _mm256_fmadd_pd(A[3 * i + 1], B[3 * j + 1], _mm256_mul_pd(A[3 * i], B[3 * j]));
  return _mm256_fmadd_pd(A[3 * i + 2], B[3 * j + 2], s);
}
MICA_AVX2 inline __m256d product_transposed(const __m256d* A, const __m256d* B, int i, int j) {
  const __m256d s = _mm256_fmadd_pd(A[3 + i], B[3 + j], _mm256_mul_pd(A[i], B[j]));
  return _mm256_fmadd_pd(A[6 + i], B[6 + j], s);
}
// A v for a 3x3 matrix and a 3-vector in lanes.
MICA_AVX2 inline void apply(const __m256d* A, const __m256d* v, __m256d* out) {
  for (int i = 0; i < 3; ++i)
    out[i] = _mm256_fmadd_pd(A[6 + i], v[2], _mm256_fmadd_pd(A[3 + i], v[1], _mm256_mul_pd(A[i], v[0])));
}

MICA_AVX2 inline __m256d dot(const __m256d* a, const __m256d* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
MICA_AVX2 inline void cross(const __m256d* a, const __m256d* b, __m256d* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// The four elements' rest gradients: g[a][i] holds entry i of g_a.
MICA_AVX2 inline void load_gradients(const TetElement* const el[4], __m256d g[4][3]) {
  __m256d rows[12];  // grad's 12 entries (std::array<Vec3, 4>, contiguous) in three rows of 4
  for (int q = 0; q < 3; ++q) {
    const double* p[4];
    for (int l = 0; l < 4; ++l) p[l] = el[l]->grad[0].data() + 4 * q;
    load_lanes4(p, rows + 4 * q);
  }
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) g[a][i] = rows[3 * a + i];
}

// Their edge matrices Ds = [p1 - p0, p2 - p0, p3 - p0] of node values p (positions, velocities).
MICA_AVX2 inline void edge_lanes(const TetElement* const el[4], const Vec3List& p, __m256d ds[9]) {
  for (int k = 0; k < 3; ++k) {
    __m128d xy[4];  // element l's column k
    double z[4];
    for (int l = 0; l < 4; ++l) {
      const double *pk = p[el[l]->nodes[k + 1]].data(), *p0 = p[el[l]->nodes[0]].data();
      xy[l] = _mm_sub_pd(_mm_loadu_pd(pk), _mm_loadu_pd(p0));
      z[l] = pk[2] - p0[2];
    }
    vectors_to_lanes(xy, z, ds + 3 * k);
  }
}

// F = Ds Dm^-1, Dm^-1's rows being the gradients g_1, g_2, g_3 (make_tet_element).
MICA_AVX2 inline void deformation_gradients(const __m256d ds[9], const __m256d (&g)[4][3], __m256d F[9]) {
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) F[3 * j + i] = ds[i] * g[1][j] + ds[3 + i] * g[2][j] + ds[6 + i] * g[3][j];
}

}  // namespace mica::lanes4
#endif
