// SPDX-License-Identifier: Apache-2.0
// The stiffness the warped stiffness R Ke R^T leaves out.
//
// The co-rotational energy of an element is, in the signed singular values s of F (the
// smallest one negative for an inverted element, as proper_rotation flips it),
//   Psi(s) = mu sum (s_i - 1)^2 + lambda/2 (sum s_i - 3)^2,
// and its Hessian in F has nine eigenmatrices (Smith, De Goes, Kim, "Analytic eigensystems for
// isotropic distortion energies", TOG 2019): three scalings U diag(e) V^T, three flips
// U (e_i e_j^T + e_j e_i^T) V^T / sqrt 2 with eigenvalue 2 mu, and three twists
// T_ij = U (e_i e_j^T - e_j e_i^T) V^T / sqrt 2 with eigenvalue
//   (dPsi/ds_i + dPsi/ds_j) / (s_i + s_j).
// R Ke R^T (R held fixed) is exactly this Hessian with the twist eigenvalues set to zero. Where
// an element is stretched the twists are stiff (a tensed membrane resists turning); where it is
// compressed they are negative. The projected Hessian keeps the positive ones: R Ke R^T plus
// the modes below, each contributing V value (T g_a)(T g_b)^T to the block (a, b).
#pragma once
#include "core/types.hpp"
#include "fem/material.hpp"
#include "fem/tet_element.hpp"

namespace mica {

struct TwistModes {
  int32_t count = 0;
  double weight[3];  // V * eigenvalue
  Vec3 q[3][4];      // T g_a for the element's four nodes
};

// The twist modes of the element at deformation gradient F: the positive ones (the projected
// Hessian), or all that are finite when `positive_only` is false (the exact Hessian, for tests).
TwistModes twist_modes(const TetElement& e, const Lame& m, const Mat3& F, bool positive_only = true);

}  // namespace mica
