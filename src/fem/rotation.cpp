// SPDX-License-Identifier: Apache-2.0
#include "fem/rotation.hpp"

#include <Eigen/SVD>
#include <cmath>

namespace mica {

namespace {

// Irving/Teran: F = U diag(s) V^T; flip the smallest singular direction when det F < 0.
Mat3 rotation_by_svd(const Mat3& F) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  // Singular values come sorted descending: column 2 belongs to the smallest one.
  if (U.determinant() * V.determinant() < 0) U.col(2) = -U.col(2);
  return U * V.transpose();
}

}  // namespace

Mat3 proper_rotation(const Mat3& F) {
  // Higham's Newton iteration X <- (X + X^-T) / 2 converges quadratically to the polar factor
  // of a well-conditioned F with det F > 0 — about ten times cheaper than an SVD. Inverted,
  // nearly collapsed or badly stretched elements take the SVD path.
  const double scale = F.norm();
  const double det = F.determinant();
  if (!(det > 1e-3 * scale * scale * scale)) return rotation_by_svd(F);
  Mat3 X = F;
  for (int k = 0; k < 20; ++k) {
    const Mat3 next = 0.5 * (X + X.inverse().transpose());
    const double change = (next - X).lpNorm<Eigen::Infinity>();
    X = next;
    if (change < 1e-13) return X;
  }
  return rotation_by_svd(F);
}

}  // namespace mica
