// SPDX-License-Identifier: Apache-2.0
#include "solver/projection.hpp"

#include <Eigen/Eigenvalues>

namespace mica {

void Projection::reset(int32_t node_count) {
  S.assign(size_t(node_count), Mat3::Identity());
  z.assign(size_t(node_count), Vec3::Zero());
  is_constrained.assign(size_t(node_count), 0);
  nodes.clear();
}

const Mat3& Projection::projector(int32_t i) const {
  static const Mat3 identity = Mat3::Identity();
  return active() && is_constrained[i] ? S[i] : identity;
}

void Projection::constrain(int32_t node, const Mat3& C, const Vec3& velocity) {
  const Mat3 I = Mat3::Identity();
  const Mat3 C_old = I - S[node];
  // The union of two subspaces is the range of the sum of their projectors.
  Eigen::SelfAdjointEigenSolver<Mat3> eig(C_old + C);
  Mat3 C_new = Mat3::Zero();
  for (int k = 0; k < 3; ++k)
    if (eig.eigenvalues()[k] > 1e-9) C_new += eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose();
  z[node] = C_new * (C * velocity + (I - C) * z[node]);
  S[node] = I - C_new;
  if (!is_constrained[node]) {
    is_constrained[node] = 1;
    nodes.push_back(node);
  }
}

}  // namespace mica
