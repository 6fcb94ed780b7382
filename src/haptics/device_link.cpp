// SPDX-License-Identifier: Apache-2.0
#include "haptics/device_link.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.hpp"

namespace mica {

namespace {

int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

bool finite(const DeviceState& s) {
  return s.position.allFinite() && s.velocity.allFinite() && s.orientation.coeffs().allFinite() &&
         std::isfinite(s.timestamp);
}

constexpr DeviceResult kBadReading{-1, "the device returned a non-finite reading"};
constexpr DeviceResult kTimeWentBack{-1, "the device clock went back in time"};
constexpr DeviceResult kBadOrientation{-1, "the device returned an orientation that is not a unit quaternion"};
constexpr DeviceResult kBadMapping{-1, "the device pose mapped into the scene is not finite, or beyond 1e6 m"};

// A reading's orientation, normalised, if it is a unit quaternion to within kUnitTolerance
// (rounding in the device or its driver); anything further off is a broken reading.
bool unit_orientation(Eigen::Quaterniond& q) {
  const double n = std::sqrt(q.coeffs().squaredNorm());  // inf for huge components: refused
  if (!(std::fabs(n - 1) <= kUnitQuaternionTolerance)) return false;
  q.coeffs() /= n;
  return true;
}

// The device's own figures, checked: a backend (a host's callback table, a driver) that reports
// a non-finite or absurd one would otherwise set the force clamp (max_force 1e300 N: none) or the
// stiffness cap of the force model.
DeviceInfo checked(const DeviceInfo& info, const DeviceSettings& settings) {
  const auto check = [](double value, double most, const char* what, const char* unit, const char* advice) {
    if (std::isfinite(value) && value > 0 && value <= most) return;
    char text[256];
    if (std::isfinite(most))
      std::snprintf(text, sizeof text, "the device reports a %s of %g %s, outside (0, %g] %s%s", what, value, unit, most,
                    unit, advice);
    else
      std::snprintf(text, sizeof text, "the device reports a %s of %g %s: it must be finite and > 0%s", what, value,
                    unit, advice);
    fail(Errc::Device, text);
  };
  if (settings.safety.max_force == 0)
    check(info.max_force, kDeviceMaxForceLimit, "max_force", "N",
          ": set the force clamp yourself (mica_device_def.max_force)");
  else
    check(info.max_force, HUGE_VAL, "max_force", "N", "");
  check(info.continuous_force, HUGE_VAL, "continuous_force", "N", "");
  check(info.nominal_stiffness, kDeviceStiffnessLimit, "nominal_stiffness", "N/m", "");
  check(info.nominal_damping, HUGE_VAL, "nominal_damping", "N s/m", "");
  check(info.workspace_radius, HUGE_VAL, "workspace_radius", "m", "");
  return info;
}

}  // namespace

DeviceLink::DeviceLink(std::unique_ptr<Device> device, const DeviceSettings& settings)
    : device_(std::move(device)), settings_(settings), info_(checked(device_->info(), settings)),
      filter_(settings.filter_window),
      safety_(SafetySettings{settings.safety.max_force > 0 ? settings.safety.max_force : info_.max_force,
                             settings.safety.max_rate, settings.safety.stall_timeout, settings.safety.stall_ramp}),
      epoch_(steady_ns()) {
  settings_.safety.max_force = settings.safety.max_force > 0 ? settings.safety.max_force : info_.max_force;
  filter_.set_restart_on_contact_change(settings.filter_restart_on_contact);
  // Nothing published yet: a model at rest, published "now", renders zero.
  model_.write_slot() = ForceModel{};
  model_.publish();
}

DeviceLink::~DeviceLink() { stop(); }

double DeviceLink::now() const { return 1e-9 * double(steady_ns() - epoch_); }

DeviceResult DeviceLink::poll(DeviceState* out_state, Vec3* out_force) noexcept {
  const double t = now();
  // The force may grow by max_force_rate * dt per cycle; dt is capped at two servo periods so that
  // a cycle after a stall (a late read, a descheduled thread) does not jump to the clamp.
  const double dt = last_poll_ < 0 ? 1e-3 : std::clamp(t - last_poll_, 1e-6, kMaxRateInterval);
  last_poll_ = t;
  stats_.polls.fetch_add(1, std::memory_order_relaxed);

  DeviceState state;
  DeviceResult result = device_->read(state);
  if (result.ok() && !finite(state)) result = kBadReading;
  if (result.ok() && state.timestamp < last_timestamp_) result = kTimeWentBack;
  if (result.ok() && !unit_orientation(state.orientation)) result = kBadOrientation;
  // Device frame -> scene: x = R (s p) + o. A pose that is not finite there never reaches the tool.
  const double s = settings_.scale;
  const Eigen::Quaterniond& R = settings_.rotation;
  ScenePose mapped;
  if (result.ok()) {
    mapped.position = R * (s * state.position) + settings_.offset;
    mapped.orientation = (R * state.orientation).normalized();
    mapped.velocity = R * (s * state.velocity);
    if (!(mapped.position.allFinite() && mapped.velocity.allFinite() && mapped.orientation.coeffs().allFinite()) ||
        !(mapped.position.cwiseAbs().maxCoeff() <= kMaxScenePosition))
      result = kBadMapping;
  }
  Vec3 force = Vec3::Zero();
  if (result.ok()) {
    last_timestamp_ = state.timestamp;
    // The pose goes to the simulation thread.
    ScenePose& pose = pose_.write_slot();
    pose = mapped;
    pose.sequence = ++sequence_;
    pose_.publish();

    // The force model of the last step, evaluated where the device is now.
    const ForceModel& model = *model_.read();
    Vec3 scene_force = Vec3::Zero();
    switch (settings_.mode) {
      case ForceMode::Hold: scene_force = model.f0; break;
      case ForceMode::LocalModel: scene_force = model.evaluate(mapped.position, ForceMode::LocalModel); break;
      case ForceMode::Coupling:
        scene_force = model.f0 + coupling_force(mapped.position, mapped.velocity, model.x0, Vec3::Zero(),
                                                settings_.coupling_stiffness, settings_.coupling_damping);
        break;
    }
    // Scene -> device frame: virtual work gives F_device = s R^T F_scene.
    const Vec3 device_force = s * (R.inverse() * scene_force);
    for (int k = 0; k < 3; ++k) stats_.last_raw_force[k].store(device_force[k], std::memory_order_relaxed);
    SafetyFlags flags;
    force = safety_.apply(filter_.filter(device_force, model.in_contact), t, model.published_at, dt, flags);
    if (flags.clamped || flags.rate_limited) stats_.clamped.fetch_add(1, std::memory_order_relaxed);
    const DeviceResult written = device_->write(force, Vec3::Zero());
    if (!written.ok() || written.code > 0) result = written;
  }
  if (!result.ok()) {
    // Whatever failed, the hand gets no force from us this cycle; the limiter restarts from zero.
    force.setZero();
    filter_.reset();
    safety_.reset();
    device_->write(force, Vec3::Zero());
    stats_.failures.fetch_add(1, std::memory_order_relaxed);
  }
  for (int k = 0; k < 3; ++k) stats_.last_force[k].store(force[k], std::memory_order_relaxed);
  stats_.last_code.store(result.code, std::memory_order_relaxed);
  // The rate over the last second.
  ++rate_window_polls_;
  if (t - rate_window_start_ >= 1.0) {
    stats_.rate_hz.store(double(rate_window_polls_) / (t - rate_window_start_), std::memory_order_relaxed);
    rate_window_start_ = t;
    rate_window_polls_ = 0;
  }
  if (out_state) *out_state = state;
  if (out_force) *out_force = force;
  return result;
}

bool DeviceLink::latest_pose(ScenePose& out) {
  out = *pose_.read();
  return out.sequence > 0;
}

void DeviceLink::publish(const ForceModel& model) {
  ForceModel& slot = model_.write_slot();
  slot = model;
  slot.published_at = now();
  last_published_ = slot;
  model_.publish();
}

void DeviceLink::tick(void* self) { static_cast<DeviceLink*>(self)->poll(nullptr, nullptr); }

void DeviceLink::start() {
  if (on_scheduler_ || thread_.running()) return;
  on_scheduler_ = device_->start_scheduler(&DeviceLink::tick, this);
  if (!on_scheduler_) thread_.start(&DeviceLink::tick, this, 1e-3);
}

void DeviceLink::stop() {
  if (on_scheduler_) device_->stop_scheduler();
  on_scheduler_ = false;
  thread_.stop();
}

}  // namespace mica
