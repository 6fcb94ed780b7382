// SPDX-License-Identifier: Apache-2.0
// Three doubles written past the cache, for arrays the update writes once and does not read again
// (the host's positions and normals): a line written whole by streaming stores need not be read
// first, where an ordinary store reads it from memory before writing it.
#pragma once
#include <cstdint>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>

namespace mica {

// v's first three lanes to out[0..2] in two stores: 16 bytes where out (or out + 1) is 16-aligned,
// and the other 8 (an array of doubles not aligned to 8 bytes, which C does not allow but a host
// may pass, is written the ordinary way). Call _mm_sfence() after the last.
__attribute__((target("avx2"))) inline void stream3(double* out, __m256d v) {
  const uintptr_t misalignment = reinterpret_cast<uintptr_t>(out) & 15;
  if (misalignment == 0) {
    _mm_stream_pd(out, _mm256_castpd256_pd128(v));
    _mm_stream_si64(reinterpret_cast<long long*>(out + 2),
                    _mm_cvtsi128_si64(_mm_castpd_si128(_mm256_extractf128_pd(v, 1))));
  } else if (misalignment == 8) {
    _mm_stream_si64(reinterpret_cast<long long*>(out), _mm_cvtsi128_si64(_mm_castpd_si128(_mm256_castpd256_pd128(v))));
    _mm_stream_pd(out + 1, _mm256_castpd256_pd128(_mm256_permute4x64_pd(v, _MM_SHUFFLE(3, 3, 2, 1))));
  } else {
    _mm_storeu_pd(out, _mm256_castpd256_pd128(v));
    _mm_storel_pd(out + 2, _mm256_extractf128_pd(v, 1));
  }
}

}  // namespace mica
#endif
