// SPDX-License-Identifier: Apache-2.0
#include "solver/projected_system.hpp"

namespace mica {

void ProjectedSystem::apply(const Vec3List& y, Vec3List& out, Vec3List& tmp) const {
  if (!projection.active()) {
    block_multiply(pattern, A, y, out);
    return;
  }
  tmp = y;
  for (int32_t i : projection.nodes) tmp[i] = projection.S[i] * y[i];
  block_multiply(pattern, A, tmp, out);
  for (int32_t i : projection.nodes)
    out[i] = projection.S[i] * out[i] + (y[i] - projection.S[i] * y[i]);
}

void ProjectedSystem::right_hand_side(const Vec3List& b, Vec3List& rhs, Vec3List& tmp) const {
  if (!projection.active()) {
    rhs = b;
    return;
  }
  // z is zero where free, and on fixed nodes too: A z only when some node is moved.
  bool moved = false;
  for (int32_t i : projection.nodes) moved = moved || !projection.z[i].isZero(0);
  if (moved) {
    block_multiply(pattern, A, projection.z, tmp);
    for (size_t i = 0; i < b.size(); ++i) rhs[i] = b[i] - tmp[i];
  } else {
    rhs = b;
  }
  for (int32_t i : projection.nodes) rhs[i] = projection.S[i] * rhs[i];
}

Mat3 ProjectedSystem::block(int32_t i, int32_t k) const {
  if (!projection.active()) return A[k];
  const int32_t j = pattern.col[k];
  const Mat3& Si = projection.S[i];
  const Mat3& Sj = projection.S[j];
  Mat3 P = Si * A[k] * Sj;
  if (i == j) P += Mat3::Identity() - Si;
  return P;
}

Mat3 ProjectedSystem::diagonal_block(int32_t i) const { return block(i, pattern.diag[i]); }

}  // namespace mica
