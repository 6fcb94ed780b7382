// SPDX-License-Identifier: Apache-2.0
#include "fem/neo_hookean.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "fem/fem_model.hpp"
#include "fem/neo_hookean_elements4.hpp"
#include "fem/neo_hookean_energies4.hpp"
#include "fem/rotation_variant_svd.hpp"

namespace mica {

namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;

Mat3 cross_matrix(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// dJ/dF: the columns f1 x f2, f2 x f0, f0 x f1.
Mat3 cofactor(const Mat3& F) {
  Mat3 c;
  c.col(0) = F.col(1).cross(F.col(2));
  c.col(1) = F.col(2).cross(F.col(0));
  c.col(2) = F.col(0).cross(F.col(1));
  return c;
}

Vec9 vec(const Mat3& m) { return Eigen::Map<const Vec9>(m.data()); }

}  // namespace

NeoHookean neo_hookean_parameters(const Lame& lame) {
  NeoHookean p;
  p.mu = lame.mu;
  p.lambda = lame.lambda + lame.mu;  // matches Hooke's law at small strain (header)
  p.alpha = 1 + p.mu / p.lambda;
  return p;
}

double neo_hookean_energy_density(const NeoHookean& p, const Mat3& F) {
  // lambda/2 (J - alpha)^2 - mu^2 / (2 lambda) = lambda/2 (J - 1)^2 - mu (J - 1): no constant to cancel.
  const double j = F.determinant() - 1;
  return 0.5 * p.mu * (F.squaredNorm() - 3) - p.mu * j + 0.5 * p.lambda * j * j;
}

Mat3 neo_hookean_stress(const NeoHookean& p, const Mat3& F) {
  return p.mu * F + (p.lambda * (F.determinant() - p.alpha)) * cofactor(F);
}

Mat3 neo_hookean_cauchy(const NeoHookean& p, const Mat3& F) {
  const double J = F.determinant();
  const Mat3 tau = neo_hookean_stress(p, F) * F.transpose();
  return J > 0 ? Mat3(tau / J) : tau;
}

Mat9 neo_hookean_hessian(const NeoHookean& p, const Mat3& F) {
  const Vec9 g = vec(cofactor(F));
  const double w = p.lambda * (F.determinant() - p.alpha);
  Mat9 H = p.lambda * g * g.transpose();
  H.diagonal().array() += p.mu;
  // w d^2J/dF^2: off-diagonal column blocks (i, j) = +-w [f_k]x, k the third column.
  const Mat3 c0 = w * cross_matrix(F.col(0)), c1 = w * cross_matrix(F.col(1)), c2 = w * cross_matrix(F.col(2));
  H.block<3, 3>(0, 3) -= c2;
  H.block<3, 3>(3, 0) += c2;
  H.block<3, 3>(0, 6) += c1;
  H.block<3, 3>(6, 0) -= c1;
  H.block<3, 3>(3, 6) -= c0;
  H.block<3, 3>(6, 3) += c0;
  return H;
}

NeoHookeanFrame neo_hookean_frame(const NeoHookean& p, const Mat3& F) {
  Mat3 U, V;
  Vec3 s;
  rotation_variant_svd(F, U, s, V);
  return neo_hookean_frame(p, U, s, V);
}

NeoHookeanFrame neo_hookean_frame(const NeoHookean& p, const Mat3& U, const Vec3& s, const Mat3& V) {
  NeoHookeanFrame f;
  f.U = U;
  f.V = V;
  const double w = p.lambda * (s[0] * s[1] * s[2] - p.alpha);
  // The pairs: twist mu + w s_k and flip mu - w s_k, each clamped at zero, as the 2x2 they make.
  for (int k = 0; k < 3; ++k) {
    const double twist = std::max(p.mu + w * s[k], 0.0), flip = std::max(p.mu - w * s[k], 0.0);
    f.d1[k] = 0.5 * (twist + flip);
    f.d2[k] = 0.5 * (flip - twist);
  }
  // The scaling block: d^2 Psi / ds^2 = mu I + lambda g g^T + w d^2J/ds^2 in the singular values.
  const Vec3 g(s[1] * s[2], s[0] * s[2], s[0] * s[1]);
  Mat3& A = f.A;
  A = p.lambda * g * g.transpose();
  A.diagonal().array() += p.mu;
  A(0, 1) += w * s[2], A(1, 0) += w * s[2];
  A(0, 2) += w * s[1], A(2, 0) += w * s[1];
  A(1, 2) += w * s[0], A(2, 1) += w * s[0];
  // Positive definite by its leading minors (the common case): nothing to clamp, no eigensolve.
  const double m2 = A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1);
  if (A(0, 0) > 0 && m2 > 0 && A.determinant() > 0) return f;
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(A);
  A = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  return f;
}

