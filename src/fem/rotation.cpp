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
  // Higham's Newton iteration X <- (g X + X^-T / g) / 2 converges quadratically to the polar
  // factor of a well-conditioned F with det F > 0, several times cheaper than an SVD. The scaling
  // g = |det X|^(-1/3) (Higham 1986) takes a uniformly scaled rotation (a node's summed element
  // rotations, ~20 R) there in one step, where plain Newton halves the scale per step. Inverted,
  // nearly collapsed or badly stretched elements take the SVD path.
  const double n2 = F.squaredNorm();
  Mat3 X = F;
  for (int k = 0; k < 20; ++k) {
    // X^-T = cof(X) / det X, the cofactors by columns.
    Mat3 cof;
    cof.col(0) = X.col(1).cross(X.col(2));
    cof.col(1) = X.col(2).cross(X.col(0));
    cof.col(2) = X.col(0).cross(X.col(1));
    const double det = X.col(0).dot(cof.col(0));
    // det F > 1e-3 |F|^3, from the first step's determinant (no square root).
    if (k == 0 && !(det > 0 && det * det > 1e-6 * n2 * n2 * n2)) return rotation_by_svd(F);
    const double g = std::abs(det - 1) < 1e-2 ? 1.0 : std::cbrt(1 / det);  // near the end, plain Newton
    const Mat3 next = (0.5 * g) * X + (0.5 / (g * det)) * cof;
    const double change = (next - X).lpNorm<Eigen::Infinity>();
    X = next;
    // Quadratic convergence: the error left is about change^2 (< 1e-14 here).
    if (change < 1e-7) return X;
  }
  return rotation_by_svd(F);
}

}  // namespace mica
