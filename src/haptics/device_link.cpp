#include "haptics/device_link.hpp"

#include <chrono>
#include <cmath>

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

}  // namespace

DeviceLink::DeviceLink(std::unique_ptr<Device> device, const DeviceSettings& settings)
    : device_(std::move(device)), settings_(settings), info_(device_->info()), filter_(settings.filter_window),
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
  const double dt = last_poll_ < 0 ? 1e-3 : std::max(t - last_poll_, 1e-6);
  last_poll_ = t;
  stats_.polls.fetch_add(1, std::memory_order_relaxed);

  DeviceState state;
  DeviceResult result = device_->read(state);
  if (result.ok() && !finite(state)) result = kBadReading;
  if (result.ok() && state.timestamp < last_timestamp_) result = kTimeWentBack;
  Vec3 force = Vec3::Zero();
  if (result.ok()) {
    last_timestamp_ = state.timestamp;
    // Device frame -> scene: x = R (s p) + o; the pose goes to the simulation thread.
    const double s = settings_.scale;
    const Eigen::Quaterniond& R = settings_.rotation;
    ScenePose& pose = pose_.write_slot();
    pose.position = R * (s * state.position) + settings_.offset;
    pose.orientation = R * state.orientation;
    pose.velocity = R * (s * state.velocity);
    pose.sequence = ++sequence_;
    pose_.publish();

    // The force model of the last step, evaluated where the device is now.
    const ForceModel& model = *model_.read();
    Vec3 scene_force = Vec3::Zero();
    switch (settings_.mode) {
      case ForceMode::Hold: scene_force = model.f0; break;
      case ForceMode::LocalModel: scene_force = model.evaluate(pose.position, ForceMode::LocalModel); break;
      case ForceMode::Coupling:
        scene_force = model.f0 + coupling_force(pose.position, pose.velocity, model.x0, Vec3::Zero(),
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
