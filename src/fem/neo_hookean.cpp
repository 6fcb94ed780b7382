// SPDX-License-Identifier: Apache-2.0
#include "fem/neo_hookean.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "fem/fem_model.hpp"

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

// F = U diag(s) V^T with det U det V = 1, so det F = s0 s1 s2 and U V^T is a rotation: an inverted
// F has s[2] < 0 (Irving et al. 2004).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push  // GCC 12 sees JacobiSVD's singular values as maybe uninitialised when inlined
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
void jacobi_svd(const Mat3& F, Mat3& U, Vec3& s, Mat3& V) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  U = svd.matrixU();
  V = svd.matrixV();
  s = svd.singularValues();
  if (U.determinant() * V.determinant() < 0) {
    U.col(2) = -U.col(2);
    s(2) = -s(2);
  }
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

// The same from the closed-form eigensystem of F^T F (several times faster than Jacobi): V its
// eigenvectors, u_k = F v_k / s_k for the two largest, u_2 = u_0 x u_1 and s_2 = u_2 . F v_2 (signed).
// Where F is far from well conditioned (s_1 < 1e-3 s_0: nearly flat or a needle) F^T F has lost the
// small singular values' digits: Jacobi there.
void rotation_variant_svd(const Mat3& F, Mat3& U, Vec3& s, Mat3& V) {
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(F.transpose() * F);
  const Vec3& l = eig.eigenvalues();  // ascending
  const double s0 = std::sqrt(std::max(l[2], 0.0)), s1 = std::sqrt(std::max(l[1], 0.0));
  if (!(s1 > 1e-3 * s0)) return jacobi_svd(F, U, s, V);
  V.col(0) = eig.eigenvectors().col(2);
  V.col(1) = eig.eigenvectors().col(1);
  V.col(2) = V.col(0).cross(V.col(1));  // det V = +1
  U.col(0) = F * V.col(0) / s0;
  U.col(1) = F * V.col(1) / s1;
  U.col(1) -= U.col(1).dot(U.col(0)) * U.col(0);  // orthonormal to round-off
  U.col(1).normalize();
  U.col(0).normalize();
  U.col(2) = U.col(0).cross(U.col(1));
  s = Vec3(s0, s1, U.col(2).dot(F * V.col(2)));
}

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

Mat9 neo_hookean_projected_hessian(const NeoHookean& p, const Mat3& F, Mat3* rotation) {
  Mat3 U, V;
  Vec3 s;
  rotation_variant_svd(F, U, s, V);
  if (rotation) *rotation = U * V.transpose();
  Mat9 H = neo_hookean_hessian(p, F);
  const double J = s[0] * s[1] * s[2];
  const double w = p.lambda * (J - p.alpha);
  // Each negative eigenpair (value, U D V^T) is taken out: H -= value vec vec^T.
  auto remove = [&](double value, const Mat3& D) {
    if (value >= 0) return;
    const Vec9 q = vec(U * D * V.transpose());
    H.noalias() -= value * q * q.transpose();
  };
  // Twist and flip modes of the pair (i, j), k the third axis: mu + w s_k and mu - w s_k.
  const double r = std::sqrt(0.5);
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    Mat3 twist = Mat3::Zero(), flip = Mat3::Zero();
    twist(i, j) = r, twist(j, i) = -r;
    flip(i, j) = r, flip(j, i) = r;
    remove(p.mu + w * s[k], twist);
    remove(p.mu - w * s[k], flip);
  }
  // Scaling modes: the 3x3 d^2 Psi / ds^2 = mu I + lambda g g^T + w d^2J/ds^2 in the singular values.
  const Vec3 g(s[1] * s[2], s[0] * s[2], s[0] * s[1]);
  Mat3 A = p.lambda * g * g.transpose();
  A.diagonal().array() += p.mu;
  A(0, 1) += w * s[2], A(1, 0) += w * s[2];
  A(0, 2) += w * s[1], A(2, 0) += w * s[1];
  A(1, 2) += w * s[0], A(2, 1) += w * s[0];
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(A);
  for (int m = 0; m < 3; ++m) remove(eig.eigenvalues()[m], eig.eigenvectors().col(m).asDiagonal());
  return H;
}

