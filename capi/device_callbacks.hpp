// SPDX-License-Identifier: Apache-2.0
// The host's C callback table (mica_device.h) as a core Device.
#pragma once
#include "devices/device.hpp"
#include "mica/mica_device.h"

namespace mica_capi {

class CallbackDevice : public mica::Device {
 public:
  explicit CallbackDevice(const mica_device_callbacks& table);  // opens; throws Error(Device) on failure
  ~CallbackDevice() override;
  mica::DeviceInfo info() const override { return info_; }
  mica::DeviceResult read(mica::DeviceState& out) noexcept override;
  mica::DeviceResult write(const mica::Vec3& force, const mica::Vec3& torque) noexcept override;

 private:
  mica_device_callbacks table_;
  mica::DeviceInfo info_;
};

}  // namespace mica_capi
