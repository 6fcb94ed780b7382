// SPDX-License-Identifier: Apache-2.0
#include "solver/half_products.hpp"

#include "core/cpu_features.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <cpuid.h>
#include <immintrin.h>
#define MICA_HALF_PRODUCTS 1
#define MICA_F16C __attribute__((target("avx2,fma,f16c")))
#endif

namespace mica {

#ifdef MICA_HALF_PRODUCTS

bool half_products_supported() {
  // F16C from CPUID leaf 1 (ECX bit 29): clang 14 has no "f16c" for __builtin_cpu_supports. Its
  // "avx2" also checks that the OS saves the AVX registers.
  static const bool supported = [] {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    const bool f16c = __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C) != 0;
    return f16c && cpu::avx2_fma();
  }();
  return supported;
}

namespace {

MICA_F16C inline __m256 load8(const uint16_t* p) {
  return _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

MICA_F16C inline float sum8(__m256 v) {  // a fixed order: the same bits every call
  __m128 s = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  s = _mm_add_ps(s, _mm_movehl_ps(s, s));
  s = _mm_add_ss(s, _mm_shuffle_ps(s, s, 1));
  return _mm_cvtss_f32(s);
}

}  // namespace

MICA_F16C void to_half(const float* in, size_t n, float scale, uint16_t* out) {
  size_t q = 0;
  const __m256 s = _mm256_set1_ps(scale);
  for (; q + 8 <= n; q += 8)  // eight at a time, rounded as one at a time
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + q),
                     _mm256_cvtps_ph(_mm256_mul_ps(_mm256_loadu_ps(in + q), s), _MM_FROUND_TO_NEAREST_INT));
  for (; q < n; ++q) out[q] = _cvtss_sh(in[q] * scale, _MM_FROUND_TO_NEAREST_INT);
}

MICA_F16C void half_product(const uint16_t* B, int ld, int rows, int nc, const float* x, float s, float* y) {
  int i = 0;
  for (; i + 16 <= rows; i += 16) {  // 16 rows held in two registers across the columns
    __m256 a0 = _mm256_setzero_ps(), a1 = _mm256_setzero_ps();
    for (int j = 0; j < nc; ++j) {
      const __m256 xj = _mm256_set1_ps(x[j]);
      const uint16_t* c = B + size_t(j) * size_t(ld) + i;
      a0 = _mm256_fmadd_ps(load8(c), xj, a0);
      a1 = _mm256_fmadd_ps(load8(c + 8), xj, a1);
    }
    const __m256 scale = _mm256_set1_ps(s);
    _mm256_storeu_ps(y + i, _mm256_mul_ps(a0, scale));
    _mm256_storeu_ps(y + i + 8, _mm256_mul_ps(a1, scale));
  }
  if (i + 8 <= rows) {  // 8 rows more
    __m256 a = _mm256_setzero_ps();
    for (int j = 0; j < nc; ++j) a = _mm256_fmadd_ps(load8(B + size_t(j) * size_t(ld) + i), _mm256_set1_ps(x[j]), a);
    _mm256_storeu_ps(y + i, _mm256_mul_ps(a, _mm256_set1_ps(s)));
    i += 8;
  }
  for (; i < rows; ++i) {
    float sum = 0;
    for (int j = 0; j < nc; ++j) sum += _cvtsh_ss(B[size_t(j) * size_t(ld) + i]) * x[j];
    y[i] = sum * s;
  }
}

MICA_F16C void half_transposed_product(const uint16_t* B, int ld, int rows, int nc, const float* y, float s,
                                       float* out) {
  const size_t stride = size_t(ld);
  int j = 0;
  for (; j + 4 <= nc; j += 4) {  // four columns share each load of y
    const uint16_t* c = B + size_t(j) * stride;
    __m256 a0 = _mm256_setzero_ps(), a1 = a0, a2 = a0, a3 = a0;
    int i = 0;
    for (; i + 8 <= rows; i += 8) {
      const __m256 v = _mm256_loadu_ps(y + i);
      a0 = _mm256_fmadd_ps(load8(c + i), v, a0);
      a1 = _mm256_fmadd_ps(load8(c + stride + i), v, a1);
      a2 = _mm256_fmadd_ps(load8(c + 2 * stride + i), v, a2);
      a3 = _mm256_fmadd_ps(load8(c + 3 * stride + i), v, a3);
    }
    float sum[4] = {sum8(a0), sum8(a1), sum8(a2), sum8(a3)};
    for (; i < rows; ++i)
      for (int q = 0; q < 4; ++q) sum[q] += _cvtsh_ss(c[size_t(q) * stride + i]) * y[i];
    for (int q = 0; q < 4; ++q) out[j + q] = sum[q] * s;
  }
  for (; j < nc; ++j) {
    const uint16_t* c = B + size_t(j) * stride;
    __m256 a = _mm256_setzero_ps();
    int i = 0;
    for (; i + 8 <= rows; i += 8) a = _mm256_fmadd_ps(load8(c + i), _mm256_loadu_ps(y + i), a);
    float sum = sum8(a);
    for (; i < rows; ++i) sum += _cvtsh_ss(c[i]) * y[i];
    out[j] = sum * s;
  }
}

#else  // not x86-64: no half copy (the single-precision one serves)

bool half_products_supported() { return false; }
void to_half(const float*, size_t, float, uint16_t*) {}
void half_product(const uint16_t*, int, int, int, const float*, float, float*) {}
void half_transposed_product(const uint16_t*, int, int, int, const float*, float, float*) {}

#endif

}  // namespace mica
