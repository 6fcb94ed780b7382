// SPDX-License-Identifier: Apache-2.0
// A device that stays at the origin and renders nothing: a host without hardware still runs
// the whole servo path.
#pragma once
#include <cstdint>

#include "devices/device.hpp"

namespace mica {

class NullDevice final : public Device {
 public:
  // The clock: read number k (from 0) reports k servo periods, like a device polled at 1 kHz.
  static constexpr double kServoPeriod = 1e-3;  // s

  DeviceInfo info() const override;  // "null", the Touch's figures
  // The origin, identity orientation, at rest, no button.
  DeviceResult read(DeviceState& out) noexcept override;
  // Accepts and drops the force.
  DeviceResult write(const Vec3& force, const Vec3& torque) noexcept override;

 private:
  int64_t reads_ = 0;
};

}  // namespace mica
