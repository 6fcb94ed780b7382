// SPDX-License-Identifier: Apache-2.0
#include "embedding/place_vertices.hpp"

#include <algorithm>

#include "core/cpu_features.hpp"
#include "embedding/stream_store.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define MICA_PLACE_AVX2 1
#endif

namespace mica {

namespace {

void place(const VertexBinding& b, const Tet& t, const Vec3List& x, double* out) {
  const double *x0 = x[size_t(t[0])].data(), *x1 = x[size_t(t[1])].data(), *x2 = x[size_t(t[2])].data(),
               *x3 = x[size_t(t[3])].data();
  const double w1 = b.weights[0], w2 = b.weights[1], w3 = b.weights[2], w0 = 1 - (w1 + w2 + w3);
  for (int a = 0; a < 3; ++a) out[a] = w0 * x0[a] + w1 * x1[a] + w2 * x2[a] + w3 * x3[a];
}

void place_generic(const VertexBinding* bindings, int32_t count, const std::vector<Tet>& tets, const Vec3List& x,
                   double* out_xyz, const int32_t* slot, NormalSlot* scratch) {
  for (int32_t k = 0; k < count; ++k) {
    const VertexBinding& b = bindings[k];
    double* out = out_xyz + 3 * size_t(b.vertex);
    if (b.tet >= 0) place(b, tets[size_t(b.tet)], x, out);
    if (!scratch) continue;
    NormalSlot& s = scratch[slot[k]];
    std::copy_n(out, 3, s.xyz);
    std::fill_n(s.normal, 4, 0.0);
  }
}

#if MICA_PLACE_AVX2
// The weighted sum of the four nodes of t, each read as four doubles: x, y, z and the next node's x
// (one load), or 0 for the last node (kSafe: a tet with the last node, whose next double is past
// the array). Both give the same bits.
template <bool kSafe>
__attribute__((target("avx2,fma"))) inline __m256d node(const double* base, int32_t n) {
  const double* p = base + 3 * size_t(n);
  if (!kSafe) return _mm256_loadu_pd(p);
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p)), _mm_load_sd(p + 2), 1);
}

template <bool kSafe>
__attribute__((target("avx2,fma"))) inline __m256d weighted_sum(const double* base, const Tet& t,
                                                                const VertexBinding& b) {
  const double w0 = 1 - (b.weights[0] + b.weights[1] + b.weights[2]);
  __m256d p = _mm256_mul_pd(_mm256_set1_pd(w0), node<kSafe>(base, t[0]));
  p = _mm256_fmadd_pd(_mm256_broadcast_sd(&b.weights[0]), node<kSafe>(base, t[1]), p);
  p = _mm256_fmadd_pd(_mm256_broadcast_sd(&b.weights[1]), node<kSafe>(base, t[2]), p);
  return _mm256_fmadd_pd(_mm256_broadcast_sd(&b.weights[2]), node<kSafe>(base, t[3]), p);
}

// Each node read as four doubles, four FMAs a vertex where the generic loop takes twelve multiplies
// and nine additions, and the position streamed past the cache (the host's array is not read here
// again; the sums read the scratch). The library is built for any x86-64, so this is compiled for
// AVX2 + FMA and called where the CPU has them.
__attribute__((target("avx2,fma"))) void place_avx2(const VertexBinding* bindings, int32_t count,
                                                    const std::vector<Tet>& tets, const Vec3List& x,
                                                    double* out_xyz, const int32_t* slot, NormalSlot* scratch) {
  const double* base = x.data()->data();
  for (int32_t k = 0; k < count; ++k) {
    const VertexBinding& b = bindings[k];
    double* out = out_xyz + 3 * size_t(b.vertex);
    __m256d p;
    if (b.tet < 0) {  // unbound: the host's value stays, and the sums read it
      if (!scratch) continue;
      p = _mm256_setr_pd(out[0], out[1], out[2], 0);
    } else {
      const Tet& t = tets[size_t(b.tet)];
      p = b.has_last_node ? weighted_sum<true>(base, t, b) : weighted_sum<false>(base, t, b);
      stream3(out, p);
      if (!scratch) continue;
    }
    NormalSlot& s = scratch[slot[k]];
    _mm256_store_pd(s.xyz, p);
    _mm256_store_pd(s.normal, _mm256_setzero_pd());
  }
  _mm_sfence();  // the streamed positions ordered before what the caller writes next
}

bool avx2_supported() { return cpu::avx2_fma(); }
#endif

}  // namespace

void place_vertices(const VertexBinding* bindings, int32_t count, const std::vector<Tet>& tets, const Vec3List& x,
                    double* out_xyz, const int32_t* slot, NormalSlot* scratch) {
#if MICA_PLACE_AVX2
  if (avx2_supported()) return place_avx2(bindings, count, tets, x, out_xyz, slot, scratch);
#endif
  place_generic(bindings, count, tets, x, out_xyz, slot, scratch);
}

}  // namespace mica
