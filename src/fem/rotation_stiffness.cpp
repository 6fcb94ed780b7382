// SPDX-License-Identifier: Apache-2.0
#include "fem/rotation_stiffness.hpp"

#include <Eigen/SVD>
#include <cmath>

namespace mica {

TwistModes twist_modes(const TetElement& e, const Lame& m, const Mat3& F, bool positive_only) {
  Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  Vec3 s = svd.singularValues();
  if (U.determinant() * V.determinant() < 0) {  // inverted: the smallest singular value negative
    U.col(2) = -U.col(2);
    s(2) = -s(2);
  }
  const double trace = s.sum() - 3;
  Vec3 g;  // dPsi/ds
  for (int i = 0; i < 3; ++i) g(i) = 2 * m.mu * (s(i) - 1) + m.lambda * trace;
  TwistModes out;
  static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (const auto& p : pairs) {
    const int i = p[0], j = p[1];
    const double denom = s(i) + s(j);  // >= 0: |s_2| <= s_1, s_0
    // Near s_i + s_j = 0 the eigenvalue is unbounded: those elements keep R Ke R^T alone.
    if (!(denom > 1e-6 * s(0))) continue;
    const double value = (g(i) + g(j)) / denom;
    if (!(value > 0) && (positive_only || !std::isfinite(value))) continue;
    const int k = out.count++;
    out.weight[k] = e.volume * value;
    for (int a = 0; a < 4; ++a)
      out.q[k][a] = (U.col(i) * V.col(j).dot(e.grad[a]) - U.col(j) * V.col(i).dot(e.grad[a])) * M_SQRT1_2;
  }
  return out;
}

}  // namespace mica
