// SPDX-License-Identifier: Apache-2.0
#include "fem/rotation_variant_svd.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace mica {

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push  // GCC 12 sees JacobiSVD's singular values as maybe uninitialised when inlined
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
void rotation_variant_svd_jacobi(const Mat3& F, Mat3& U, Vec3& s, Mat3& V) {
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

void rotation_variant_svd(const Mat3& F, Mat3& U, Vec3& s, Mat3& V) {
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(F.transpose() * F);
  const Vec3& l = eig.eigenvalues();  // ascending
  const double s0 = std::sqrt(std::max(l[2], 0.0)), s1 = std::sqrt(std::max(l[1], 0.0));
  if (!(s1 > 1e-3 * s0)) return rotation_variant_svd_jacobi(F, U, s, V);
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

}  // namespace mica
