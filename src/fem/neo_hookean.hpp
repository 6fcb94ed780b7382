// SPDX-License-Identifier: Apache-2.0
// Stable neo-Hookean elasticity (Smith, de Goes, Kim, "Stable Neo-Hookean Flesh Simulation", ACM
// TOG 2018) on linear tetrahedra: the energy, its first Piola-Kirchhoff stress and its Hessian
// projected to positive semidefinite through the energy's closed-form eigensystem, per element and
// assembled over a body.
//
// The energy density is the paper's without its optional log(I_C + 1) term,
//   Psi(F) = mu/2 (I_C - 3) + lambda/2 (J - alpha)^2 - mu^2 / (2 lambda),  alpha = 1 + mu / lambda,
// I_C = |F|_F^2, J = det F: zero and stress-free at F = I, finite and smooth through J = 0 (no
// log J), so an inverted element pushes back out. Its small-strain tangent is
// mu (dF + dF^T) + (lambda - mu) tr(dF) I, so the Lame parameters (lambda_L, mu_L) of E and nu are
// matched by mu = mu_L, lambda = lambda_L + mu_L (the paper's 4/3 and 5/6 remapping belongs to the
// form with the log term; tests/fem/test_neo_hookean.cpp checks this one against Hooke's law).
#pragma once
#include <array>
#include <vector>

#include "core/colouring.hpp"
#include "core/thread_pool.hpp"
#include "core/types.hpp"
#include "fem/block_matrix.hpp"
#include "fem/material.hpp"
#include "fem/tet_element.hpp"

namespace mica {

struct FemModel;
using Mat9 = Eigen::Matrix<double, 9, 9>;  // on vec(F), column-major: entry (i, j) of F at i + 3 j

struct NeoHookean {
  double mu, lambda, alpha;
};
NeoHookean neo_hookean_parameters(const Lame& lame);

// Psi(F), J/m^3.
double neo_hookean_energy_density(const NeoHookean& p, const Mat3& F);
// P = dPsi/dF = mu F + lambda (J - alpha) cof(F), Pa.
Mat3 neo_hookean_stress(const NeoHookean& p, const Mat3& F);
// Cauchy stress P F^T / J (Pa); for J <= 0 (a collapsed or inverted element) P F^T, the Kirchhoff
// stress, so that a readout stays finite.
Mat3 neo_hookean_cauchy(const NeoHookean& p, const Mat3& F);
// d^2 Psi / dF^2 with its negative eigenvalues clamped to zero, kept in the frame of F's
// rotation-variant SVD F = U diag(s) V^T (det U det V = 1; an inverted F has s_2 < 0), where it is
// block diagonal: on dF^ = U^T dF V, the diagonal entries meet the 3x3 scaling block A (mu I +
// lambda g g^T + lambda (J - alpha) d^2J/ds^2, clamped through its eigensystem when it is not
// definite), and each pair (i, j) = ((k + 1) % 3, (k + 2) % 3) the 2x2 [[d1, d2], [d2, d1]] on
// (dF^_ij, dF^_ji) whose eigenvalues are the twist mu + lambda (J - alpha) s_k and the flip
// mu - lambda (J - alpha) s_k, each clamped at zero.
struct NeoHookeanFrame {
  Mat3 U, V;
  Mat3 A;
  Vec3 d1, d2;
  Mat3 apply(const Mat3& dF) const;       // H : dF
  double quadratic(const Mat3& dF) const;  // dF : H : dF
};
NeoHookeanFrame neo_hookean_frame(const NeoHookean& p, const Mat3& F);
// The same from F's rotation-variant SVD F = U diag(s) V^T (fem/rotation_variant_svd.hpp).
NeoHookeanFrame neo_hookean_frame(const NeoHookean& p, const Mat3& U, const Vec3& s, const Mat3& V);
// The same as a 9x9 on vec(F) (tests); with `rotation`, also R = U V^T (the co-rotated frame).
Mat9 neo_hookean_projected_hessian(const NeoHookean& p, const Mat3& F, Mat3* rotation = nullptr);
// The unprojected d^2 Psi / dF^2 (tests).
Mat9 neo_hookean_hessian(const NeoHookean& p, const Mat3& F);

// What a step linearised at x_lin keeps per element: Psi V, P and the projected Hessian at x_lin,
// the quadratic model the step solved (neo_hookean_model_energies reads it back).
struct NeoHookeanLinearisation {
  std::vector<double> energy;          // J
  std::vector<Mat3> stress;            // P
  std::vector<NeoHookeanFrame> frame;  // projected d^2 Psi / dF^2
  void resize(size_t elements);
};

// f_int = -dU/dx at x_lin over the body's elements; with K, also K += k_scale * H (the projected
// Hessian, assembled); with v_lin, f_int += h H v_lin (the linearisation at x_lin = x + h v_lin of
// a step whose unknown is v: f(x_lin) - H (x + h v - x_lin)); with R, each element's rotation
// (for the factored sweep's warping); with lin, the per-element quadratic model. Serial, or colour
// by colour on the pool as assemble_elastic (fem/fem_model.hpp).
struct NeoHookeanAssembly {
  double k_scale = 0;
  BlockValues* K = nullptr;
  const Vec3List* v_lin = nullptr;
  double h = 0;
  std::vector<Mat3>* R = nullptr;
  NeoHookeanLinearisation* lin = nullptr;
};
void assemble_neo_hookean(const FemModel& m, const Vec3List& x_lin, const NeoHookeanAssembly& what, Vec3List& f_int,
                          const Colouring* element_colours = nullptr, ThreadPool* pool = nullptr);
// Element e's share of it: f_int (sized, not cleared) gains its forces, K its blocks, and R and lin
// (sized) its entries. The plain reference of the four-wide kernel (fem/neo_hookean_elements4.hpp),
// which assemble_neo_hookean runs on all but the last few elements of each range.
void add_neo_hookean_element(const FemModel& m, int32_t e, const Vec3List& x_lin, const NeoHookeanAssembly& what,
                             Vec3List& f_int);

// U(x), J.
double neo_hookean_energy(const FemModel& m, const Vec3List& x);

// At x_end: U(x_end) and the quadratic model of `lin` (made at x_lin),
//   U_L(x_end) = sum V [Psi + P : dF + dF : H : dF / 2],  dF = F(x_end) - F(x_lin);
// |U(x_end) - U_L(x_end)| is how far the step the model solved is from the model's own energy.
// With v, also v^T H v (the model's stiffness along v, for Rayleigh damping).
struct NeoHookeanModelEnergies {
  double u_end = 0, u_lin_end = 0;  // J
  double vKv = 0;                   // J/s^2
};
NeoHookeanModelEnergies neo_hookean_model_energies(const FemModel& m, const NeoHookeanLinearisation& lin,
                                                   const Vec3List& x_lin, const Vec3List& x_end,
                                                   const Vec3List* v = nullptr);
// Element e's terms of those sums, added to out: the plain reference of the four-wide
// add_neo_hookean_model_energies4 (fem/neo_hookean_energies4.hpp), which takes all but the last few.
void add_neo_hookean_model_energies(const FemModel& m, int32_t e, const NeoHookeanLinearisation& lin,
                                    const Vec3List& x_lin, const Vec3List& x_end, const Vec3List* v,
                                    NeoHookeanModelEnergies& out);

}  // namespace mica
