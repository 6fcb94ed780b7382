// SPDX-License-Identifier: Apache-2.0
// The paper's force smoothing: a moving average over the last N servo samples, restarted at
// every change of contact (onset and release) so the window only ever holds samples of one
// contact state: n_k = min(N, k - k_change + 1).
//
// Servo path: filter() and reset() never allocate, lock, block or make a system call. The
// window's storage is allocated by the constructor and by set_window(), which are not for
// the servo thread.
#pragma once
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace mica {

class MovingAverage {
 public:
  // Throws Error(InvalidArgument) unless window >= 1.
  explicit MovingAverage(int32_t window = 20);

  // false: a plain moving average that keeps averaging across contact changes (no post-contact
  // correction: the onset is smeared over N samples). Not on the servo path.
  void set_restart_on_contact_change(bool restart) { restart_ = restart; }

  // Not on the servo path: reallocates the window and empties it.
  void set_window(int32_t window);
  int32_t window() const { return int32_t(samples_.size()); }

  // Adds one sample and returns the mean of the samples since the last contact change (at most
  // the last N). The first sample after a change is returned exactly. A non-finite sample is
  // returned as is (the safety layer zeroes it) and empties the window, so it cannot linger in
  // the running sum.
  Vec3 filter(const Vec3& raw, bool in_contact) noexcept;

  // Empties the window and forgets the contact state (the next sample starts afresh).
  void reset() noexcept;

  // How many samples the last output averaged.
  int32_t count() const { return count_; }
  // Everything a later filter() depends on (World::save_state; not on the servo path).
  struct State {
    std::vector<Vec3> samples;
    int32_t next = 0, count = 0, since_resum = 0;
    Vec3 sum = Vec3::Zero();
    bool in_contact = false;
  };
  State state() const { return {samples_, next_, count_, since_resum_, sum_, in_contact_}; }
  // Throws Error(InvalidArgument), unchanged, unless the state is of a window of this size.
  void set_state(const State& s);

 private:
  bool restart_ = true;
  void clear_window() noexcept;
  void resum() noexcept;

  std::vector<Vec3> samples_;  // ring buffer, capacity N
  int32_t next_ = 0;           // where the next sample goes
  int32_t count_ = 0;          // valid samples, <= N
  int32_t since_resum_ = 0;    // updates since the sum was last recomputed from the buffer
  Vec3 sum_ = Vec3::Zero();
  bool in_contact_ = false;
};

}  // namespace mica
