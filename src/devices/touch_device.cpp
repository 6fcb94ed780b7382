// SPDX-License-Identifier: Apache-2.0
#include "devices/touch_device.hpp"

#include <dlfcn.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/error.hpp"
#include "devices/device_name.hpp"
#include "devices/hd_api.h"

namespace mica {

namespace {

struct LibraryCloser {
  void operator()(void* library) const { dlclose(library); }
};

// Static text for an HD error code: the servo path reports it without formatting anything.
const char* hd_error_text(HDerror code) {
  switch (code) {
    case HD_SUCCESS: return "HD_SUCCESS";
    case HD_INVALID_ENUM: return "HD_INVALID_ENUM: HD does not know a parameter libmica used";
    case HD_INVALID_VALUE: return "HD_INVALID_VALUE: HD refused a value";
    case HD_INVALID_OPERATION: return "HD_INVALID_OPERATION: HD refused the call in this state";
    case HD_INVALID_INPUT_TYPE: return "HD_INVALID_INPUT_TYPE: HD refused a parameter's type";
    case HD_BAD_HANDLE: return "HD_BAD_HANDLE: the device handle is not valid";
    case HD_WARM_MOTORS: return "HD_WARM_MOTORS: the motors are warm; the device limits its force while they cool";
    case HD_EXCEEDED_MAX_FORCE: return "HD_EXCEEDED_MAX_FORCE: the force sent exceeded the device's maximum";
    case HD_EXCEEDED_MAX_FORCE_IMPULSE: return "HD_EXCEEDED_MAX_FORCE_IMPULSE: the force changed too fast";
    case HD_EXCEEDED_MAX_VELOCITY: return "HD_EXCEEDED_MAX_VELOCITY: the device moved too fast";
    case HD_FORCE_ERROR: return "HD_FORCE_ERROR: the device could not render the force";
    case HD_DEVICE_FAULT: return "HD_DEVICE_FAULT: the device reported a fault";
    case HD_DEVICE_ALREADY_INITIATED: return "HD_DEVICE_ALREADY_INITIATED: the device is already in use";
    case HD_COMM_ERROR: return "HD_COMM_ERROR: communication with the device failed";
    case HD_COMM_CONFIG_ERROR: return "HD_COMM_CONFIG_ERROR: the device's connection is misconfigured";
    case HD_TIMER_ERROR: return "HD_TIMER_ERROR: HD's servo timer failed";
    case HD_ILLEGAL_BEGIN: return "HD_ILLEGAL_BEGIN: an HD frame began inside another";
    case HD_ILLEGAL_END: return "HD_ILLEGAL_END: an HD frame ended that had not begun";
    case HD_FRAME_ERROR: return "HD_FRAME_ERROR: the HD frame failed";
    case HD_INVALID_PRIORITY: return "HD_INVALID_PRIORITY: HD refused the scheduler priority";
    case HD_SCHEDULER_FULL: return "HD_SCHEDULER_FULL: HD's scheduler has no room for another callback";
    case HD_INVALID_LICENSE: return "HD_INVALID_LICENSE: OpenHaptics has no valid license";
    default: return "an OpenHaptics HD error";
  }
}

// Errors after which the device still rendered (a reduced) force.
bool is_warning(HDerror code) { return code == HD_WARM_MOTORS || code == HD_EXCEEDED_MAX_FORCE; }

// HD keeps a stack of errors; reading back at most this many keeps a broken library from
// looping the servo thread forever.
constexpr int kMaxErrorsRead = 32;

}  // namespace

struct TouchDevice::Hd {
  std::unique_ptr<void, LibraryCloser> library;
  HHD handle = HD_INVALID_HANDLE;
  HDSchedulerHandle schedule = 0;

