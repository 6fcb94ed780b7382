// SPDX-License-Identifier: Apache-2.0
// The rotation of a deformation gradient for co-rotational elasticity.
#pragma once
#include "core/types.hpp"

namespace mica {

// Rotation part of F = R P by SVD, F = U diag(s) V^T, R = U V^T. When det F < 0 (an inverted
// element) the smallest singular value's sign is flipped (Irving, Teran, Fedkiw 2004), so R
// is always a proper rotation (det R = +1), also for collapsed elements.
Mat3 proper_rotation(const Mat3& F);
// proper_rotation of two matrices at once, in about the time of one (R0 = proper_rotation(F0),
// R1 = proper_rotation(F1), the same bits): loops over many elements or nodes should take them in
// pairs. R0 and R1 must not be F0 or F1 (they may be one another when F0 and F1 are too).
void proper_rotations(const Mat3& F0, const Mat3& F1, Mat3& R0, Mat3& R1);
// proper_rotation of four matrices at once (R[l] = proper_rotation(F[l]), the same bits), in AVX2
// where the CPU has it (else as two pairs). R may be F (in place), not otherwise overlap it.
void proper_rotations4(const Mat3 F[4], Mat3 R[4]);
// R[l] = proper_rotation(F[l]) for l < count (0 to 4), the same bits: four at once, else a pair
// and then a single, for the tail of a loop taking four at a time. R must not overlap F.
void proper_rotations(const Mat3* F, Mat3* R, int count);

}  // namespace mica
