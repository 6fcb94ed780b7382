// SPDX-License-Identifier: Apache-2.0
#include "fem/tet_element.hpp"

#include <cmath>

#include <Eigen/LU>

#include "fem/lanes4.hpp"

namespace mica {

TetElement make_tet_element(const Vec3List& rest, const Tet& nodes) {
  TetElement e;
  e.nodes = nodes;
  Mat3 dm;
  for (int k = 0; k < 3; ++k) dm.col(k) = rest[nodes[k + 1]] - rest[nodes[0]];
  e.volume = dm.determinant() / 6.0;
  e.dm_inv = dm.inverse();
  e.grad[0].setZero();
  for (int k = 0; k < 3; ++k) {
    e.grad[k + 1] = e.dm_inv.row(k).transpose();
    e.grad[0] -= e.grad[k + 1];
  }
  return e;
}

Mat3 deformation_gradient(const TetElement& e, const Vec3List& x) {
  Mat3 ds;
  const Vec3& x0 = x[e.nodes[0]];
  for (int k = 0; k < 3; ++k) ds.col(k) = x[e.nodes[k + 1]] - x0;
  return ds * e.dm_inv;
}

Mat3 rotated_strain(const Mat3& R, const Mat3& F) {
  const Mat3 G = R.transpose() * F;
  return 0.5 * (G + G.transpose()) - Mat3::Identity();
}

Mat3 stress(const Lame& m, const Mat3& eps) {
  return 2 * m.mu * eps + m.lambda * eps.trace() * Mat3::Identity();
}

double von_mises(const Mat3& sigma) {
  const Mat3 s = sigma - (sigma.trace() / 3) * Mat3::Identity();
  return std::sqrt(1.5 * s.squaredNorm());
}

void add_elastic_forces(const TetElement& e, const Lame& m, const Mat3& R, const Mat3& F, Vec3List& f) {
  const Mat3 P = -e.volume * (R * stress(m, rotated_strain(R, F)));
  for (int a = 0; a < 4; ++a) f[e.nodes[a]] += P * e.grad[a];
}

void rotated_stiffness(const TetElement& e, const Lame& m, const Mat3& R, double scale, Mat3 K[16]) {
  Vec3 h[4];
  for (int a = 0; a < 4; ++a) h[a] = R * e.grad[a];
  const double vl = scale * e.volume * m.lambda, vm = scale * e.volume * m.mu;
  for (int a = 0; a < 4; ++a) {
    for (int b = a; b < 4; ++b) {
      Mat3 k = vl * h[a] * h[b].transpose() + vm * h[b] * h[a].transpose();
      k.diagonal().array() += vm * e.grad[a].dot(e.grad[b]);
      K[4 * a + b] = k;
      if (b != a) K[4 * b + a] = k.transpose();
    }
  }
}

void add_element(const TetElement& e, const Lame& m, const Mat3& R, const Vec3List& x, double scale,
                 const std::array<int32_t, 16>& slots, Mat3* K, Vec3List& f) {
  add_elastic_forces(e, m, R, deformation_gradient(e, x), f);
  if (!K) return;
  // h_a = R g_a, the rotated gradients: R Ke_ab R^T = V (lambda h_a h_b^T + mu h_b h_a^T + mu
  // (g_a . g_b) I).
  Vec3 h[4];
  for (int a = 0; a < 4; ++a) h[a] = R * e.grad[a];
  const double vl = scale * e.volume * m.lambda, vm = scale * e.volume * m.mu;
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b) {
      const Vec3 u = vl * h[a], w = vm * h[b];
      const double d = vm * e.grad[a].dot(e.grad[b]);
      Mat3& k = K[slots[4 * a + b]];  // u h_b^T + w h_a^T + d I
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) k(r, c) += u[r] * h[b][c] + w[r] * h[a][c] + (r == c ? d : 0.0);
      if (b == a) continue;
      Mat3& kt = K[slots[4 * b + a]];  // its transpose
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) kt(r, c) += u[c] * h[b][r] + w[c] * h[a][r] + (r == c ? d : 0.0);
    }
}