  decltype(&hdInitDevice) initDevice = nullptr;
  decltype(&hdMakeCurrentDevice) makeCurrentDevice = nullptr;
  decltype(&hdDisableDevice) disableDevice = nullptr;
  decltype(&hdBeginFrame) beginFrame = nullptr;
  decltype(&hdEndFrame) endFrame = nullptr;
  decltype(&hdGetError) getError = nullptr;
  decltype(&hdGetErrorString) getErrorString = nullptr;  // optional
  decltype(&hdEnable) enable = nullptr;
  decltype(&hdDisable) disable = nullptr;
  decltype(&hdGetIntegerv) getIntegerv = nullptr;
  decltype(&hdGetDoublev) getDoublev = nullptr;
  decltype(&hdGetString) getString = nullptr;  // optional
  decltype(&hdSetDoublev) setDoublev = nullptr;
  decltype(&hdCheckCalibration) checkCalibration = nullptr;
  decltype(&hdUpdateCalibration) updateCalibration = nullptr;
  decltype(&hdStartScheduler) startScheduler = nullptr;
  decltype(&hdStopScheduler) stopScheduler = nullptr;
  decltype(&hdScheduleAsynchronous) scheduleAsynchronous = nullptr;
  decltype(&hdUnschedule) unschedule = nullptr;

  explicit Hd(const std::string& path) {
    dlerror();
    library.reset(dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL));
    if (!library) {
      const char* why = dlerror();
      fail(Errc::Device, "cannot load the OpenHaptics HD library '" + path + "': " + (why ? why : "unknown error") +
                             "; set MICA_HD_LIBRARY to the path of OpenHaptics' libHD.so");
    }
    bind(path, "hdInitDevice", initDevice);
    bind(path, "hdMakeCurrentDevice", makeCurrentDevice);
    bind(path, "hdDisableDevice", disableDevice);
    bind(path, "hdBeginFrame", beginFrame);
    bind(path, "hdEndFrame", endFrame);
    bind(path, "hdGetError", getError);
    bind(path, "hdGetErrorString", getErrorString, false);
    bind(path, "hdEnable", enable);
    bind(path, "hdDisable", disable);
    bind(path, "hdGetIntegerv", getIntegerv);
    bind(path, "hdGetDoublev", getDoublev);
    bind(path, "hdGetString", getString, false);
    bind(path, "hdSetDoublev", setDoublev);
    bind(path, "hdCheckCalibration", checkCalibration);
    bind(path, "hdUpdateCalibration", updateCalibration);
    bind(path, "hdStartScheduler", startScheduler);
    bind(path, "hdStopScheduler", stopScheduler);
    bind(path, "hdScheduleAsynchronous", scheduleAsynchronous);
    bind(path, "hdUnschedule", unschedule);
  }

  template <class F>
  void bind(const std::string& path, const char* name, F& function, bool required = true) {
    function = reinterpret_cast<F>(dlsym(library.get(), name));
    if (!function && required)
      fail(Errc::Device, "the OpenHaptics HD library '" + path + "' has no function " + name +
                             "; set MICA_HD_LIBRARY to the path of OpenHaptics' libHD.so");
  }

  // Reads HD's error stack empty; returns the worst error on it (a failure before a
  // warning), HD_SUCCESS if none.
  HDErrorInfo take_errors() noexcept {
    HDErrorInfo worst{HD_SUCCESS, 0, handle};
    for (int i = 0; i < kMaxErrorsRead; ++i) {
      const HDErrorInfo e = getError();
      if (e.errorCode == HD_SUCCESS) break;
      const bool worse = worst.errorCode == HD_SUCCESS || (is_warning(worst.errorCode) && !is_warning(e.errorCode));
      if (worse) worst = e;
    }
    return worst;
  }

  // "HD error 0x0302 (HD_COMM_ERROR: ..., internal code 5): <HD's own description>".
  std::string describe(const HDErrorInfo& e) const {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04X", e.errorCode);
    std::string text = std::string("HD error ") + code + " (" + hd_error_text(e.errorCode) + ", internal code " +
                       std::to_string(e.internalErrorCode) + ")";
    const char* own = getErrorString ? getErrorString(e.errorCode) : nullptr;
    if (own && *own) text += std::string(": ") + own;
    return text;
  }
};

std::string TouchDevice::default_library() {
  const char* env = std::getenv("MICA_HD_LIBRARY");
  return env && *env ? env : "libHD.so";
}

