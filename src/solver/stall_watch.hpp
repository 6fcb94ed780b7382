// SPDX-License-Identifier: Apache-2.0
// Progress of an iterative loop judged by windows: the best value of a residual must halve from
// one window to the next. The frictional sweeps (frictional_contact.cpp) and the factored
// sweep's alternating rounds (factored_mica.cpp) stop, or change course, on a window that did not.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace mica {

class StallWatch {
 public:
  explicit StallWatch(int32_t window) : window_(window), window_end_(window) {}
  void add(double residual) { best_ = std::min(best_, residual); }
  // At step `at` (sweeps, rounds): false when a window ended here without halving the best of
  // the one before it (the first window only sets that best); true between window ends.
  bool progressing(int32_t at) {
    if (at < window_end_) return true;
    const bool halved = best_ <= 0.5 * best_at_window_ || !std::isfinite(best_at_window_);
    best_at_window_ = best_;
    window_end_ = at + window_;
    return halved;
  }

 private:
  int32_t window_, window_end_;
  double best_ = std::numeric_limits<double>::infinity(), best_at_window_ = best_;
};

}  // namespace mica
