// SPDX-License-Identifier: Apache-2.0
// One linear tetrahedron of isotropic linear elasticity, in a co-rotated frame.
//
// The 12x12 element stiffness Ke = V B^T D B is never stored: its 3x3 blocks have the closed
// form Ke_ab = V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I) in the rest gradients
// g_a of the shape functions, so a rotated block R Ke_ab R^T needs only the rotated gradients
// R g_a. That is the same matrix for 1/10 of the memory (16 doubles per tet, not 144).
#pragma once
#include "core/types.hpp"
#include "fem/material.hpp"

namespace mica {

struct TetElement {
  Tet nodes;
  double volume;            // rest volume, m^3
  Mat3 dm_inv;              // F = Ds dm_inv with Ds = [x1 - x0, x2 - x0, x3 - x0]
  std::array<Vec3, 4> grad; // rest shape-function gradients, 1/m (sum to zero)
};

// Precomputes an element from rest positions. The caller has checked its volume is positive.
TetElement make_tet_element(const Vec3List& rest, const Tet& nodes);

Mat3 deformation_gradient(const TetElement& e, const Vec3List& x);

// Small strain in the rotated frame: eps = sym(R^T F) - I (R = I: the linear model's strain).
Mat3 rotated_strain(const Mat3& R, const Mat3& F);
// Hooke's law: sigma = 2 mu eps + lambda tr(eps) I, Pa.
Mat3 stress(const Lame& m, const Mat3& eps);
// sqrt(3/2 s:s) with s the deviatoric part of sigma, Pa.
double von_mises(const Mat3& sigma);

// Elastic forces f_a = -R Ke (R^T x - X) on the element's four nodes, added to f.
// With eps = sym(R^T F) - I the small strain in the rotated frame, f_a = -V R sigma g_a.
void add_elastic_forces(const TetElement& e, const Lame& m, const Mat3& R, const Mat3& F, Vec3List& f);

// The 16 blocks R Ke_ab R^T, scaled by `scale`, row-major in (a, b).
void rotated_stiffness(const TetElement& e, const Lame& m, const Mat3& R, double scale, Mat3 K[16]);

// The element's share of the step: f += its elastic forces at x (add_elastic_forces) and, when K
// is not null, K[slots[4a + b]] += scale * R Ke_ab R^T, written straight into the blocks: the 10
// blocks of a <= b are computed once and the other 6 are their transposes (no 16-block scratch).
// The assembly's kernel; rotated_stiffness is its reference (tests/fem/test_tet_element.cpp).
void add_element(const TetElement& e, const Lame& m, const Mat3& R, const Vec3List& x, double scale,
                 const std::array<int32_t, 16>& slots, Mat3* K, Vec3List& f);

// add_element on two elements at once, side by side in SIMD lanes (about the time of one): the same
// contributions, to round-off (the sums into a node or block the two share may run in another
// order).
void add_elements(const TetElement* const e[2], const Lame* const m[2], const Mat3* const R[2], const Vec3List& x,
                  double scale, const std::array<int32_t, 16>* const slots[2], Mat3* K, Vec3List& f);

// add_element on four elements at once, in AVX2 + FMA lanes where the CPU has them (else as two
// add_elements): the same contributions, to round-off. The four may share nodes and blocks.
void add_elements4(const TetElement* const e[4], const Lame* const m[4], const Mat3* const R[4], const Vec3List& x,
                   double scale, const std::array<int32_t, 16>* const slots[4], Mat3* K, Vec3List& f);

// Strain energy 1/2 (R^T x - X)^T Ke (R^T x - X), J.
double elastic_energy(const TetElement& e, const Lame& m, const Mat3& R, const Mat3& F);
// The strain energy of one F in two frames, {elastic_energy(Ra, F), elastic_energy(Rb, F)} (to
// round-off), side by side in SIMD lanes.
std::array<double, 2> elastic_energies(const TetElement& e, const Lame& m, const Mat3& Ra, const Mat3& Rb,
                                       const Mat3& F);

}  // namespace mica
