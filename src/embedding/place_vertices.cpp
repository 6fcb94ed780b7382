// SPDX-License-Identifier: Apache-2.0
#include "embedding/place_vertices.hpp"

#include <algorithm>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define MICA_PLACE_AVX2 1
#endif

namespace mica {

namespace {

void place(const VertexBinding& b, const Vec3List& x, double* out) {
  const double *x0 = x[size_t(b.nodes[0])].data(), *x1 = x[size_t(b.nodes[1])].data(),
               *x2 = x[size_t(b.nodes[2])].data(), *x3 = x[size_t(b.nodes[3])].data();
  const double w0 = b.weights[0], w1 = b.weights[1], w2 = b.weights[2], w3 = b.weights[3];
  for (int a = 0; a < 3; ++a) out[a] = w0 * x0[a] + w1 * x1[a] + w2 * x2[a] + w3 * x3[a];
}

void place_generic(const VertexBinding* bindings, const int32_t* order, int32_t begin, int32_t end,
                   const Vec3List& x, double* out_xyz, double* clear_normals) {
  for (int32_t j = begin; j < end; ++j) {
    const size_t v = 3 * size_t(order[j]);
    if (bindings[j].nodes[0] >= 0) place(bindings[j], x, out_xyz + v);
    if (clear_normals) std::fill_n(clear_normals + v, 3, 0.0);
  }
}

#if MICA_PLACE_AVX2
// Each node read as four doubles (x, y, z and the next node's x, unused), four FMAs a vertex where
// the generic loop takes twelve multiplies and nine additions: the library is built for any x86-64,
// so this is compiled for AVX2 + FMA and called where the CPU has them. A tet with the last node,
// whose fourth double is past the array, goes the generic way.
__attribute__((target("avx2,fma"))) void place_avx2(const VertexBinding* bindings, const int32_t* order,
                                                    int32_t begin, int32_t end, const Vec3List& x,
                                                    double* out_xyz, double* clear_normals) {
  const int32_t last = int32_t(x.size()) - 1;
  const double* base = x.data()->data();
  for (int32_t j = begin; j < end; ++j) {
    const VertexBinding& b = bindings[j];
    double* out = out_xyz + 3 * size_t(order[j]);
    if (clear_normals) {
      double* n = clear_normals + 3 * size_t(order[j]);
      _mm_storeu_pd(n, _mm_setzero_pd());
      n[2] = 0;
    }
    if (b.nodes[0] < 0) continue;
    if (std::max(std::max(b.nodes[0], b.nodes[1]), std::max(b.nodes[2], b.nodes[3])) == last) {
      place(b, x, out);
      continue;
    }
    __m256d p = _mm256_mul_pd(_mm256_broadcast_sd(&b.weights[0]), _mm256_loadu_pd(base + 3 * size_t(b.nodes[0])));
    p = _mm256_fmadd_pd(_mm256_broadcast_sd(&b.weights[1]), _mm256_loadu_pd(base + 3 * size_t(b.nodes[1])), p);
    p = _mm256_fmadd_pd(_mm256_broadcast_sd(&b.weights[2]), _mm256_loadu_pd(base + 3 * size_t(b.nodes[2])), p);
    p = _mm256_fmadd_pd(_mm256_broadcast_sd(&b.weights[3]), _mm256_loadu_pd(base + 3 * size_t(b.nodes[3])), p);
    _mm_storeu_pd(out, _mm256_castpd256_pd128(p));
    _mm_store_sd(out + 2, _mm256_extractf128_pd(p, 1));
  }
}

bool avx2_supported() {
  static const bool supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return supported;
}
#endif

}  // namespace

void place_vertices(const VertexBinding* bindings, const int32_t* order, int32_t begin, int32_t end,
                    const Vec3List& x, double* out_xyz, double* clear_normals) {
#if MICA_PLACE_AVX2
  if (avx2_supported()) return place_avx2(bindings, order, begin, end, x, out_xyz, clear_normals);
#endif
  place_generic(bindings, order, begin, end, x, out_xyz, clear_normals);
}

void prefetch_placement(const VertexBinding* bindings, const int32_t* order, int32_t begin, int32_t end,
                        const double* out_xyz, const double* normals) {
  if (begin >= end) return;
  const char* from = reinterpret_cast<const char*>(bindings + begin);
  const char* to = reinterpret_cast<const char*>(bindings + end);
  for (const char* line = from; line < to; line += 64) __builtin_prefetch(line, 0, 3);
  for (int32_t j = begin; j < end; ++j) {
    __builtin_prefetch(out_xyz + 3 * size_t(order[j]), 1, 3);
    if (normals) __builtin_prefetch(normals + 3 * size_t(order[j]), 1, 3);
  }
}

}  // namespace mica
