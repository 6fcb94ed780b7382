// SPDX-License-Identifier: Apache-2.0
// Basic numeric types shared by every part of the core.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <vector>

namespace mica {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec3List = std::vector<Vec3>;
using Tet = std::array<int32_t, 4>;
using Tri = std::array<int32_t, 3>;

// A flat view of a node array as one vector of 3n doubles (Vec3 is packed: 3 doubles, no padding).
inline Eigen::Map<Eigen::VectorXd> flat(Vec3List& v) {
  return {v.empty() ? nullptr : v[0].data(), Eigen::Index(3 * v.size())};
}
inline Eigen::Map<const Eigen::VectorXd> flat(const Vec3List& v) {
  return {v.empty() ? nullptr : v[0].data(), Eigen::Index(3 * v.size())};
}

}  // namespace mica