Mat3 NeoHookeanFrame::apply(const Mat3& dF) const {
  const Mat3 X = U.transpose() * dF * V;
  Mat3 Y;
  Y.diagonal() = A * X.diagonal();
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    Y(i, j) = d1[k] * X(i, j) + d2[k] * X(j, i);
    Y(j, i) = d2[k] * X(i, j) + d1[k] * X(j, i);
  }
  return U * Y * V.transpose();
}

double NeoHookeanFrame::quadratic(const Mat3& dF) const {
  const Mat3 X = U.transpose() * dF * V;
  const Vec3 x = X.diagonal();
  double q = x.dot(A * x);
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    q += d1[k] * (X(i, j) * X(i, j) + X(j, i) * X(j, i)) + 2 * d2[k] * X(i, j) * X(j, i);
  }
  return q;
}

Mat9 neo_hookean_projected_hessian(const NeoHookean& p, const Mat3& F, Mat3* rotation) {
  const NeoHookeanFrame f = neo_hookean_frame(p, F);
  if (rotation) *rotation = f.U * f.V.transpose();
  Mat9 H;
  for (int c = 0; c < 9; ++c) {
    Mat3 E = Mat3::Zero();
    E(c % 3, c / 3) = 1;
    H.col(c) = vec(f.apply(E));
  }
  return H;
}

void NeoHookeanLinearisation::resize(size_t elements) {
  energy.resize(elements);
  stress.resize(elements);
  frame.resize(elements);
}

void add_neo_hookean_element(const FemModel& m, int32_t e, const Vec3List& x, const NeoHookeanAssembly& what,
                             Vec3List& f) {
  const TetElement& el = m.elements[e];
  const NeoHookean p = neo_hookean_parameters(m.lame[e]);
  const Mat3 F = deformation_gradient(el, x);
  const Mat3 P = neo_hookean_stress(p, F);
  const bool need_hessian = what.K || what.v_lin || what.R || what.lin;
  NeoHookeanFrame H;
  if (need_hessian) H = neo_hookean_frame(p, F);
  if (what.R) (*what.R)[e] = H.U * H.V.transpose();
  // f_a = -V P g_a, and with v_lin + h V (H : F(v_lin)) g_a (F(v) = sum_b v_b g_b^T).
  Mat3 stress = -el.volume * P;
  if (what.v_lin) stress += (what.h * el.volume) * H.apply(deformation_gradient(el, *what.v_lin));
  for (int a = 0; a < 4; ++a) f[el.nodes[a]] += stress * el.grad[a];
  if (what.lin) {
    what.lin->energy[e] = el.volume * neo_hookean_energy_density(p, F);
    what.lin->stress[e] = P;
    what.lin->frame[e] = H;
  }
  if (!what.K) return;
  // In the SVD frame (g^ = V^T g): K_ab = s V U M_ab U^T with M_ab = diag(g^_a) A diag(g^_b) plus the
  // pairs' 2x2 blocks (neo_hookean.hpp, NeoHookeanFrame).
  const double scale = what.k_scale * el.volume;
  Vec3 gh[4];
  for (int a = 0; a < 4; ++a) gh[a] = H.V.transpose() * el.grad[a];
  Mat3* blocks = what.K->data();
  for (int a = 0; a < 4; ++a)
    for (int b = a; b < 4; ++b) {  // symmetric: K_ba = K_ab^T
      const Vec3 &u = gh[a], &v = gh[b];
      Mat3 M = u.asDiagonal() * H.A * v.asDiagonal();
      for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        M(i, i) += H.d1[k] * u[j] * v[j];
        M(j, j) += H.d1[k] * u[i] * v[i];
        M(i, j) += H.d2[k] * u[j] * v[i];
        M(j, i) += H.d2[k] * u[i] * v[j];
      }
      const Mat3 k = scale * (H.U * M * H.U.transpose());
      blocks[m.slots[e][4 * a + b]] += k;
      if (b != a) blocks[m.slots[e][4 * b + a]] += k.transpose();
    }
}

