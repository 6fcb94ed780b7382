// SPDX-License-Identifier: Apache-2.0
// One device attached to the world: the servo cycle (read, map, evaluate, filter, limit,
// write) on the servo thread, and the exchange with the simulation thread — the device pose
// goes one way, the force model of each step the other — through lock-free buffers.
// poll() never allocates, locks, blocks or throws.
#pragma once
#include <atomic>
#include <memory>

#include "devices/device.hpp"
#include "haptics/force_model.hpp"
#include "haptics/force_safety.hpp"
#include "haptics/moving_average.hpp"
#include "haptics/servo_thread.hpp"
#include "haptics/triple_buffer.hpp"

namespace mica {

// A device's orientation may be off unit length by this much (rounding in the device or its
// driver): it is normalised. A reading further off is refused (poll fails, zero force).
constexpr double kUnitQuaternionTolerance = 1e-2;
// A device pose mapped into the scene further than this from the origin (m, any coordinate) is
// refused like a non-finite one: 1e300 m is a broken reading, not a place to put a tool.
constexpr double kMaxScenePosition = 1e6;

// A device's own figures are trusted up to these (beyond, device creation is refused): its
// max_force as the force clamp when the host sets none, its nominal stiffness as the cap on the
// force model's stiffness.
constexpr double kDeviceMaxForceLimit = 100;     // N
constexpr double kDeviceStiffnessLimit = 1e5;    // N/m

// The longest servo cycle the force's rate limit counts (s): after a longer one (a stall) the
// force grows as if 2 ms had passed.
constexpr double kMaxRateInterval = 2e-3;
// The longest moving-average window (servo samples) a device may ask for.
constexpr int32_t kMaxFilterWindow = 10000;

struct DeviceSettings {
  uint64_t tool = 0;  // the tool id the device drives, 0 for none
  uint64_t lpc = 0;   // or the grasp (a constraint with a handle) whose handle it moves, 0 for none
  double scale = 1;   // scene = rotation * (scale * device) + offset
  Vec3 offset = Vec3::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  ForceMode mode = ForceMode::LocalModel;
  int32_t filter_window = 20;
  bool filter_restart_on_contact = true;  // the paper's post-contact correction
  SafetySettings safety{0, 1000, 0.1, 0.05};  // max_force 0: the device's own
  double coupling_stiffness = 300;  // N/m
  double coupling_damping = 2;      // N s/m
};

// The device's pose mapped into the scene, as the servo thread last read it.
struct ScenePose {
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 velocity = Vec3::Zero();
  int64_t sequence = 0;  // 0: nothing read yet
};

struct ServoStats {
  std::atomic<int64_t> polls{0}, failures{0}, clamped{0};
  std::atomic<int32_t> last_code{0};
  std::atomic<double> rate_hz{0};
  std::atomic<double> last_force[3] = {0, 0, 0};
  std::atomic<double> last_raw_force[3] = {0, 0, 0};  // before the filter and the limits
};

class DeviceLink {
 public:
  DeviceLink(std::unique_ptr<Device> device, const DeviceSettings& settings);
  ~DeviceLink();

  // Servo thread.
  DeviceResult poll(DeviceState* out_state, Vec3* out_force) noexcept;

  // Simulation thread: the newest device pose (false before the first poll), and the force
  // model of the step just taken.
  bool latest_pose(ScenePose& out);
  void publish(const ForceModel& model);
  // Simulation thread: the model publish() last sent (step -1 before the first).
  const ForceModel& last_published() const { return last_published_; }

  // The world's thread: the servo loop on libmica's own 1 kHz thread or the backend's scheduler.
  void start();
  void stop();

  const DeviceSettings& settings() const { return settings_; }
  const DeviceInfo& info() const { return info_; }
  const ServoStats& stats() const { return stats_; }
  // The servo path's filter state (the moving average and the last force sent), for
  // World::save_state; only while no servo loop runs (servo_running()).
  struct FilterState {
    MovingAverage::State average;
    Vec3 previous_force = Vec3::Zero();
  };
  bool servo_running() const { return on_scheduler_ || thread_.running(); }
  FilterState filter_state() const { return {filter_.state(), safety_.previous()}; }
  // Throws Error(InvalidArgument), unchanged, when the state is of another filter window.
  void set_filter_state(const FilterState& s) {
    filter_.set_state(s.average);
    safety_.set_previous(s.previous_force);
  }

 private:
  static void tick(void* self);
  double now() const;  // s since the link was made, steady clock

  std::unique_ptr<Device> device_;
  DeviceSettings settings_;
  DeviceInfo info_;
  TripleBuffer<ForceModel> model_;
  TripleBuffer<ScenePose> pose_;
  ForceModel last_published_;  // simulation thread only
  MovingAverage filter_;
  ForceSafety safety_;
  ServoThread thread_;
  bool on_scheduler_ = false;
  // Servo-thread state.
  double last_timestamp_ = -HUGE_VAL;
  double last_poll_ = -1;
  int64_t sequence_ = 0;
  double rate_window_start_ = 0;
  int64_t rate_window_polls_ = 0;
  ServoStats stats_;
  const int64_t epoch_;
};

}  // namespace mica