TouchDevice::TouchDevice(const std::string& device_name, const std::string& library)
    : library_(library.empty() ? default_library() : library),
      hd_(std::make_unique<Hd>(library_)),
      info_(named_device_info("Touch")),
      start_(std::chrono::steady_clock::now()) {
  const std::string shown = device_name.empty() ? "the default device" : "'" + device_name + "'";
  hd_->take_errors();  // nothing of an earlier user of the library is ours
  hd_->handle = hd_->initDevice(device_name.empty() ? HD_DEFAULT_DEVICE : device_name.c_str());
  const HDErrorInfo e = hd_->take_errors();
  if (e.errorCode != HD_SUCCESS || hd_->handle == HD_INVALID_HANDLE) {
    hd_->handle = HD_INVALID_HANDLE;
    fail(Errc::Device, "cannot initialise the OpenHaptics device " + shown + " (library '" + library_ +
                           "'): " + (e.errorCode != HD_SUCCESS ? hd_->describe(e) : "hdInitDevice gave no handle"));
  }
  try {
    hd_->makeCurrentDevice(hd_->handle);
    calibrate();
    hd_->enable(HD_FORCE_OUTPUT);
    check_errors("enabling force output on the OpenHaptics device " + shown);
    read_info();
  } catch (...) {
    hd_->disableDevice(hd_->handle);
    throw;
  }
}

TouchDevice::~TouchDevice() {
  stop_scheduler();
  if (in_frame_) end_frame_with_zero_force();
  hd_->makeCurrentDevice(hd_->handle);
  hd_->disable(HD_FORCE_OUTPUT);
  hd_->disableDevice(hd_->handle);
  hd_->take_errors();  // nobody left to tell
}

void TouchDevice::check_errors(const std::string& what) {
  const HDErrorInfo e = hd_->take_errors();
  if (e.errorCode != HD_SUCCESS && !is_warning(e.errorCode)) fail(Errc::Device, what + ": " + hd_->describe(e));
}

void TouchDevice::calibrate() {
  hd_->beginFrame(hd_->handle);
  const HDenum status = hd_->checkCalibration();
  hd_->endFrame(hd_->handle);
  check_errors("checking the OpenHaptics device's calibration");
  if (status == HD_CALIBRATION_NEEDS_MANUAL_INPUT)
    fail(Errc::Device,
         "the OpenHaptics device needs a manual calibration: put the stylus in its inkwell (or calibrate it with "
         "the vendor's setup or diagnostic tool), then create the device again");
  if (status != HD_CALIBRATION_NEEDS_UPDATE) return;
  // Of the styles the device supports, the ones that need nobody: automatic, then the inkwell
  // (HD updates from it when the stylus sits there), then the encoder reset.
  HDint styles = 0;
  hd_->getIntegerv(HD_CALIBRATION_STYLE, &styles);
  const HDenum style = (styles & HD_CALIBRATION_AUTO)      ? HD_CALIBRATION_AUTO
                       : (styles & HD_CALIBRATION_INKWELL) ? HD_CALIBRATION_INKWELL
                                                           : HD_CALIBRATION_ENCODER_RESET;
  hd_->beginFrame(hd_->handle);
  hd_->updateCalibration(style);
  hd_->endFrame(hd_->handle);
  check_errors("updating the OpenHaptics device's calibration");
}

void TouchDevice::read_info() {
  if (hd_->getString) {
    const char* model = hd_->getString(HD_DEVICE_MODEL_TYPE);
    if (model && *model) info_ = named_device_info(model);
  }
  // NaN marks what HD left unwritten; HD's lengths are mm.
  const auto nominal = [&](HDenum parameter, double to_si, double& into) {
    double value = NAN;
    hd_->getDoublev(parameter, &value);
    if (std::isfinite(value) && value > 0) into = value * to_si;
  };
  nominal(HD_NOMINAL_MAX_FORCE, 1, info_.max_force);
  nominal(HD_NOMINAL_MAX_CONTINUOUS_FORCE, 1, info_.continuous_force);
  nominal(HD_NOMINAL_MAX_STIFFNESS, 1000, info_.nominal_stiffness);  // N/mm -> N/m
  nominal(HD_NOMINAL_MAX_DAMPING, 1000, info_.nominal_damping);      // N s/mm -> N s/m
  double box[6] = {NAN, NAN, NAN, NAN, NAN, NAN};
  hd_->getDoublev(HD_USABLE_WORKSPACE_DIMENSIONS, box);
  const double side = std::fmin(box[3] - box[0], std::fmin(box[4] - box[1], box[5] - box[2]));
  if (std::isfinite(side) && side > 0) info_.workspace_radius = 0.5 * side / 1000;
  hd_->take_errors();  // a model without one of these figures keeps the default
}