void assemble_neo_hookean(const FemModel& m, const Vec3List& x_lin, const NeoHookeanAssembly& what, Vec3List& f_int,
                          const Colouring* element_colours, ThreadPool* pool) {
  const bool coloured = pool && element_colours && !element_colours->empty();
  for (Vec3& f : f_int) f.setZero();
  if (what.lin) what.lin->resize(m.elements.size());  // sized at the first step: no allocation after
  auto elements = [&](int32_t first, int32_t last) {  // four at a time, then one by one
    int32_t e = first;
    for (; e + 3 < last; e += 4) {
      const int32_t four[4] = {e, e + 1, e + 2, e + 3};
      add_neo_hookean_elements4(m, four, x_lin, what, f_int);
    }
    for (; e < last; ++e) add_neo_hookean_element(m, e, x_lin, what, f_int);
  };
  if (!coloured) {
    elements(0, int32_t(m.elements.size()));
    return;
  }
  const Colouring& c = *element_colours;
  auto colour_blocks = [&](int32_t, int32_t first, int32_t last, int32_t) {
    for (int32_t n = first; n < last; ++n) elements(c.block_start[c.order[n]], c.block_start[c.order[n] + 1]);
  };
  pool->phased_for(c.start.data(), c.colours(), 1, colour_blocks);
}

double neo_hookean_energy(const FemModel& m, const Vec3List& x) {
  double u = 0;
  for (size_t e = 0; e < m.elements.size(); ++e)
    u += m.elements[e].volume *
         neo_hookean_energy_density(neo_hookean_parameters(m.lame[e]), deformation_gradient(m.elements[e], x));
  return u;
}

void add_neo_hookean_model_energies(const FemModel& m, int32_t e, const NeoHookeanLinearisation& lin,
                                    const Vec3List& x_lin, const Vec3List& x_end, const Vec3List* v,
                                    NeoHookeanModelEnergies& out) {
  const TetElement& el = m.elements[e];
  const Mat3 F = deformation_gradient(el, x_end);
  const Mat3 dF = F - deformation_gradient(el, x_lin);
  out.u_end += el.volume * neo_hookean_energy_density(neo_hookean_parameters(m.lame[e]), F);
  out.u_lin_end +=
      lin.energy[e] + el.volume * (lin.stress[e].cwiseProduct(dF).sum() + 0.5 * lin.frame[e].quadratic(dF));
  if (v) out.vKv += el.volume * lin.frame[e].quadratic(deformation_gradient(el, *v));
}

NeoHookeanModelEnergies neo_hookean_model_energies(const FemModel& m, const NeoHookeanLinearisation& lin,
                                                   const Vec3List& x_lin, const Vec3List& x_end,
                                                   const Vec3List* v) {
  NeoHookeanModelEnergies out;
  int32_t e = add_neo_hookean_model_energies4(m, lin, x_lin, x_end, v, out);  // four at a time, as far as it can
  for (; e < int32_t(m.elements.size()); ++e) add_neo_hookean_model_energies(m, e, lin, x_lin, x_end, v, out);
  return out;
}

}  // namespace mica
