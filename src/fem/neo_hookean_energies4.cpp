// SPDX-License-Identifier: Apache-2.0
// add_neo_hookean_model_energies' steps (neo_hookean.cpp) four lanes wide, summed in lanes; matrices
// column-major as in lanes4.hpp, M[3j + i] entry (i, j).
#include "fem/neo_hookean_energies4.hpp"

#include "fem/fem_model.hpp"
#include "fem/lanes4.hpp"

namespace mica {

namespace {

#ifdef MICA_LANES4
using namespace lanes4;
using Lanes = __m256d;  // its operators are the lane-wise IEEE operations (neo_hookean_elements4.cpp)

// dF : H : dF for the four frames (NeoHookeanFrame::quadratic): X = U^T dF V, its diagonal x
// through A, each pair (i, j) of k through [[d1_k, d2_k], [d2_k, d1_k]].
MICA_AVX2 inline Lanes quadratic(const Lanes U[9], const Lanes V[9], const Lanes A[9], const Lanes d1[3],
                                 const Lanes d2[3], const Lanes dF[9]) {
  Lanes T[9], X[9];
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) T[3 * j + i] = transposed_product(U, dF, i, j);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) X[3 * j + i] = product(T, V, i, j);
  Lanes q = _mm256_setzero_pd();
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) q = q + X[4 * r] * A[3 * c + r] * X[4 * c];
  for (int k = 0; k < 3; ++k) {
    const Lanes xij = X[3 * ((k + 2) % 3) + (k + 1) % 3], xji = X[3 * ((k + 1) % 3) + (k + 2) % 3];
    q = q + d1[k] * (xij * xij + xji * xji) + all(2.0) * d2[k] * xij * xji;
  }
  return q;
}

MICA_AVX2 inline double sum(Lanes v) {
  alignas(32) double a[4];
  _mm256_store_pd(a, v);
  return (a[0] + a[1]) + (a[2] + a[3]);
}

MICA_AVX2 int32_t model_energies_avx2(const FemModel& m, const NeoHookeanLinearisation& lin, const Vec3List& x_lin,
                                      const Vec3List& x_end, const Vec3List* v, NeoHookeanModelEnergies& out) {
  const int32_t n = int32_t(m.elements.size()) / 4 * 4;
  Lanes u_end = _mm256_setzero_pd(), u_lin_end = u_end, vKv = u_end;
  for (int32_t e = 0; e < n; e += 4) {
    const TetElement* el[4];
    NeoHookean p[4];
    for (int l = 0; l < 4; ++l) el[l] = &m.elements[e + l], p[l] = neo_hookean_parameters(m.lame[e + l]);
    const Lanes volume = _mm256_setr_pd(el[0]->volume, el[1]->volume, el[2]->volume, el[3]->volume);
    const Lanes mu = _mm256_setr_pd(p[0].mu, p[1].mu, p[2].mu, p[3].mu);
    const Lanes lambda = _mm256_setr_pd(p[0].lambda, p[1].lambda, p[2].lambda, p[3].lambda);
    Lanes g[4][3], ds[9], F[9], F_lin[9], dF[9];
    load_gradients(el, g);
    edge_lanes(el, x_end, ds);
    deformation_gradients(ds, g, F);
    edge_lanes(el, x_lin, ds);
    deformation_gradients(ds, g, F_lin);
    for (int q = 0; q < 9; ++q) dF[q] = F[q] - F_lin[q];

    // Psi = mu/2 (|F|^2 - 3) - mu (J - 1) + lambda/2 (J - 1)^2 (neo_hookean_energy_density).
    Lanes c0[3];
    cross(F + 3, F + 6, c0);
    const Lanes j = dot(F, c0) - all(1.0);
    const Lanes F2 = dot(F, F) + dot(F + 3, F + 3) + dot(F + 6, F + 6);
    u_end = u_end + volume * (all(0.5) * mu * (F2 - all(3.0)) - mu * j + all(0.5) * lambda * j * j);

    // The model: Psi V + V (P : dF + dF : H : dF / 2) at x_lin.
    const NeoHookeanFrame* frame[4] = {&lin.frame[e], &lin.frame[e + 1], &lin.frame[e + 2], &lin.frame[e + 3]};
    const Mat3* Pl[4] = {&lin.stress[e], &lin.stress[e + 1], &lin.stress[e + 2], &lin.stress[e + 3]};
    const Mat3 *Ul[4], *Vl[4], *Al[4];
    for (int l = 0; l < 4; ++l) Ul[l] = &frame[l]->U, Vl[l] = &frame[l]->V, Al[l] = &frame[l]->A;
    Lanes P[9], U[9], V[9], A[9], d1[3], d2[3];
    load_matrices(Pl, P);
    load_matrices(Ul, U);
    load_matrices(Vl, V);
    load_matrices(Al, A);
    for (int k = 0; k < 3; ++k) {
      d1[k] = _mm256_setr_pd(frame[0]->d1[k], frame[1]->d1[k], frame[2]->d1[k], frame[3]->d1[k]);
      d2[k] = _mm256_setr_pd(frame[0]->d2[k], frame[1]->d2[k], frame[2]->d2[k], frame[3]->d2[k]);
    }
    Lanes PdF = P[0] * dF[0];
    for (int q = 1; q < 9; ++q) PdF = PdF + P[q] * dF[q];
    const Lanes energy = _mm256_loadu_pd(&lin.energy[e]);
    u_lin_end = u_lin_end + energy + volume * (PdF + all(0.5) * quadratic(U, V, A, d1, d2, dF));
    if (!v) continue;
    Lanes Fv[9];
    edge_lanes(el, *v, ds);
    deformation_gradients(ds, g, Fv);
    vKv = vKv + volume * quadratic(U, V, A, d1, d2, Fv);
  }
  out.u_end += sum(u_end);
  out.u_lin_end += sum(u_lin_end);
  out.vKv += sum(vKv);
  return n;
}
#endif

}  // namespace

int32_t add_neo_hookean_model_energies4(const FemModel& m, const NeoHookeanLinearisation& lin, const Vec3List& x_lin,
                                        const Vec3List& x_end, const Vec3List* v, NeoHookeanModelEnergies& out) {
#ifdef MICA_LANES4
  if (lanes4::supported()) return model_energies_avx2(m, lin, x_lin, x_end, v, out);
#endif
  (void)m, (void)lin, (void)x_lin, (void)x_end, (void)v, (void)out;
  return 0;
}

}  // namespace mica
