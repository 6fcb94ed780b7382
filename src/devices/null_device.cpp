// SPDX-License-Identifier: Apache-2.0
#include "devices/null_device.hpp"

#include "devices/device_name.hpp"

namespace mica {

DeviceInfo NullDevice::info() const { return named_device_info("null"); }

DeviceResult NullDevice::read(DeviceState& out) noexcept {
  out = DeviceState{};
  out.timestamp = double(reads_++) * kServoPeriod;
  return {};
}

DeviceResult NullDevice::write(const Vec3& /*force*/, const Vec3& /*torque*/) noexcept { return {}; }

}  // namespace mica
