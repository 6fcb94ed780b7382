// SPDX-License-Identifier: Apache-2.0
// Simulated devices for tests and demos without hardware, both on a deterministic clock:
// read number k (from 0) reports time k * kServoPeriod, however fast or slow it is called.
//  - SimulatedStylus replays a trajectory and ignores the force: an open-loop user.
//  - VirtualHand is a mass pulled toward the trajectory by a spring-damper and pushed back by
//    the rendered force: a closed-loop user that feels the tissue.
#pragma once
#include "devices/device.hpp"
#include "devices/trajectory.hpp"

namespace mica {

class SimulatedStylus final : public Device {
 public:
  static constexpr double kServoPeriod = 1e-3;  // s

  // `trajectory` may be empty: the stylus rests at the origin. For a CSV file pass
  // load_trajectory_csv(path), which throws on a malformed file before any servo cycle.
  explicit SimulatedStylus(Trajectory trajectory);

  DeviceInfo info() const override;  // "simulated stylus", the Touch's figures
  // The trajectory at time(), then advances time() by one servo period. The velocity is the
  // backward difference over one period, reaching back no further than t = 0 (0 at t = 0).
  // A trajectory that throws gives code -1.
  DeviceResult read(DeviceState& out) noexcept override;
  // Drops the force: the stylus does not feel it.
  DeviceResult write(const Vec3& force, const Vec3& torque) noexcept override;

  // The time the next read() reports; set_time(t) moves it (finite t >= 0, else
  // Errc::InvalidArgument). Not on the servo thread while it runs.
  double time() const { return t_; }
  void set_time(double t);

 private:
  Vec3 position_at(double t) const;

  Trajectory trajectory_;
  double t_ = 0;
};

struct HandParams {
  double mass = 0.1;       // kg
  double stiffness = 200;  // N/m, the pull toward the trajectory
  double damping = 5;      // N s/m, on the hand's own velocity (its arm's viscosity)
};

class VirtualHand final : public Device {
 public:
  static constexpr double kServoPeriod = 1e-3;  // s

  // Starts at rest on target(0) (the origin if `target` is empty). Errc::InvalidArgument
  // unless mass > 0, stiffness > 0 and damping >= 0 are finite and the 1 ms step is stable
  // for them: dt^2 k/m + 2 dt b/m < 4.
  explicit VirtualHand(Trajectory target, HandParams params = {});

  DeviceInfo info() const override;  // "virtual hand", the Touch's figures
  // The first read reports the initial state; every later one first integrates one servo
  // period of  m a = k (target(t) - x) - b v + F  (F: the last force written) with
  // semi-implicit Euler: v += dt a, then x += dt v. A target that throws gives code -1.
  DeviceResult read(DeviceState& out) noexcept override;
  // Stores the force the hand feels until the next write; the torque is dropped.
  DeviceResult write(const Vec3& force, const Vec3& torque) noexcept override;

  double time() const { return t_; }  // s, of the last state read
  const Vec3& position() const { return x_; }
  const Vec3& velocity() const { return v_; }
  const HandParams& params() const { return params_; }

 private:
  Vec3 target_at(double t) const;

  Trajectory target_;
  HandParams params_;
  Vec3 x_ = Vec3::Zero();
  Vec3 v_ = Vec3::Zero();
  Vec3 force_ = Vec3::Zero();
  double t_ = 0;
  bool started_ = false;  // whether a read has reported the initial state yet
};

}  // namespace mica
