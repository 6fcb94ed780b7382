#include "fem/rotation.hpp"

#include <Eigen/SVD>

namespace mica {

Mat3 proper_rotation(const Mat3& F) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  // Singular values come sorted descending: column 2 belongs to the smallest one.
  if (U.determinant() * V.determinant() < 0) U.col(2) = -U.col(2);
  return U * V.transpose();
}

}  // namespace mica
