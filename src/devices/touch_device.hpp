// SPDX-License-Identifier: Apache-2.0
// The Geomagic Touch (and other OpenHaptics devices) through the HD API of OpenHaptics,
// loaded at run time: libmica neither includes nor links OpenHaptics, so it builds and runs
// without it, and only creating this device needs the library.
//
// One servo cycle is one HD frame: read() begins the frame and reads the device, write()
// sets the force and ends the frame, so mica_device_poll's read-then-write is exactly the
// begin / get state / set force / end sequence HD expects once per scheduler tick.
#pragma once
#include <chrono>
#include <memory>
#include <string>

#include "devices/device.hpp"

namespace mica {

class TouchDevice final : public Device {
 public:
  // The library tried when none is given: $MICA_HD_LIBRARY if set and not empty, else "libHD.so".
  static std::string default_library();

  // Loads `library` (empty: default_library()), initialises the HD device configured as
  // `device_name` (empty: HD's default device), checks its calibration (updating it when HD
  // can do so alone), enables force output and reads the device's nominal limits.
  // Errc::Device when the library cannot be loaded or lacks a function, the device does not
  // initialise (the message gives the HD error code), or it needs a manual calibration.
  explicit TouchDevice(const std::string& device_name = {}, const std::string& library = {});
  // Stops the scheduler, disables force output and the device, and unloads the library.
  ~TouchDevice() override;
  TouchDevice(const TouchDevice&) = delete;
  TouchDevice& operator=(const TouchDevice&) = delete;

  // The HD model name and its nominal figures, converted to SI (stiffness N/mm -> N/m,
  // workspace: half the smallest side of the usable box). Figures HD does not give keep
  // DeviceInfo's defaults.
  DeviceInfo info() const override;

  // Begins an HD frame (ending, with zero force, one a read left open) and reads position
  // (mm -> m), velocity (mm/s -> m/s), orientation (the rotation of HD's transform) and
  // buttons. The timestamp is a steady clock started at construction.
  // HD errors: HD_WARM_MOTORS and HD_EXCEEDED_MAX_FORCE give code +error (a warning), any
  // other -error; the message is static text naming the error.
  DeviceResult read(DeviceState& out) noexcept override;
  // Sets the force (N, unchanged: the caller limits it) and ends the frame, beginning one if
  // no read did. The Touch renders no torque: `torque` is dropped. Errors as read().
  DeviceResult write(const Vec3& force, const Vec3& torque) noexcept override;

  // Schedules `tick(context)` on HD's servo thread at the highest priority, every tick, and
  // starts HD's scheduler; returns true. Errc::Device if HD refuses, Errc::WrongState if
  // already started. HD has one scheduler per process, shared by all its devices.
  bool start_scheduler(Tick tick, void* context) override;
  // Unschedules the tick and stops HD's scheduler; when it returns the tick no longer runs.
  void stop_scheduler() override;

  const std::string& library() const { return library_; }

 private:
  struct Hd;  // the loaded library, its functions and HD's handles

  void check_errors(const std::string& what);
  DeviceResult frame_result() noexcept;
  void begin_frame() noexcept;
  void end_frame_with_zero_force() noexcept;
  void calibrate();
  void read_info();

  std::string library_;
  std::unique_ptr<Hd> hd_;
  DeviceInfo info_;
  bool in_frame_ = false;
  bool scheduled_ = false;
  Tick tick_ = nullptr;
  void* tick_context_ = nullptr;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace mica
