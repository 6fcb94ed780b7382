// SPDX-License-Identifier: Apache-2.0
// add_neo_hookean_element's steps (neo_hookean.cpp) four lanes wide: each quantity a lane vector,
// lane l that of element e[l]; matrices column-major as in lanes4.hpp, M[3j + i] entry (i, j).
#include "fem/neo_hookean_elements4.hpp"

#include "fem/eigensystems4.hpp"
#include "fem/fem_model.hpp"
#include "fem/lanes4.hpp"
#include "fem/rotation_variant_svd.hpp"

namespace mica {

namespace {

#ifdef MICA_LANES4
using namespace lanes4;
// GCC's and Clang's operators on __m256d are the lane-wise IEEE operations (the compiler may fuse a
// product and a sum into one FMA).
using Lanes = __m256d;

MICA_AVX2 inline Lanes max4(Lanes a, Lanes b) { return _mm256_max_pd(a, b); }
MICA_AVX2 inline Lanes sqrt4(Lanes a) { return _mm256_sqrt_pd(a); }
// A bit per lane where a > b (false for NaN).
MICA_AVX2 inline int greater_bits(Lanes a, Lanes b) { return _mm256_movemask_pd(_mm256_cmp_pd(a, b, _CMP_GT_OQ)); }

// Lane l of four matrices, and lane l set from a matrix.
MICA_AVX2 inline Mat3 lane(const Lanes M[9], int l) {
  Mat3 out;
  for (int q = 0; q < 9; ++q) out(q) = M[q][l];
  return out;
}
MICA_AVX2 inline void set_lane(Lanes M[9], int l, const Mat3& m) {
  for (int q = 0; q < 9; ++q) M[q][l] = m(q);
}

// rotation_variant_svd in lanes: U, s, V.
MICA_AVX2 void svd_lanes(const Lanes F[9], Lanes U[9], Lanes s[3], Lanes V[9]) {
  const Lanes C[6] = {dot(F, F), dot(F + 3, F + 3), dot(F + 6, F + 6), dot(F, F + 3), dot(F, F + 6), dot(F + 3, F + 6)};
  Lanes lambda[3], E[9];  // ascending
  symmetric_eigensystems(C, lambda, E);
  const Lanes zero = _mm256_setzero_pd();
  s[0] = sqrt4(max4(lambda[2], zero));
  s[1] = sqrt4(max4(lambda[1], zero));
  for (int i = 0; i < 3; ++i) {
    V[i] = E[6 + i];
    V[3 + i] = E[3 + i];
  }
  cross(V, V + 3, V + 6);  // det V = +1
  Lanes* u0 = U;
  Lanes* u1 = U + 3;
  apply(F, V, u0);
  apply(F, V + 3, u1);
  // Products with reciprocals where the reference divides: the same to round-off.
  const Lanes one = all(1.0), inverse_s0 = one / s[0], inverse_s1 = one / s[1];
  for (int i = 0; i < 3; ++i) u0[i] = u0[i] * inverse_s0, u1[i] = u1[i] * inverse_s1;
  const Lanes d = dot(u1, u0);
  for (int i = 0; i < 3; ++i) u1[i] = u1[i] - d * u0[i];  // orthonormal to round-off
  const Lanes inverse_n1 = one / sqrt4(dot(u1, u1)), inverse_n0 = one / sqrt4(dot(u0, u0));
  for (int i = 0; i < 3; ++i) u1[i] = u1[i] * inverse_n1, u0[i] = u0[i] * inverse_n0;
  cross(u0, u1, U + 6);
  Lanes Fv2[3];
  apply(F, V + 6, Fv2);
  s[2] = dot(U + 6, Fv2);
  // Nearly flat or needle-like elements (or NaN): Jacobi, lane by lane.
  const int ill = ~greater_bits(s[1], all(1e-3) * s[0]) & 0xF;
  for (int l = 0; l < 4; ++l) {
    if (!(ill >> l & 1)) continue;
    Mat3 Ul, Vl;
    Vec3 sl;
    rotation_variant_svd_jacobi(lane(F, l), Ul, sl, Vl);
    set_lane(U, l, Ul);
    set_lane(V, l, Vl);
    for (int k = 0; k < 3; ++k) s[k][l] = sl[k];
  }
}

// The projected Hessian in the SVD frame (neo_hookean_frame): the scaling block A and the pairs'
// d1, d2. Lanes whose A is not positive definite are clamped lane by lane.
MICA_AVX2 void frame_lanes(const NeoHookean p[4], const Lanes U[9], const Lanes s[3], const Lanes V[9], Lanes A[9],
                           Lanes d1[3], Lanes d2[3]) {
  const Lanes mu = _mm256_setr_pd(p[0].mu, p[1].mu, p[2].mu, p[3].mu);
  const Lanes lambda = _mm256_setr_pd(p[0].lambda, p[1].lambda, p[2].lambda, p[3].lambda);
  const Lanes alpha = _mm256_setr_pd(p[0].alpha, p[1].alpha, p[2].alpha, p[3].alpha);
  const Lanes zero = _mm256_setzero_pd(), half = all(0.5);
  const Lanes w = lambda * (s[0] * s[1] * s[2] - alpha);
  for (int k = 0; k < 3; ++k) {
    const Lanes twist = max4(mu + w * s[k], zero), flip = max4(mu - w * s[k], zero);
    d1[k] = half * (twist + flip);
    d2[k] = half * (flip - twist);
  }
  const Lanes g[3] = {s[1] * s[2], s[0] * s[2], s[0] * s[1]};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) A[3 * c + r] = lambda * g[r] * g[c] + (r == c ? mu : w * s[3 - r - c]);
  // Positive definite by its leading minors (the common case): nothing to clamp.
  const Lanes m2 = A[0] * A[4] - A[3] * A[3];
  const Lanes det = A[0] * (A[4] * A[8] - A[7] * A[7]) - A[3] * (A[3] * A[8] - A[7] * A[6]) +
                    A[6] * (A[3] * A[7] - A[4] * A[6]);
  const int definite = greater_bits(A[0], zero) & greater_bits(m2, zero) & greater_bits(det, zero);
  for (int l = 0; l < 4; ++l) {
    if (definite >> l & 1) continue;
    const Vec3 sl(s[0][l], s[1][l], s[2][l]);
    set_lane(A, l, neo_hookean_frame(p[l], lane(U, l), sl, lane(V, l)).A);
  }
}

MICA_AVX2 void add_elements4_avx2(const FemModel& m, const int32_t e[4], const Vec3List& x,
                                   const NeoHookeanAssembly& what, Vec3List& f) {
  const TetElement* el[4];
  NeoHookean p[4];
  for (int l = 0; l < 4; ++l) el[l] = &m.elements[e[l]], p[l] = neo_hookean_parameters(m.lame[e[l]]);
  Lanes g[4][3];
  load_gradients(el, g);
  const Lanes volume = _mm256_setr_pd(el[0]->volume, el[1]->volume, el[2]->volume, el[3]->volume);
  const Lanes mu = _mm256_setr_pd(p[0].mu, p[1].mu, p[2].mu, p[3].mu);
  const Lanes lambda = _mm256_setr_pd(p[0].lambda, p[1].lambda, p[2].lambda, p[3].lambda);
  const Lanes alpha = _mm256_setr_pd(p[0].alpha, p[1].alpha, p[2].alpha, p[3].alpha);

  // P = mu F + lambda (J - alpha) cof(F), cof's columns f1 x f2, f2 x f0, f0 x f1.
  Lanes ds[9], F[9], cof[9], P[9];
  edge_lanes(el, x, ds);
  deformation_gradients(ds, g, F);
  cross(F + 3, F + 6, cof);
  cross(F + 6, F, cof + 3);
  cross(F, F + 3, cof + 6);
  const Lanes J = dot(F, cof);
  const Lanes lw = lambda * (J - alpha);
  for (int q = 0; q < 9; ++q) P[q] = mu * F[q] + lw * cof[q];

  const bool need_frame = what.K || what.v_lin || what.R || what.lin;
  Lanes U[9], s[3], V[9], A[9], d1[3], d2[3];
  if (need_frame) {
    svd_lanes(F, U, s, V);
    frame_lanes(p, U, s, V, A, d1, d2);
  }
  if (what.R) {  // U V^T
    Lanes R[9];
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) R[3 * j + i] = product_transposed(U, V, i, j);
    Mat3* out[4] = {&(*what.R)[e[0]], &(*what.R)[e[1]], &(*what.R)[e[2]], &(*what.R)[e[3]]};
    store_matrices(out, R);
  }
  if (what.lin) {
    // Psi = mu/2 (|F|^2 - 3) - mu (J - 1) + lambda/2 (J - 1)^2 (neo_hookean_energy_density).
    const Lanes j = J - all(1.0);
    const Lanes F2 = dot(F, F) + dot(F + 3, F + 3) + dot(F + 6, F + 6);
    alignas(32) double energy[4];
    _mm256_store_pd(energy, volume * (all(0.5) * mu * (F2 - all(3.0)) - mu * j + all(0.5) * lambda * j * j));
    NeoHookeanLinearisation& lin = *what.lin;
    Mat3* Pl[4] = {&lin.stress[e[0]], &lin.stress[e[1]], &lin.stress[e[2]], &lin.stress[e[3]]};
    store_matrices(Pl, P);
    Mat3 *fu[4], *fv[4], *fa[4];
    for (int l = 0; l < 4; ++l) {
      NeoHookeanFrame& frame = lin.frame[e[l]];
      fu[l] = &frame.U, fv[l] = &frame.V, fa[l] = &frame.A;
    }
    store_matrices(fu, U);
    store_matrices(fv, V);
    store_matrices(fa, A);
    for (int l = 0; l < 4; ++l) {
      lin.energy[e[l]] = energy[l];
      lin.frame[e[l]].d1 = Vec3(d1[0][l], d1[1][l], d1[2][l]);
      lin.frame[e[l]].d2 = Vec3(d2[0][l], d2[1][l], d2[2][l]);
    }
  }

