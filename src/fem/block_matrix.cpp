// SPDX-License-Identifier: Apache-2.0
#include "fem/block_matrix.hpp"

#include <algorithm>

#include "core/cpu_features.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

namespace mica {

int32_t BlockPattern::find(int32_t i, int32_t j) const {
  const auto first = col.begin() + row_start[i], last = col.begin() + row_start[i + 1];
  const auto it = std::lower_bound(first, last, j);
  return (it != last && *it == j) ? int32_t(it - col.begin()) : -1;
}

BlockPattern build_block_pattern(int32_t node_count, const std::vector<Tet>& tets) {
  std::vector<std::vector<int32_t>> adjacency(static_cast<size_t>(node_count));
  for (const Tet& t : tets)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) adjacency[t[a]].push_back(t[b]);
  BlockPattern p;
  p.rows = node_count;
  p.row_start.assign(size_t(node_count) + 1, 0);
  p.diag.assign(size_t(node_count), -1);
  for (int32_t i = 0; i < node_count; ++i) {
    auto& row = adjacency[i];
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    p.row_start[i + 1] = p.row_start[i] + int32_t(row.size());
  }
  p.col.reserve(size_t(p.row_start.back()));
  for (int32_t i = 0; i < node_count; ++i) {
    for (int32_t j : adjacency[i]) {
      if (j == i) p.diag[i] = int32_t(p.col.size());
      p.col.push_back(j);
    }
  }
  return p;
}

std::vector<std::array<int32_t, 16>> element_block_slots(const BlockPattern& p, const std::vector<Tet>& tets) {
  std::vector<std::array<int32_t, 16>> slots(tets.size());
  for (size_t e = 0; e < tets.size(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) slots[e][4 * a + b] = p.find(tets[e][a], tets[e][b]);
  return slots;
}

namespace {

// y = A x; with kBound also bound[i] = (sum_k |A_k|^2)(sum_k |x_col(k)|^2) over row i's blocks.
template <bool kBound>
void block_multiply_sse2(const BlockPattern& p, const BlockValues& A, const Vec3List& x, Vec3List& y, double* bound) {
  for (int32_t i = 0; i < p.rows; ++i) {
    Vec3 sum = Vec3::Zero();
    double a2 = 0, x2 = 0;
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) {
      sum += A[k] * x[p.col[k]];
      if (kBound) a2 += A[k].squaredNorm(), x2 += x[p.col[k]].squaredNorm();
    }
    y[i] = sum;
    if (kBound) bound[i] = a2 * x2;
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define MICA_BLOCK_AVX2 1
// A block's three columns as three vectors of 4 (the 4th lane reads the next column's first
// entry, or the next block's: the array's last block goes the SSE2 way), 3 FMAs a block where
// SSE2 takes 9 scalar ones: 0.054 -> 0.042 ms on the nidus's 30 k blocks. With kBound, the squares
// of the entries summed too (lanes 0-2 of each load). Written by hand for the reason
// half_products.hpp gives: the library is built for any x86-64.
template <bool kBound>
__attribute__((target("avx2,fma"))) void block_multiply_avx2(const BlockPattern& p, const BlockValues& A,
                                                                 const Vec3List& x, Vec3List& y, double* bound) {
  const int32_t blocks = p.row_start[p.rows];
  for (int32_t i = 0; i < p.rows; ++i) {
    __m256d s0 = _mm256_setzero_pd(), s1 = _mm256_setzero_pd(), q = _mm256_setzero_pd();
    double x2 = 0;
    const int32_t end = std::min(p.row_start[i + 1], blocks - 1);
    for (int32_t k = p.row_start[i]; k < end; ++k) {
      const double *a = A[k].data(), *v = x[p.col[k]].data();
      const __m256d c0 = _mm256_loadu_pd(a), c1 = _mm256_loadu_pd(a + 3), c2 = _mm256_loadu_pd(a + 6);
      s0 = _mm256_fmadd_pd(c0, _mm256_set1_pd(v[0]), s0);
      s1 = _mm256_fmadd_pd(c1, _mm256_set1_pd(v[1]), s1);
      s0 = _mm256_fmadd_pd(c2, _mm256_set1_pd(v[2]), s0);
      if (kBound) {
        q = _mm256_fmadd_pd(c0, c0, _mm256_fmadd_pd(c1, c1, _mm256_fmadd_pd(c2, c2, q)));
        x2 += v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      }
    }
    alignas(32) double sum[4], a2[4];
    _mm256_store_pd(sum, _mm256_add_pd(s0, s1));
    y[i] = Vec3(sum[0], sum[1], sum[2]);
    if (end < p.row_start[i + 1]) y[i] += A[end] * x[p.col[end]];
    if (!kBound) continue;
    _mm256_store_pd(a2, q);
    double a2_sum = a2[0] + a2[1] + a2[2];
    if (end < p.row_start[i + 1]) a2_sum += A[end].squaredNorm(), x2 += x[p.col[end]].squaredNorm();
    bound[i] = a2_sum * x2;
  }
}

bool avx2_supported() { return cpu::avx2_fma(); }
#endif

}  // namespace

void block_multiply(const BlockPattern& p, const BlockValues& A, const Vec3List& x, Vec3List& y) {
#ifdef MICA_BLOCK_AVX2
  if (avx2_supported()) return block_multiply_avx2<false>(p, A, x, y, nullptr);
#endif
  block_multiply_sse2<false>(p, A, x, y, nullptr);
}

void block_multiply_bound(const BlockPattern& p, const BlockValues& A, const Vec3List& x, Vec3List& y,
                          std::vector<double>& bound) {
#ifdef MICA_BLOCK_AVX2
  if (avx2_supported()) return block_multiply_avx2<true>(p, A, x, y, bound.data());
#endif
  block_multiply_sse2<true>(p, A, x, y, bound.data());
}

}  // namespace mica
