// SPDX-License-Identifier: Apache-2.0
#include "haptics/moving_average.hpp"

#include <algorithm>
#include <string>

#include "core/error.hpp"

namespace mica {

MovingAverage::MovingAverage(int32_t window) { set_window(window); }

void MovingAverage::set_window(int32_t window) {
  if (window < 1) fail(Errc::InvalidArgument, "moving average: the window must be >= 1 sample");
  samples_.assign(size_t(window), Vec3::Zero());
  reset();
}

Vec3 MovingAverage::filter(const Vec3& raw, bool in_contact) noexcept {
  if (!raw.allFinite()) {
    clear_window();
    in_contact_ = in_contact;
    return raw;
  }
  // Onset or release: the window restarts with this sample (the post-contact correction).
  if (in_contact != in_contact_ && restart_) clear_window();
  in_contact_ = in_contact;

  const int32_t n = window();
  if (count_ == n) {
    sum_ -= samples_[size_t(next_)];  // the oldest sample leaves
  } else {
    ++count_;
  }
  samples_[size_t(next_)] = raw;
  sum_ += raw;
  next_ = next_ + 1 == n ? 0 : next_ + 1;

  // The running sum collects one rounding per update; recomputing it every N updates bounds
  // the error by that of N updates, however long the run (O(1) amortised).
  if (++since_resum_ >= n) resum();
  return sum_ / double(count_);
}

void MovingAverage::set_state(const State& s) {
  const int32_t n = window();
  if (s.samples.size() != samples_.size() || s.next < 0 || s.next >= n || s.count < 0 || s.count > n ||
      s.since_resum < 0)
    fail(Errc::InvalidArgument, "moving average: the saved state is of a window of " +
                                    std::to_string(s.samples.size()) + " samples, this one has " + std::to_string(n));
  std::copy(s.samples.begin(), s.samples.end(), samples_.begin());
  next_ = s.next;
  count_ = s.count;
  since_resum_ = s.since_resum;
  sum_ = s.sum;
  in_contact_ = s.in_contact;
}

void MovingAverage::reset() noexcept {
  clear_window();
  in_contact_ = false;
}

void MovingAverage::clear_window() noexcept {
  next_ = 0;
  count_ = 0;
  since_resum_ = 0;
  sum_.setZero();
}

void MovingAverage::resum() noexcept {
  // The valid samples are the count_ slots before next_, oldest first.
  const int32_t n = window();
  int32_t i = next_ - count_;
  if (i < 0) i += n;
  sum_.setZero();
  for (int32_t k = 0; k < count_; ++k) {
    sum_ += samples_[size_t(i)];
    i = i + 1 == n ? 0 : i + 1;
  }
  since_resum_ = 0;
}

}  // namespace mica
