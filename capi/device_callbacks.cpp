// SPDX-License-Identifier: Apache-2.0
#include "device_callbacks.hpp"

#include <cstring>
#include <string>

#include "core/error.hpp"

namespace mica_capi {

namespace {
mica::DeviceResult result(mica_status s, const char* what) {
  if (s == MICA_OK) return {};
  return {s > 0 ? 1 : -1, what};
}
}  // namespace

CallbackDevice::CallbackDevice(const mica_device_callbacks& table) : table_(table) {
  if (!table_.read_state || !table_.write_force)
    throw mica::Error(mica::Errc::InvalidArgument, "the callback table needs read_state and write_force");
  if (table_.open) {
    const mica_status s = table_.open(table_.user);
    if (s < 0) throw mica::Error(mica::Errc::Device, "the device's open callback failed with status " + std::to_string(s));
  }
  if (table_.info) {
    mica_device_info in{};
    in.struct_size = sizeof in;
    if (table_.info(table_.user, &in) >= 0) {
      std::memcpy(info_.name.data(), in.name, sizeof in.name);
      info_.name.back() = '\0';
      if (in.max_force > 0) info_.max_force = in.max_force;
      if (in.continuous_force > 0) info_.continuous_force = in.continuous_force;
      if (in.nominal_stiffness > 0) info_.nominal_stiffness = in.nominal_stiffness;
      if (in.nominal_damping > 0) info_.nominal_damping = in.nominal_damping;
      if (in.workspace_radius > 0) info_.workspace_radius = in.workspace_radius;
    }
  }
}

CallbackDevice::~CallbackDevice() {
  if (table_.close) table_.close(table_.user);
}

mica::DeviceResult CallbackDevice::read(mica::DeviceState& out) noexcept {
  mica_device_state s{};
  s.struct_size = sizeof s;
  s.orientation[0] = 1;
  const mica_status status = table_.read_state(table_.user, &s);
  if (status < 0) return result(status, "the device's read_state callback failed");
  out.position = {s.position[0], s.position[1], s.position[2]};
  out.orientation = Eigen::Quaterniond(s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3]);
  out.velocity = {s.velocity[0], s.velocity[1], s.velocity[2]};
  out.buttons = s.buttons;
  out.timestamp = s.timestamp;
  return result(status, "the device's read_state callback reported a warning");
}

mica::DeviceResult CallbackDevice::write(const mica::Vec3& force, const mica::Vec3& torque) noexcept {
  const double f[3] = {force.x(), force.y(), force.z()}, t[3] = {torque.x(), torque.y(), torque.z()};
  return result(table_.write_force(table_.user, f, t), "the device's write_force callback failed");
}

}  // namespace mica_capi
