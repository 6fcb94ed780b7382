// SPDX-License-Identifier: Apache-2.0
#include "collision/contact_curvature.hpp"

#include <algorithm>

namespace mica {

namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;

// The gap's gradient in the corner coordinates of the triangle: w_k n for corner k.
bool gap_gradient(const ToolCore& core, const Contact& c, const Tri& t, const Vec3 (&x)[3], Vec9& g) {
  FeatureHit hit;
  if (c.core_corner >= 0) {
    if (!corner_triangle(core.corners[size_t(c.core_corner)], core.radius, x[0], x[1], x[2], hit)) return false;
  } else {
    // The edge's corners in the triangle: the contact's two nodes.
    int ei = -1, ej = -1;
    for (int k = 0; k < 3; ++k) {
      if (t[k] == c.a.nodes[0]) ei = k;
      if (t[k] == c.a.nodes[1]) ej = k;
    }
    const auto& e = core.edges[size_t(c.core_edge)];
    if (ei < 0 || ej < 0 || !edge_edge(core.corners[size_t(e[0])], core.corners[size_t(e[1])], core.radius, x[ei],
                                       x[ej], hit))
      return false;
    const Vec3 w = hit.weights;
    hit.weights.setZero();
    hit.weights[ei] = w[0];
    hit.weights[ej] = w[1];
  }
  if (hit.normal.isZero()) return false;
  // The contact's side: a core point that crosses the triangle's plane must not flip the gradient.
  if (hit.normal.dot(c.normal) < 0) hit.normal = -hit.normal;
  for (int k = 0; k < 3; ++k) g.segment<3>(3 * k) = hit.weights[k] * hit.normal;
  return true;
}

}  // namespace

bool contact_curvature(const ToolCore& core, const Contact& c, const Tri& t, const Vec3List& x, Mat9& K) {
  if (!(core.radius > 0) || (c.core_corner < 0 && c.core_edge < 0)) return false;
  const Vec3 at[3] = {x[size_t(t[0])], x[size_t(t[1])], x[size_t(t[2])]};
  // A step small next to the triangle, large next to rounding.
  const double eps = 1e-5 * std::max({(at[1] - at[0]).norm(), (at[2] - at[1]).norm(), (at[0] - at[2]).norm()});
  if (!(eps > 0)) return false;
  Mat9 H;
  for (int j = 0; j < 9; ++j) {
    Vec3 plus[3] = {at[0], at[1], at[2]}, minus[3] = {at[0], at[1], at[2]};
    plus[j / 3][j % 3] += eps;
    minus[j / 3][j % 3] -= eps;
    Vec9 gp, gm;
    if (!gap_gradient(core, c, t, plus, gp) || !gap_gradient(core, c, t, minus, gm)) return false;
    H.col(j) = (gp - gm) / (2 * eps);
  }
  // Only the curvature that holds the contact back stiffens it; the rest (a point rolling round a
  // convex core) would make A indefinite and is left out.
  const Eigen::SelfAdjointEigenSolver<Mat9> eig(-0.5 * (H + H.transpose()));
  K = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
  return K.allFinite();
}

}  // namespace mica
