// SPDX-License-Identifier: Apache-2.0
// A haptic device backend as the core sees it. read() and write() run on the servo thread at
// 1 kHz: they must not allocate, lock or block, and they report failure by status, never by
// throwing. The C callback table of mica_device.h is adapted to this interface in capi/.
#pragma once
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string>

#include "core/types.hpp"

namespace mica {

struct DeviceInfo {
  std::array<char, 64> name{};   // NUL-terminated
  double max_force = 3.3;        // N, peak (Geomagic Touch figures by default)
  double continuous_force = 0.88;// N
  double nominal_stiffness = 400;// N/m
  double nominal_damping = 2;    // N s/m
  double workspace_radius = 0.075;  // m
};

struct DeviceState {
  Vec3 position = Vec3::Zero();  // m, device frame
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 velocity = Vec3::Zero();  // m/s
  int32_t buttons = 0;
  double timestamp = 0;          // s, the device's clock
};

// The result of a servo-path call: code 0 ok, > 0 a warning (the call did its work), < 0 failed.
// `message` is static text (no allocation on the servo path).
struct DeviceResult {
  int32_t code = 0;
  const char* message = "";
  bool ok() const { return code >= 0; }
};

class Device {
 public:
  virtual ~Device() = default;
  virtual DeviceInfo info() const = 0;
  // Servo thread.
  virtual DeviceResult read(DeviceState& out) noexcept = 0;
  virtual DeviceResult write(const Vec3& force, const Vec3& torque) noexcept = 0;
  // A backend with its own 1 kHz scheduler (the Touch) runs `tick` itself between
  // start_scheduler and stop_scheduler; others return false and libmica runs its own thread.
  using Tick = void (*)(void* context);
  virtual bool start_scheduler(Tick /*tick*/, void* /*context*/) { return false; }
  virtual void stop_scheduler() {}
};

}  // namespace mica
