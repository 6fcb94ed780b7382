// SPDX-License-Identifier: Apache-2.0
// The rotation-variant SVD of a deformation gradient (Irving, Teran, Fedkiw 2004), the frame of the
// neo-Hookean projected Hessian (neo_hookean.hpp).
#pragma once
#include "core/types.hpp"

namespace mica {

// F = U diag(s) V^T with det U det V = 1, so det F = s0 s1 s2 and U V^T is a rotation: an inverted
// F has s[2] < 0. From the closed-form eigensystem of F^T F (several times faster than Jacobi): V
// its eigenvectors, u_k = F v_k / s_k for the two largest, u_2 = u_0 x u_1 and s_2 = u_2 . F v_2
// (signed). Where F is far from well conditioned (s_1 <= 1e-3 s_0: nearly flat or a needle) F^T F
// has lost the small singular values' digits: Jacobi there.
void rotation_variant_svd(const Mat3& F, Mat3& U, Vec3& s, Mat3& V);

// The Jacobi branch alone (any F).
void rotation_variant_svd_jacobi(const Mat3& F, Mat3& U, Vec3& s, Mat3& V);

}  // namespace mica