void NeoHookeanLinearisation::resize(size_t elements) {
  energy.resize(elements);
  stress.resize(elements);
  hessian.resize(elements);
}

namespace {

// One element's share (assemble_neo_hookean).
void add_element(const FemModel& m, size_t e, const Vec3List& x, const NeoHookeanAssembly& what, Vec3List& f) {
  const TetElement& el = m.elements[e];
  const NeoHookean p = neo_hookean_parameters(m.lame[e]);
  const Mat3 F = deformation_gradient(el, x);
  const Mat3 P = neo_hookean_stress(p, F);
  const bool need_hessian = what.K || what.v_lin || what.R || what.lin;
  Mat9 H;
  if (need_hessian) H = neo_hookean_projected_hessian(p, F, what.R ? &(*what.R)[e] : nullptr);
  // f_a = -V P g_a, and with v_lin + h V (H : F(v_lin)) g_a (F(v) = sum_b v_b g_b^T).
  Mat3 stress = -el.volume * P;
  if (what.v_lin) {
    const Mat3 Fv = deformation_gradient(el, *what.v_lin);
    const Vec9 dP = H * vec(Fv);
    stress += (what.h * el.volume) * Eigen::Map<const Mat3>(dP.data());
  }
  for (int a = 0; a < 4; ++a) f[el.nodes[a]] += stress * el.grad[a];
  if (what.lin) {
    what.lin->energy[e] = el.volume * neo_hookean_energy_density(p, F);
    what.lin->stress[e] = P;
    what.lin->hessian[e] = H;
  }
  if (!what.K) return;
  // K_ab(i, k) = s V sum_jl H(i + 3j, k + 3l) g_a[j] g_b[l]; C_b(:, k) = sum_l H(:, k + 3l) g_b[l].
  const double s = what.k_scale * el.volume;
  Eigen::Matrix<double, 9, 3> C[4];
  for (int b = 0; b < 4; ++b)
    for (int k = 0; k < 3; ++k)
      C[b].col(k) = s * (H.col(k) * el.grad[b][0] + H.col(k + 3) * el.grad[b][1] + H.col(k + 6) * el.grad[b][2]);
  Mat3* blocks = what.K->data();
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      const Vec3& ga = el.grad[a];
      blocks[m.slots[e][4 * a + b]] +=
          ga[0] * C[b].block<3, 3>(0, 0) + ga[1] * C[b].block<3, 3>(3, 0) + ga[2] * C[b].block<3, 3>(6, 0);
    }
}

}  // namespace

void assemble_neo_hookean(const FemModel& m, const Vec3List& x_lin, const NeoHookeanAssembly& what, Vec3List& f_int,
                          const Colouring* element_colours, ThreadPool* pool) {
  const bool coloured = pool && element_colours && !element_colours->empty();
  for (Vec3& f : f_int) f.setZero();
  if (what.lin) what.lin->resize(m.elements.size());  // sized at the first step: no allocation after
  auto elements = [&](int32_t first, int32_t last) {
    for (int32_t e = first; e < last; ++e) add_element(m, size_t(e), x_lin, what, f_int);
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

NeoHookeanModelEnergies neo_hookean_model_energies(const FemModel& m, const NeoHookeanLinearisation& lin,
                                                   const Vec3List& x_lin, const Vec3List& x_end,
                                                   const Vec3List* v) {
  NeoHookeanModelEnergies out;
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const TetElement& el = m.elements[e];
    const Mat3 F = deformation_gradient(el, x_end);
    const Mat3 dF = F - deformation_gradient(el, x_lin);
    const Vec9 d = vec(dF);
    out.u_end += el.volume * neo_hookean_energy_density(neo_hookean_parameters(m.lame[e]), F);
    out.u_lin_end += lin.energy[e] + el.volume * (lin.stress[e].cwiseProduct(dF).sum() + 0.5 * d.dot(lin.hessian[e] * d));
    if (v) {
      const Vec9 dv = vec(deformation_gradient(el, *v));
      out.vKv += el.volume * dv.dot(lin.hessian[e] * dv);
    }
  }
  return out;
}

}  // namespace mica