void add_elements(const TetElement* const e[2], const Lame* const m[2], const Mat3* const R[2], const Vec3List& x,
                  double scale, const std::array<int32_t, 16>* const slots[2], Mat3* K, Vec3List& f) {
  // add_element's steps, each quantity a pair: lane l belongs to element e[l].
  using Lanes = Eigen::Array2d;
  auto lanes = [](const auto& v0, const auto& v1, int i, int j) { return Lanes(v0(i, j), v1(i, j)); };
  Lanes Rl[3][3], dm[3][3], ds[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Rl[i][j] = lanes(*R[0], *R[1], i, j);
      dm[i][j] = lanes(e[0]->dm_inv, e[1]->dm_inv, i, j);
    }
  for (int k = 0; k < 3; ++k) {
    const Vec3 d0 = x[e[0]->nodes[k + 1]] - x[e[0]->nodes[0]], d1 = x[e[1]->nodes[k + 1]] - x[e[1]->nodes[0]];
    for (int i = 0; i < 3; ++i) ds[i][k] = Lanes(d0[i], d1[i]);
  }
  Lanes g[4][3];  // the rest gradients
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) g[a][i] = Lanes(e[0]->grad[a][i], e[1]->grad[a][i]);
  const Lanes volume(e[0]->volume, e[1]->volume), lambda(m[0]->lambda, m[1]->lambda), mu(m[0]->mu, m[1]->mu);

  // Forces: F = Ds Dm^-1, G = R^T F, eps = sym(G) - I, sigma = 2 mu eps + lambda tr(eps) I,
  // P = -V R sigma, f_a = P g_a.
  Lanes F[3][3], G[3][3], sigma[3][3], P[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F[i][j] = ds[i][0] * dm[0][j] + ds[i][1] * dm[1][j] + ds[i][2] * dm[2][j];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) G[i][j] = Rl[0][i] * F[0][j] + Rl[1][i] * F[1][j] + Rl[2][i] * F[2][j];
  const Lanes tr = (G[0][0] - 1) + (G[1][1] - 1) + (G[2][2] - 1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const Lanes eps = i == j ? Lanes(G[i][i] - 1) : Lanes(0.5 * (G[i][j] + G[j][i]));
      sigma[i][j] = 2 * mu * eps;
      if (i == j) sigma[i][j] += lambda * tr;
    }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      P[i][j] = -volume * (Rl[i][0] * sigma[0][j] + Rl[i][1] * sigma[1][j] + Rl[i][2] * sigma[2][j]);
  for (int a = 0; a < 4; ++a) {
    Lanes fa[3];
    for (int i = 0; i < 3; ++i) fa[i] = P[i][0] * g[a][0] + P[i][1] * g[a][1] + P[i][2] * g[a][2];
    for (int l = 0; l < 2; ++l) f[e[l]->nodes[a]] += Vec3(fa[0](l), fa[1](l), fa[2](l));
  }
  if (!K) return;

  // Stiffness: block (a, b) = u h_b^T + w h_a^T + d I with h = R g, u = V lambda h_a, w = V mu h_b,
  // d = V mu g_a . g_b; block (b, a) is its transpose, the same pairs read across.
  Lanes h[4][3];
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) h[a][i] = Rl[i][0] * g[a][0] + Rl[i][1] * g[a][1] + Rl[i][2] * g[a][2];
  const Lanes vl = scale * volume * lambda, vm = scale * volume * mu;
  // block += k (or k^T), k's entries (r, c) at 3c + r as Mat3 stores them: lane l into block[l].
  auto add = [](Mat3* const block[2], const Lanes (&k)[3][3], bool transposed) {
    auto at = [&](int i) -> const Lanes& { return transposed ? k[i / 3][i % 3] : k[i % 3][i / 3]; };
    for (int l = 0; l < 2; ++l) {
      double* out = block[l]->data();
      for (int i = 0; i < 8; i += 2) Eigen::Map<Lanes>(out + i) += Lanes(at(i)(l), at(i + 1)(l));
      out[8] += at(8)(l);
    }
  };
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b) {
      const Lanes d = vm * (g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2]);
      Lanes k[3][3];
      for (int r = 0; r < 3; ++r) {
        const Lanes u = vl * h[a][r], w = vm * h[b][r];
        for (int c = 0; c < 3; ++c) k[r][c] = u * h[b][c] + w * h[a][c];
        k[r][r] += d;
      }
      Mat3* const ab[2] = {&K[(*slots[0])[4 * a + b]], &K[(*slots[1])[4 * a + b]]};
      add(ab, k, false);
      if (b == a) continue;
      Mat3* const ba[2] = {&K[(*slots[0])[4 * b + a]], &K[(*slots[1])[4 * b + a]]};
      add(ba, k, true);
    }
}

