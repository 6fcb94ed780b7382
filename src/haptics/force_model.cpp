// SPDX-License-Identifier: Apache-2.0
#include "haptics/force_model.hpp"

#include <algorithm>
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

ForceModel grasp_force_model(const ForceModel& last, const Vec3& reaction, const Vec3& handle,
                             double nominal_stiffness) {
  ForceModel model;
  model.f0 = reaction;
  model.x0 = handle;
  model.in_contact = true;
  model.holds = true;
  // A move below kSecantStep keeps the last estimate (the reaction's own step-to-step change would
  // swamp it).
  constexpr double kSecantStep = 1e-5;  // m
  double k = last.holds ? -last.H(0, 0) : 0;
  const Vec3 dx = model.x0 - last.x0;
  if (last.holds && dx.norm() >= kSecantStep)
    k = std::clamp(-dx.dot(model.f0 - last.f0) / dx.squaredNorm(), 0.0, nominal_stiffness);
  model.H = -k * Mat3::Identity();
  return model;
}

}  // namespace mica
