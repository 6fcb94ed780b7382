// SPDX-License-Identifier: Apache-2.0
#include "haptics/force_model.hpp"

#include <cmath>

#include "core/error.hpp"

namespace mica {

Vec3 ForceModel::evaluate(const Vec3& x, ForceMode mode) const noexcept {
  if (mode != ForceMode::LocalModel) return f0;
  // Tissue only pushes: once the linear model turns against f0 the contact has opened.
  const Vec3 f = f0 + H * (x - x0);
  return holds || f.dot(f0) > 0 ? f : Vec3::Zero();
}

Vec3 coupling_force(const Vec3& x_device, const Vec3& v_device, const Vec3& x_tool, const Vec3& v_tool,
                    double k, double b) noexcept {
  return -k * (x_device - x_tool) - b * (v_device - v_tool);
}

double passive_coupling_damping(double k, double period) {
  if (!(std::isfinite(k) && k >= 0)) fail(Errc::InvalidArgument, "coupling stiffness must be finite and >= 0");
  if (!(std::isfinite(period) && period > 0)) fail(Errc::InvalidArgument, "servo period must be finite and > 0");
  return k * period / 2;
}

}  // namespace mica