namespace {

#ifdef MICA_LANES4
using namespace lanes4;

// add_elements' steps four lanes wide (lanes4.hpp).
MICA_AVX2 void add_elements4_avx2(const TetElement* const e[4], const Lame* const m[4], const Mat3* const R[4],
                                   const Vec3List& x, double scale, const std::array<int32_t, 16>* const slots[4],
                                   Mat3* K, Vec3List& f) {
  __m256d Rl[9], dm[9], g[4][3];
  load_matrices(R, Rl);
  load_gradients(e, g);
  for (int k = 0; k < 3; ++k)  // Dm^-1's rows are g_1, g_2, g_3 (make_tet_element): no loads of their own
    for (int j = 0; j < 3; ++j) dm[3 * j + k] = g[k + 1][j];
  __m256d ds[9];  // Ds = [x1 - x0, x2 - x0, x3 - x0]
  edge_lanes(e, x, ds);
  const __m256d volume = _mm256_setr_pd(e[0]->volume, e[1]->volume, e[2]->volume, e[3]->volume);
  const __m256d lambda = _mm256_setr_pd(m[0]->lambda, m[1]->lambda, m[2]->lambda, m[3]->lambda);
  const __m256d mu = _mm256_setr_pd(m[0]->mu, m[1]->mu, m[2]->mu, m[3]->mu);
  const __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5), two = _mm256_set1_pd(2.0);

  // Forces: F = Ds Dm^-1, G = R^T F, eps = sym(G) - I, sigma = 2 mu eps + lambda tr(eps) I,
  // P = -V R sigma, f_a = P g_a.
  __m256d F[9], G[9], sigma[9], P[9];
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) F[3 * j + i] = product(ds, dm, i, j);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) G[3 * j + i] = transposed_product(Rl, F, i, j);
  const __m256d tr = _mm256_add_pd(_mm256_add_pd(_mm256_sub_pd(G[0], one), _mm256_sub_pd(G[4], one)),
                                   _mm256_sub_pd(G[8], one));
  const __m256d minus_volume = _mm256_sub_pd(_mm256_setzero_pd(), volume);
  // -V sigma, so that P = R (-V sigma) takes no multiplication of its own.
  const __m256d two_mu = _mm256_mul_pd(_mm256_mul_pd(two, mu), minus_volume);
  const __m256d lambda_tr = _mm256_mul_pd(_mm256_mul_pd(lambda, tr), minus_volume);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const __m256d eps = i == j ? _mm256_sub_pd(G[4 * i], one)
                                 : _mm256_mul_pd(half, _mm256_add_pd(G[3 * j + i], G[3 * i + j]));
      sigma[3 * j + i] = i == j ? _mm256_fmadd_pd(two_mu, eps, lambda_tr) : _mm256_mul_pd(two_mu, eps);
    }
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) P[3 * j + i] = product(Rl, sigma, i, j);
  for (int a = 0; a < 4; ++a) {
    __m256d fa[3];
    apply(P, g[a], fa);
    Vec3* node[4] = {&f[e[0]->nodes[a]], &f[e[1]->nodes[a]], &f[e[2]->nodes[a]], &f[e[3]->nodes[a]]};
    add_vectors(node, fa);
  }
  if (!K) return;

  // Stiffness: block (a, b) = u h_b^T + w h_a^T + d I with h = R g, u = V lambda h_a, w = V mu h_b,
  // d = V mu g_a . g_b; block (b, a) is its transpose.
  const __m256d s = _mm256_set1_pd(scale);
  const __m256d vl = _mm256_mul_pd(_mm256_mul_pd(s, volume), lambda), vm = _mm256_mul_pd(_mm256_mul_pd(s, volume), mu);
  __m256d h[4][3];
  for (int a = 0; a < 4; ++a) apply(Rl, g[a], h[a]);
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b) {
      const __m256d gg = _mm256_fmadd_pd(g[a][2], g[b][2],
                                         _mm256_fmadd_pd(g[a][1], g[b][1], _mm256_mul_pd(g[a][0], g[b][0])));
      const __m256d d = _mm256_mul_pd(vm, gg);
      __m256d k[3][3];
      for (int r = 0; r < 3; ++r) {
        const __m256d u = _mm256_mul_pd(vl, h[a][r]), w = _mm256_mul_pd(vm, h[b][r]);
        for (int c = 0; c < 3; ++c) k[r][c] = _mm256_fmadd_pd(u, h[b][c], _mm256_mul_pd(w, h[a][c]));
        k[r][r] = _mm256_add_pd(k[r][r], d);
      }
      Mat3* ab[4];
      for (int l = 0; l < 4; ++l) ab[l] = &K[(*slots[l])[4 * a + b]];
      add_blocks(ab, {k[0][0], k[1][0], k[2][0], k[0][1], k[1][1], k[2][1], k[0][2], k[1][2], k[2][2]});
      if (b == a) continue;
      Mat3* ba[4];
      for (int l = 0; l < 4; ++l) ba[l] = &K[(*slots[l])[4 * b + a]];
      add_blocks(ba, {k[0][0], k[0][1], k[0][2], k[1][0], k[1][1], k[1][2], k[2][0], k[2][1], k[2][2]});
    }
}
#endif

}  // namespace

