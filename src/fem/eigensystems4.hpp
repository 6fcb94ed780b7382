// SPDX-License-Identifier: Apache-2.0
// The eigensystems of four symmetric 3x3 matrices side by side in AVX2 lanes (lanes4.hpp): Eigen's
// closed form (SelfAdjointEigenSolver<Matrix3d>::computeDirect, Eigen 3.4) step by step, each of
// its branches a lane-wise selection and its atan2, cos and sin polynomials (within 2e-16),
// so the same results lane by lane, to round-off, with no calls and no branch per lane. Like computeDirect
// it is accurate to the round-off of the matrix where the eigenvalues are apart, and to about its
// square root at a double eigenvalue (the cubic's double root).
#pragma once
#include "fem/lanes4.hpp"

#ifdef MICA_LANES4
namespace mica::lanes4 {

namespace eigensystems_detail {

MICA_AVX2 inline __m256d abs4(__m256d v) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v); }
// Lane-wise a where the mask's sign bit is set, else b.
MICA_AVX2 inline __m256d select(__m256d mask, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, mask); }
MICA_AVX2 inline __m256d greater(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }

// c[0] + c[1] t + ... + c[n - 1] t^(n - 1).
template <int n>
MICA_AVX2 inline __m256d polynomial(__m256d t, const double (&c)[n]) {
  __m256d r = all(c[n - 1]);
  for (int k = n - 2; k >= 0; --k) r = r * t + all(c[k]);
  return r;
}

// atan2(y, x) for y >= 0, in [0, pi] (0 for y = x = 0). atan z for z = min / max of |x| and y in
// [0, 1]: above tan(pi/12), pi/6 + atan w with w = (sqrt(3) z - 1) / (z + sqrt(3)); then
// |w| <= tan(pi/12), where atan w = w + w^3 p(w^2), p interpolating at Chebyshev nodes (within 1e-18).
MICA_AVX2 inline __m256d atan2_upper(__m256d y, __m256d x) {
  static constexpr double p[9] = {-0.3333333333333333,   0.1999999999999688,   -0.14285714284553813,
                                  0.11111110944516939,   -0.09090897081592211, 0.07691819638198708,
                                  -0.06654945053677658,  0.05716329894442852,  -0.03957893591546196};
  const double sqrt3 = 1.7320508075688772, pi = 3.141592653589793;
  const __m256d ax = abs4(x), zero = _mm256_setzero_pd();
  const __m256d lo = _mm256_min_pd(y, ax), hi = _mm256_max_pd(y, ax);
  const __m256d z = lo / select(greater(hi, zero), hi, all(1.0));
  const __m256d reduced = greater(z, all(0.2679491924311227));
  const __m256d w = select(reduced, (all(sqrt3) * z - all(1.0)) / (z + all(sqrt3)), z);
  const __m256d w2 = w * w;
  __m256d a = w + w * w2 * polynomial(w2, p);
  a = select(reduced, all(pi / 6) + a, a);
  a = select(greater(y, ax), all(pi / 2) - a, a);
  return select(x, all(pi) - a, a);  // by x's sign bit: atan2(0, -0) = pi
}

// cos and sin of t in [0, pi/3]: cos t = 1 + t^2 c(t^2), sin t = t + t^3 s(t^2), c and s
// interpolating at Chebyshev nodes (within 1e-19).
MICA_AVX2 inline void cos_sin(__m256d t, __m256d& c, __m256d& s) {
  static constexpr double pc[8] = {-0.5,
                                   0.041666666666666664,
                                   -0.0013888888888888668,
                                   2.4801587301426548e-05,
                                   -2.755731916637592e-07,
                                   2.087674577367264e-09,
                                   -1.1469535736796277e-11,
                                   4.711431361376026e-14};
  static constexpr double ps[7] = {-0.16666666666666666,    0.008333333333333276, -0.00019841269841185433,
                                   2.7557319177787585e-06,  -2.50520963418345e-08, 1.6057431359176808e-10,
                                   -7.539987017771985e-13};
  const __m256d t2 = t * t;
  c = all(1.0) + t2 * polynomial(t2, pc);
  s = t + t * t2 * polynomial(t2, ps);
}

MICA_AVX2 inline __m256d squared_norm(const __m256d* v) { return dot(v, v); }
// v / |v| where |v| > 0 (Eigen's normalized()); here and below a product with the reciprocal
// where Eigen divides (one division, not three: the same to round-off).
MICA_AVX2 inline void normalise(__m256d* v) {
  const __m256d n2 = squared_norm(v);
  const __m256d inverse = all(1.0) / select(greater(n2, _mm256_setzero_pd()), _mm256_sqrt_pd(n2), all(1.0));
  for (int i = 0; i < 3; ++i) v[i] = v[i] * inverse;
}

// Eigen's extract_kernel of a symmetric m of rank 2 (entries 00, 11, 22, 10, 20, 21): i0 the first
// diagonal entry largest in magnitude, the larger of col(i0) x col(i0 + 1) and col(i0) x col(i0 + 2)
// (indices mod 3) normalised; and col(i0).
MICA_AVX2 inline void extract_kernel(const __m256d m[6], __m256d kernel[3], __m256d column[3]) {
  const __m256d col[3][3] = {{m[0], m[3], m[4]}, {m[3], m[1], m[5]}, {m[4], m[5], m[2]}};
  const __m256d d0 = abs4(m[0]), d1 = abs4(m[1]), d2 = abs4(m[2]);
  const __m256d is1 = greater(d1, d0);                         // maxCoeff keeps the first maximum
  const __m256d is2 = greater(d2, select(is1, d1, d0));
  __m256d x01[3], x12[3], x20[3];
  cross(col[0], col[1], x01);
  cross(col[1], col[2], x12);
  cross(col[2], col[0], x20);
  // i0 = 0: x01 and -x20; i0 = 1: x12 and -x01; i0 = 2: x20 and -x12.
  __m256d c0[3], c1[3];
  for (int i = 0; i < 3; ++i) {
    c0[i] = select(is2, x20[i], select(is1, x12[i], x01[i]));
    c1[i] = -select(is2, x12[i], select(is1, x01[i], x20[i]));
    column[i] = select(is2, col[2][i], select(is1, col[1][i], col[0][i]));
  }
  const __m256d n0 = squared_norm(c0), n1 = squared_norm(c1);
  const __m256d first = greater(n0, n1);
  const __m256d inverse = all(1.0) / _mm256_sqrt_pd(select(first, n0, n1));
  for (int i = 0; i < 3; ++i) kernel[i] = select(first, c0[i], c1[i]) * inverse;
}

}  // namespace eigensystems_detail