DeviceInfo TouchDevice::info() const { return info_; }

void TouchDevice::begin_frame() noexcept {
  hd_->makeCurrentDevice(hd_->handle);
  hd_->beginFrame(hd_->handle);
  in_frame_ = true;
}

void TouchDevice::end_frame_with_zero_force() noexcept {
  const HDdouble zero[3] = {0, 0, 0};
  hd_->setDoublev(HD_CURRENT_FORCE, zero);
  hd_->endFrame(hd_->handle);
  in_frame_ = false;
}

DeviceResult TouchDevice::frame_result() noexcept {
  const HDErrorInfo e = hd_->take_errors();
  if (e.errorCode == HD_SUCCESS) return {};
  const int32_t code = int32_t(e.errorCode);
  return {is_warning(e.errorCode) ? code : -code, hd_error_text(e.errorCode)};
}

DeviceResult TouchDevice::read(DeviceState& out) noexcept {
  // A read with no write after it: its frame ends here, rendering nothing.
  if (in_frame_) end_frame_with_zero_force();
  begin_frame();
  HDdouble position[3] = {0, 0, 0}, velocity[3] = {0, 0, 0};
  HDdouble transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  HDint buttons = 0;
  hd_->getDoublev(HD_CURRENT_POSITION, position);
  hd_->getDoublev(HD_CURRENT_VELOCITY, velocity);
  hd_->getDoublev(HD_CURRENT_TRANSFORM, transform);
  hd_->getIntegerv(HD_CURRENT_BUTTONS, &buttons);
  const DeviceResult result = frame_result();

  out = DeviceState{};
  for (int i = 0; i < 3; ++i) {
    out.position[i] = position[i] / 1000;  // mm -> m, rounded once
    out.velocity[i] = velocity[i] / 1000;  // mm/s -> m/s
  }
  // HD's transform is column-major, like OpenGL's; its upper 3x3 is the stylus's rotation.
  const Eigen::Map<const Eigen::Matrix4d> m(transform);
  const Mat3 rotation = m.topLeftCorner<3, 3>();
  out.orientation = Eigen::Quaterniond(rotation).normalized();
  out.buttons = buttons;
  out.timestamp = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // A transform whose upper 3x3 is no rotation (scaled, singular, a reflection) has no
  // orientation to give: the reading is refused rather than turned into some rotation.
  if (result.ok() && rotation.allFinite() &&
      !((rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-3 && rotation.determinant() > 0))
    return {-1, "the device's transform is not a rotation"};
  return result;
}

DeviceResult TouchDevice::write(const Vec3& force, const Vec3& /*torque*/) noexcept {
  if (!in_frame_) begin_frame();
  const HDdouble f[3] = {force.x(), force.y(), force.z()};
  hd_->setDoublev(HD_CURRENT_FORCE, f);
  hd_->endFrame(hd_->handle);
  in_frame_ = false;
  return frame_result();
}

bool TouchDevice::start_scheduler(Tick tick, void* context) {
  if (scheduled_) fail(Errc::WrongState, "the OpenHaptics device's servo loop is already running");
  tick_ = tick;
  tick_context_ = context;
  // HD calls this on its servo thread once per tick until unscheduled.
  const HDSchedulerCallback callback = [](void* self) -> HDCallbackCode {
    auto* device = static_cast<TouchDevice*>(self);
    device->tick_(device->tick_context_);
    return HD_CALLBACK_CONTINUE;
  };
  hd_->take_errors();
  hd_->schedule = hd_->scheduleAsynchronous(callback, this, HD_MAX_SCHEDULER_PRIORITY);
  check_errors("scheduling the servo callback with OpenHaptics");
  hd_->startScheduler();
  const HDErrorInfo e = hd_->take_errors();
  if (e.errorCode != HD_SUCCESS && !is_warning(e.errorCode)) {
    hd_->unschedule(hd_->schedule);
    hd_->take_errors();
    fail(Errc::Device, "starting OpenHaptics' scheduler: " + hd_->describe(e));
  }
  scheduled_ = true;
  return true;
}

void TouchDevice::stop_scheduler() {
  if (!scheduled_) return;
  hd_->unschedule(hd_->schedule);
  hd_->stopScheduler();
  hd_->take_errors();
  scheduled_ = false;
}

}  // namespace mica