void add_elements4(const TetElement* const e[4], const Lame* const m[4], const Mat3* const R[4], const Vec3List& x,
                   double scale, const std::array<int32_t, 16>* const slots[4], Mat3* K, Vec3List& f) {
#ifdef MICA_LANES4
  if (lanes4::supported()) return add_elements4_avx2(e, m, R, x, scale, slots, K, f);
#endif
  add_elements(e, m, R, x, scale, slots, K, f);
  add_elements(e + 2, m + 2, R + 2, x, scale, slots + 2, K, f);
}

double elastic_energy(const TetElement& e, const Lame& m, const Mat3& R, const Mat3& F) {
  const Mat3 eps = rotated_strain(R, F);
  const double tr = eps.trace();
  return e.volume * (m.mu * eps.squaredNorm() + 0.5 * m.lambda * tr * tr);
}

std::array<double, 2> elastic_energies(const TetElement& e, const Lame& m, const Mat3& Ra, const Mat3& Rb,
                                       const Mat3& F) {
  using Lanes = Eigen::Array2d;  // lane 0: the frame Ra, lane 1: Rb
  Lanes G[3][3];                 // R^T F
  for (int i = 0; i < 3; ++i) {
    const Lanes r0(Ra(0, i), Rb(0, i)), r1(Ra(1, i), Rb(1, i)), r2(Ra(2, i), Rb(2, i));
    for (int j = 0; j < 3; ++j) G[i][j] = r0 * F(0, j) + r1 * F(1, j) + r2 * F(2, j);
  }
  // eps = sym(G) - I: its diagonal d and its entries above the diagonal s.
  const Lanes d0 = G[0][0] - 1, d1 = G[1][1] - 1, d2 = G[2][2] - 1;
  const Lanes s01 = 0.5 * (G[0][1] + G[1][0]), s02 = 0.5 * (G[0][2] + G[2][0]), s12 = 0.5 * (G[1][2] + G[2][1]);
  const Lanes tr = d0 + d1 + d2;
  const Lanes eps2 = d0 * d0 + d1 * d1 + d2 * d2 + 2 * (s01 * s01 + s02 * s02 + s12 * s12);
  const Lanes u = e.volume * (m.mu * eps2 + 0.5 * m.lambda * tr * tr);
  return {u(0), u(1)};
}

}  // namespace mica
