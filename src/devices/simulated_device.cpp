// SPDX-License-Identifier: Apache-2.0
#include "devices/simulated_device.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.hpp"
#include "devices/device_name.hpp"

namespace mica {

// ---- SimulatedStylus

SimulatedStylus::SimulatedStylus(Trajectory trajectory) : trajectory_(std::move(trajectory)) {}

DeviceInfo SimulatedStylus::info() const { return named_device_info("simulated stylus"); }

Vec3 SimulatedStylus::position_at(double t) const { return trajectory_ ? trajectory_(t) : Vec3::Zero(); }

void SimulatedStylus::set_time(double t) {
  if (!std::isfinite(t) || t < 0) fail(Errc::InvalidArgument, "a simulated stylus's time must be finite and >= 0");
  t_ = t;
}

DeviceResult SimulatedStylus::read(DeviceState& out) noexcept {
  try {
    const double before = std::max(0.0, t_ - kServoPeriod);
    const Vec3 p = position_at(t_);
    out = DeviceState{};
    out.position = p;
    if (t_ > before) out.velocity = (p - position_at(before)) / (t_ - before);
    out.timestamp = t_;
    t_ += kServoPeriod;
    return {};
  } catch (...) {
    return {-1, "the simulated stylus's trajectory threw"};
  }
}

DeviceResult SimulatedStylus::write(const Vec3& /*force*/, const Vec3& /*torque*/) noexcept { return {}; }

// ---- VirtualHand

VirtualHand::VirtualHand(Trajectory target, HandParams params) : target_(std::move(target)), params_(params) {
  const double m = params.mass, k = params.stiffness, b = params.damping, dt = kServoPeriod;
  if (!(std::isfinite(m) && m > 0) || !(std::isfinite(k) && k > 0) || !(std::isfinite(b) && b >= 0))
    fail(Errc::InvalidArgument, "a virtual hand needs a finite mass > 0, stiffness > 0 and damping >= 0");
  // Jury's criterion for semi-implicit Euler on m x'' = -k x - b x'.
  if (!(dt * dt * k / m + 2 * dt * b / m < 4))
    fail(Errc::InvalidArgument, "the virtual hand's stiffness and damping are too high for its mass at a 1 ms step");
  x_ = target_at(0);
}

DeviceInfo VirtualHand::info() const { return named_device_info("virtual hand"); }

Vec3 VirtualHand::target_at(double t) const { return target_ ? target_(t) : Vec3::Zero(); }

DeviceResult VirtualHand::read(DeviceState& out) noexcept {
  try {
    if (started_) {
      const Vec3 pull = params_.stiffness * (target_at(t_) - x_) - params_.damping * v_;
      v_ += kServoPeriod / params_.mass * (pull + force_);
      x_ += kServoPeriod * v_;
      t_ += kServoPeriod;
    }
    started_ = true;
    out = DeviceState{};
    out.position = x_;
    out.velocity = v_;
    out.timestamp = t_;
    return {};
  } catch (...) {
    return {-1, "the virtual hand's target trajectory threw"};
  }
}

DeviceResult VirtualHand::write(const Vec3& force, const Vec3& /*torque*/) noexcept {
  force_ = force;
  return {};
}

}  // namespace mica
