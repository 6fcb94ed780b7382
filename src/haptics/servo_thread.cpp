// SPDX-License-Identifier: Apache-2.0
#include "haptics/servo_thread.hpp"

#include <chrono>
#include <cmath>

#include "core/error.hpp"

namespace mica {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

void ServoThread::start(Tick tick, void* context, double period_s) {
  if (!tick) fail(Errc::InvalidArgument, "servo thread: the tick function is null");
  if (!(std::isfinite(period_s) && period_s > 0))
    fail(Errc::InvalidArgument, "servo thread: the period must be finite and > 0");
  if (running() || thread_.joinable()) fail(Errc::WrongState, "servo thread: already running");

  stop_requested_.store(false, std::memory_order_relaxed);
  ticks_.store(0, std::memory_order_relaxed);
  skipped_.store(0, std::memory_order_relaxed);
  thread_ = std::thread(&ServoThread::loop, this, tick, context, period_s);
  running_.store(true, std::memory_order_release);
}

void ServoThread::stop() {
  stop_requested_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

void ServoThread::loop(Tick tick, void* context, double period_s) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s));
  const auto step = period.count() > 0 ? period : Clock::duration(1);  // a period below the clock's resolution
  Clock::time_point deadline = Clock::now();

  while (!stop_requested_.load(std::memory_order_acquire)) {
    tick(context);
    ticks_.fetch_add(1, std::memory_order_relaxed);
    const Clock::time_point now = Clock::now();

    // The next deadline on the grid; if it has already passed, the first one still ahead.
    deadline += step;
    if (deadline <= now) {
      const int64_t missed = (now - deadline) / step + 1;
      deadline += missed * step;
      skipped_.fetch_add(missed, std::memory_order_relaxed);
    }
    std::this_thread::sleep_until(deadline);
  }
}

}  // namespace mica