  // f_a = -V P g_a, and with v_lin + h V (H : F(v_lin)) g_a.
  Lanes stress[9];
  for (int q = 0; q < 9; ++q) stress[q] = -volume * P[q];
  if (what.v_lin) {
    // H : dF = U Y V^T with X = U^T dF V: diag(Y) = A diag(X), each pair (i, j) through [[d1, d2], [d2, d1]].
    Lanes dsv[9], dF[9], T[9], X[9], Y[9];
    edge_lanes(el, *what.v_lin, dsv);
    deformation_gradients(dsv, g, dF);
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) T[3 * j + i] = transposed_product(U, dF, i, j);
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) X[3 * j + i] = product(T, V, i, j);
    for (int r = 0; r < 3; ++r) Y[4 * r] = A[r] * X[0] + A[3 + r] * X[4] + A[6 + r] * X[8];
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      Y[3 * j + i] = d1[k] * X[3 * j + i] + d2[k] * X[3 * i + j];
      Y[3 * i + j] = d2[k] * X[3 * j + i] + d1[k] * X[3 * i + j];
    }
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) T[3 * j + i] = product(U, Y, i, j);
    const Lanes hv = all(what.h) * volume;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) stress[3 * j + i] = stress[3 * j + i] + hv * product_transposed(T, V, i, j);
  }
  for (int a = 0; a < 4; ++a) {
    Lanes fa[3];
    apply(stress, g[a], fa);
    Vec3* node[4] = {&f[el[0]->nodes[a]], &f[el[1]->nodes[a]], &f[el[2]->nodes[a]], &f[el[3]->nodes[a]]};
    add_vectors(node, fa);
  }
  if (!what.K) return;

  // K_ab = U M_ab U^T, M_ab = diag(u) A diag(v) plus the pairs' terms, u = V^T g_a and v = V^T g_b
  // (add_neo_hookean_element): M(r, c) = u_r A_rc v_c, and for each pair (i, j) of k
  // M(i, i) += d1_k u_j v_j, M(j, j) += d1_k u_i v_i, M(i, j) += d2_k u_j v_i, M(j, i) += d2_k u_i v_j.
  // Per node the factors of v: uA(r, c) = u_r A_rc, and the pairs' e1(r, c) = d1_k u_c on the
  // diagonal and e2(r, c) = d2_k u_c off it (k = 3 - r - c), all scaled by k_scale V.
  const Lanes scale = all(what.k_scale) * volume;
  Lanes uA[4][9], e1[4][9], e2[4][9], gh[4][3];
  for (int a = 0; a < 4; ++a) {
    for (int r = 0; r < 3; ++r) gh[a][r] = dot(V + 3 * r, g[a]);  // V^T g_a
    const Lanes* u = gh[a];
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) {
        const Lanes su = scale * u[r];
        uA[a][3 * c + r] = su * A[3 * c + r];
        if (r == c) continue;
        e1[a][3 * c + r] = scale * d1[3 - r - c] * u[c];
        e2[a][3 * c + r] = scale * d2[3 - r - c] * u[c];
      }
  }
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b) {
      const Lanes* v = gh[b];
      Lanes M[9], T[9], k[9];
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
          if (r != c) M[3 * c + r] = uA[a][3 * c + r] * v[c] + e2[a][3 * c + r] * v[r];
      for (int r = 0; r < 3; ++r) {
        const int i = (r + 1) % 3, j = (r + 2) % 3;  // M(r, r) gets the terms of columns i and j
        M[4 * r] = uA[a][4 * r] * v[r] + e1[a][3 * i + r] * v[i] + e1[a][3 * j + r] * v[j];
      }
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) T[3 * c + r] = product(U, M, r, c);
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) k[3 * c + r] = product_transposed(T, U, r, c);
      Mat3* ab[4];
      for (int l = 0; l < 4; ++l) ab[l] = &what.K->data()[m.slots[e[l]][4 * a + b]];
      add_blocks(ab, k);
      if (b == a) continue;
      Mat3* ba[4];
      for (int l = 0; l < 4; ++l) ba[l] = &what.K->data()[m.slots[e[l]][4 * b + a]];
      add_blocks(ba, {k[0], k[3], k[6], k[1], k[4], k[7], k[2], k[5], k[8]});
    }
}
#endif

}  // namespace

void add_neo_hookean_elements4(const FemModel& m, const int32_t e[4], const Vec3List& x_lin,
                               const NeoHookeanAssembly& what, Vec3List& f_int) {
#ifdef MICA_LANES4
  if (lanes4::supported()) return add_elements4_avx2(m, e, x_lin, what, f_int);
#endif
  for (int l = 0; l < 4; ++l) add_neo_hookean_element(m, e[l], x_lin, what, f_int);
}

}  // namespace mica
