// SPDX-License-Identifier: Apache-2.0
#include "fem/rotation.hpp"

#include <Eigen/SVD>
#include <cmath>

#include "core/cpu_features.hpp"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#endif

namespace mica {

namespace {

// Irving/Teran: F = U diag(s) V^T; flip the smallest singular direction when det F < 0.
Mat3 rotation_by_svd(const Mat3& F) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  // Singular values come sorted descending: column 2 belongs to the smallest one.
  if (U.determinant() * V.determinant() < 0) U.col(2) = -U.col(2);
  return U * V.transpose();
}

// One entry of two matrices side by side: an SSE2 register, so two rotations cost about one.
using Lanes = Eigen::Array2d;

// c = a x b, for 3-vectors of Lanes.
EIGEN_STRONG_INLINE void cross(const Lanes* a, const Lanes* b, Lanes* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// g = det^(-1/3), the scaling of a Newton step. Newton converges to the same polar factor for any
// g > 0, so g need not be exact: near 1 a cubic Taylor polynomial (within 6e-4 for |t| < 0.25)
// saves the cbrt call.
double newton_scale(double det) {
  const double t = det - 1;
  if (std::abs(t) < 1e-2) return 1.0;  // near the end, plain Newton
  if (std::abs(t) < 0.25) return 1 + t * (-1.0 / 3 + t * (2.0 / 9 - t * (14.0 / 81)));
  return std::cbrt(1 / det);
}

}  // namespace

void proper_rotations(const Mat3& F0, const Mat3& F1, Mat3& R0, Mat3& R1) {
  // Higham's Newton iteration X <- (g X + X^-T / g) / 2 converges quadratically to the polar
  // factor of a well-conditioned F with det F > 0, several times cheaper than an SVD. The scaling
  // g = |det X|^(-1/3) (Higham 1986) takes a uniformly scaled rotation (a node's summed element
  // rotations, ~20 R) there in one step, where plain Newton halves the scale per step. Inverted,
  // nearly collapsed or badly stretched elements take the SVD path.
  // The two matrices iterate side by side, each lane exactly as alone; a lane that has converged
  // is copied out and then iterates on (harmlessly) until the other one has too.
  const Mat3* F[2] = {&F0, &F1};
  Mat3* R[2] = {&R0, &R1};
  bool done[2] = {false, false};
  Lanes X[9];  // column-major, as Mat3
  for (int i = 0; i < 9; ++i) X[i] = Lanes(F0(i), F1(i));
  for (int k = 0; k < 20; ++k) {
    // X^-T = cof(X) / det X, the cofactors by columns.
    Lanes cof[9];
    cross(X + 3, X + 6, cof);
    cross(X + 6, X, cof + 3);
    cross(X, X + 3, cof + 6);
    Lanes det = X[0] * cof[0] + X[1] * cof[1] + X[2] * cof[2];
    if (k == 0) {
      // det F > 1e-3 |F|^3 (no square root); else that lane takes the SVD and iterates on I.
      const Lanes n2(F0.squaredNorm(), F1.squaredNorm());
      const Lanes ok = (det > 0 && det * det > 1e-6 * n2 * n2 * n2).cast<double>();
      for (int l = 0; l < 2; ++l) {
        if (ok(l) != 0) continue;
        *R[l] = rotation_by_svd(*F[l]);
        done[l] = true;
        for (int i = 0; i < 9; ++i) X[i](l) = cof[i](l) = (i % 4 == 0);
        det(l) = 1;
      }
    }
    Lanes g = Lanes::Ones();  // near the end, plain Newton
    if (!((det - 1).abs() < 1e-2).all())
      for (int l = 0; l < 2; ++l) g(l) = newton_scale(det(l));
    const Lanes a = 0.5 * g, b = 0.5 / (g * det);
    Lanes change = Lanes::Zero();
    for (int i = 0; i < 9; ++i) {
      const Lanes next = a * X[i] + b * cof[i];
      change = change.max((next - X[i]).abs());
      X[i] = next;
    }
    // Quadratic convergence: the error left is about change^2 (< 1e-14 here).
    for (int l = 0; l < 2; ++l)
      if (!done[l] && change(l) < 1e-7) {
        for (int i = 0; i < 9; ++i) (*R[l])(i) = X[i](l);
        done[l] = true;
      }
    if (done[0] && done[1]) return;
  }
  for (int l = 0; l < 2; ++l)
    if (!done[l]) *R[l] = rotation_by_svd(*F[l]);
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define MICA_ROTATION_AVX2 1

namespace {

// AVX2 without FMA: a fused multiply-add rounds once where proper_rotations rounds twice, and
// each lane must give its bits (with "fma" GCC contracts a * x + b * y even under -std=c++17).
// The operators on __m256d (GCC's and Clang's vector extensions) are the lane-wise IEEE
// operations, in the order written.
#define MICA_AVX2 __attribute__((target("avx2")))
using Lanes4 = __m256d;

MICA_AVX2 inline Lanes4 abs4(Lanes4 v) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v); }

// A bit per lane where a < b (false for NaN, as a scalar <).
MICA_AVX2 inline int less4(Lanes4 a, Lanes4 b) { return _mm256_movemask_pd(_mm256_cmp_pd(a, b, _CMP_LT_OQ)); }

// c = a x b, for 3-vectors of Lanes4.
MICA_AVX2 inline void cross4(const Lanes4* a, const Lanes4* b, Lanes4* c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

// proper_rotations' iteration in four lanes, line by line the same operations in the same order.
MICA_AVX2 void proper_rotations_avx2(const Mat3 F[4], Mat3 R[4]) {
  bool done[4] = {false, false, false, false};
  Lanes4 X[9];  // column-major, as Mat3
  for (int i = 0; i < 9; ++i) X[i] = _mm256_setr_pd(F[0](i), F[1](i), F[2](i), F[3](i));
  // Every F read before any R is written: R may be F.
  const Lanes4 n2 = _mm256_setr_pd(F[0].squaredNorm(), F[1].squaredNorm(), F[2].squaredNorm(), F[3].squaredNorm());
  const Lanes4 one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
  for (int k = 0; k < 20; ++k) {
    Lanes4 cof[9];
    cross4(X + 3, X + 6, cof);
    cross4(X + 6, X, cof + 3);
    cross4(X, X + 3, cof + 6);
    Lanes4 det = X[0] * cof[0] + X[1] * cof[1] + X[2] * cof[2];
    if (k == 0) {
      const Lanes4 positive = _mm256_cmp_pd(det, _mm256_setzero_pd(), _CMP_GT_OQ);
      const Lanes4 bound = _mm256_set1_pd(1e-6) * n2 * n2 * n2;
      const int ok = _mm256_movemask_pd(_mm256_and_pd(positive, _mm256_cmp_pd(det * det, bound, _CMP_GT_OQ)));
      for (int l = 0; l < 4; ++l) {
        if (ok >> l & 1) continue;
        R[l] = rotation_by_svd(F[l]);
        done[l] = true;
        for (int i = 0; i < 9; ++i) X[i][l] = cof[i][l] = (i % 4 == 0);
        det[l] = 1;
      }
    }
    Lanes4 g = one;
    if (less4(abs4(det - one), _mm256_set1_pd(1e-2)) != 0xF)
      for (int l = 0; l < 4; ++l) g[l] = newton_scale(det[l]);
    const Lanes4 a = half * g, b = half / (g * det);
    Lanes4 change = _mm256_setzero_pd();
    for (int i = 0; i < 9; ++i) {
      const Lanes4 next = a * X[i] + b * cof[i];
      change = _mm256_max_pd(abs4(next - X[i]), change);  // Eigen's max, operands as its pmax
      X[i] = next;
    }
    const int converged = less4(change, _mm256_set1_pd(1e-7));
    for (int l = 0; l < 4; ++l)
      if (!done[l] && (converged >> l & 1)) {
        for (int i = 0; i < 9; ++i) R[l](i) = X[i][l];
        done[l] = true;
      }
    if (done[0] && done[1] && done[2] && done[3]) return;
  }
  for (int l = 0; l < 4; ++l)
    if (!done[l]) R[l] = rotation_by_svd(F[l]);
}

#undef MICA_AVX2

bool avx2_supported() { return cpu::avx2(); }

}  // namespace
#endif

void proper_rotations4(const Mat3 F[4], Mat3 R[4]) {
#ifdef MICA_ROTATION_AVX2
  if (avx2_supported()) return proper_rotations_avx2(F, R);
#endif
  const Mat3 G[4] = {F[0], F[1], F[2], F[3]};  // a copy: the pair's R must not be its F
  proper_rotations(G[0], G[1], R[0], R[1]);
  proper_rotations(G[2], G[3], R[2], R[3]);
}

void proper_rotations(const Mat3* F, Mat3* R, int count) {
  if (count == 4) return proper_rotations4(F, R);
  if (count >= 2) proper_rotations(F[0], F[1], R[0], R[1]);
  if (count % 2 == 1) R[count - 1] = proper_rotation(F[count - 1]);
}

Mat3 proper_rotation(const Mat3& F) {
  Mat3 R, unused;
  proper_rotations(F, Mat3::Identity(), R, unused);  // the second lane converges at once
  return R;
}

}  // namespace mica
