// SPDX-License-Identifier: Apache-2.0
// Writing a backend's name into DeviceInfo's fixed, NUL-terminated buffer.
#pragma once
#include <algorithm>
#include <string_view>

#include "devices/device.hpp"

namespace mica {

// A DeviceInfo with the Touch's default figures and `name`, cut to the buffer's 63 characters.
inline DeviceInfo named_device_info(std::string_view name) {
  DeviceInfo info;
  const std::size_t n = std::min(name.size(), info.name.size() - 1);
  std::copy_n(name.data(), n, info.name.data());
  info.name[n] = '\0';
  return info;
}

}  // namespace mica