// The eigenvalues of the symmetric C (entries 00, 11, 22, 10, 20, 21), ascending, in lambda, and
// their unit eigenvectors, column k for lambda[k], in E (column-major).
MICA_AVX2 inline void symmetric_eigensystems(const __m256d C[6], __m256d lambda[3], __m256d E[9]) {
  using namespace eigensystems_detail;
  const double eps = 2.220446049250313e-16, third = 1.0 / 3, sqrt3 = 1.7320508075688772;
  const __m256d zero = _mm256_setzero_pd();
  // Shifted to the mean eigenvalue and scaled into [-1, 1].
  const __m256d shift = (C[0] + C[1] + C[2]) * all(third);
  __m256d m[6] = {C[0] - shift, C[1] - shift, C[2] - shift, C[3], C[4], C[5]};
  __m256d scale = abs4(m[0]);
  for (int q = 1; q < 6; ++q) scale = _mm256_max_pd(scale, abs4(m[q]));
  const __m256d inverse = all(1.0) / select(greater(scale, zero), scale, all(1.0));
  for (__m256d& mq : m) mq = mq * inverse;

  // The roots of x^3 - c2 x^2 + c1 x - c0.
  const __m256d c0 = m[0] * m[1] * m[2] + all(2.0) * m[3] * m[4] * m[5] - m[0] * m[5] * m[5] - m[1] * m[4] * m[4] -
                     m[2] * m[3] * m[3];
  const __m256d c1 = m[0] * m[1] - m[3] * m[3] + m[0] * m[2] - m[4] * m[4] + m[1] * m[2] - m[5] * m[5];
  const __m256d c2 = m[0] + m[1] + m[2];
  const __m256d c2_over_3 = c2 * all(third);
  const __m256d a_over_3 = _mm256_max_pd((c2 * c2_over_3 - c1) * all(third), zero);
  const __m256d half_b = all(0.5) * (c0 + c2_over_3 * (all(2.0) * c2_over_3 * c2_over_3 - c1));
  const __m256d q = _mm256_max_pd(a_over_3 * a_over_3 * a_over_3 - half_b * half_b, zero);
  const __m256d rho = _mm256_sqrt_pd(a_over_3);
  __m256d cos_theta, sin_theta;
  cos_sin(atan2_upper(_mm256_sqrt_pd(q), half_b) * all(third), cos_theta, sin_theta);
  const __m256d r[3] = {c2_over_3 - rho * (cos_theta + all(sqrt3) * sin_theta),
                        c2_over_3 - rho * (cos_theta - all(sqrt3) * sin_theta),
                        c2_over_3 + all(2.0) * rho * cos_theta};

  // The eigenvector of the most distinct eigenvalue (k: 0, or 2 where r2 - r1 > r1 - r0), then the
  // other extreme's (l), then the middle one's as their cross product.
  const __m256d gap_top = r[2] - r[1], gap_bottom = r[1] - r[0];
  const __m256d top = greater(gap_top, gap_bottom);
  const __m256d d0 = select(top, gap_bottom, gap_top);
  const __m256d lambda_k = select(top, r[2], r[0]), lambda_l = select(top, r[0], r[2]);
  __m256d tmp[6] = {m[0] - lambda_k, m[1] - lambda_k, m[2] - lambda_k, m[3], m[4], m[5]};
  __m256d ek[3], el[3], representative[3];
  extract_kernel(tmp, ek, representative);
  // The other two numerically equal (rare): computeDirect's update of the saved column, normalised.
  const __m256d equal = _mm256_cmp_pd(d0, all(2 * eps) * gap_bottom, _CMP_LE_OQ);
  __m256d saved[3];
  if (_mm256_movemask_pd(equal)) {
    const __m256d d = dot(ek, representative);
    for (int i = 0; i < 3; ++i) saved[i] = representative[i] - d * representative[i];
    normalise(saved);
  }
  for (int i = 0; i < 3; ++i) tmp[i] = m[i] - lambda_l;
  extract_kernel(tmp, el, representative);
  if (_mm256_movemask_pd(equal))
    for (int i = 0; i < 3; ++i) el[i] = select(equal, saved[i], el[i]);
  for (int i = 0; i < 3; ++i) {
    E[i] = select(top, el[i], ek[i]);
    E[6 + i] = select(top, ek[i], el[i]);
  }
  cross(E + 6, E, E + 3);
  normalise(E + 3);
  // All three numerically equal: the identity.
  const __m256d same = _mm256_cmp_pd(r[2] - r[0], all(eps), _CMP_LE_OQ);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) E[3 * j + i] = select(same, all(i == j ? 1.0 : 0.0), E[3 * j + i]);
  for (int k = 0; k < 3; ++k) lambda[k] = r[k] * scale + shift;
}

}  // namespace mica::lanes4
#endif
