// SPDX-License-Identifier: Apache-2.0
// The rotation of a deformation gradient for co-rotational elasticity.
#pragma once
#include "core/types.hpp"

namespace mica {

// Rotation part of F = R P by SVD, F = U diag(s) V^T, R = U V^T. When det F < 0 (an inverted
// element) the smallest singular value's sign is flipped (Irving, Teran, Fedkiw 2004), so R
// is always a proper rotation (det R = +1), also for collapsed elements.
Mat3 proper_rotation(const Mat3& F);

}  // namespace mica
