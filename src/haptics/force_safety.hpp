// SPDX-License-Identifier: Apache-2.0
// The last stage before a force reaches the device: never send a non-finite value, fade the
// force out when the simulation stops publishing, clamp its magnitude and limit how fast it
// grows.
//
// Servo path: apply() and reset() never allocate, lock, block or make a system call. The
// constructor and configure() validate settings (and may throw): not for the servo thread.
#pragma once
#include "core/types.hpp"

namespace mica {

struct SafetySettings {
  double max_force = 3.3;      // N, > 0: clamp on the magnitude
  double max_rate = 1000;      // N/s, > 0 (may be +inf): limit on how fast the force grows
  double stall_timeout = 0.1;  // s, >= 0: with no publish for this long the force starts to fade
  double stall_ramp = 0.05;    // s, >= 0: the fade to zero takes this long (0: cut at once)
};

// What apply() did to this force; every field is rewritten by each call.
struct SafetyFlags {
  bool non_finite = false;    // the input (or an intermediate value) was NaN or infinite: zero sent
  bool stalled = false;       // the last publish is older than stall_timeout: the force was scaled down
  bool clamped = false;       // the magnitude exceeded max_force
  bool rate_limited = false;  // the force grew faster than max_rate
};

class ForceSafety {
 public:
  // Throws Error(InvalidArgument) for settings out of their domain.
  explicit ForceSafety(const SafetySettings& settings = SafetySettings());
  void configure(const SafetySettings& settings);
  const SafetySettings& settings() const { return settings_; }

  // The force to send, from the requested one, in this order:
  //  1. non-finite input -> zero;
  //  2. stall: if now - last_publish > stall_timeout, scale by
  //     max(0, 1 - (now - last_publish - stall_timeout) / stall_ramp) (a NaN age counts as stalled);
  //  3. clamp the magnitude to max_force, keeping the direction;
  //  4. rate limit against the previously returned force p: the output is the point nearest the
  //     target among s p + d with s in [0, 1] and |d| <= max_rate * dt. Shrinking p toward zero
  //     is free, so a release (or a stall, or a fault) takes effect at once and only growth is
  //     slowed: |output| <= |p| + max_rate * dt. A reversal therefore drops to near zero at once
  //     and builds up again in the new direction. dt <= 0 (or NaN) allows no growth.
  // The output is always finite and at most max_force in magnitude.
  Vec3 apply(const Vec3& force, double now, double last_publish, double dt, SafetyFlags& flags) noexcept;

  // Forgets the previous force (as if zero had been sent): call it when the device was sent
  // something other than apply()'s result, e.g. zero after a device failure.
  void reset() noexcept { previous_.setZero(); }
  const Vec3& previous() const { return previous_; }
  void set_previous(const Vec3& force) { previous_ = force; }  // a saved state (World::restore_state)

 private:
  SafetySettings settings_;
  Vec3 previous_ = Vec3::Zero();
};

}  // namespace mica
