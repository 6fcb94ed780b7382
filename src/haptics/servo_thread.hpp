// SPDX-License-Identifier: Apache-2.0
// A thread that calls a tick function at a fixed rate (1 kHz for the servo loop), on absolute
// deadlines of a steady clock: deadlines stay on the grid start + k * period, so the rate does
// not drift. A tick that overruns skips the deadlines it missed instead of running the late
// ticks back to back (a burst of forces is worse than a dropped sample).
//
// start() and stop() are not on the servo path (they create and join the thread). The loop
// itself only reads the steady clock and sleeps between ticks; the tick is the servo path and
// must not throw (an exception escaping it terminates the process).
#pragma once
#include <atomic>
#include <cstdint>
#include <thread>

namespace mica {

class ServoThread {
 public:
  using Tick = void (*)(void* context);

  ServoThread() = default;
  ~ServoThread() { stop(); }
  ServoThread(const ServoThread&) = delete;
  ServoThread& operator=(const ServoThread&) = delete;

  // Runs tick(context) every period_s seconds until stop(). Throws Error(WrongState) if already
  // running, Error(InvalidArgument) for a null tick or a period that is not finite and > 0.
  void start(Tick tick, void* context, double period_s = 1e-3);
  // Stops the loop and waits for the tick under way; does nothing if not running. Any thread but
  // the loop's own (a tick must not stop its own thread).
  void stop();

  bool running() const { return running_.load(std::memory_order_acquire); }
  // Ticks run and deadlines skipped since start().
  int64_t ticks() const { return ticks_.load(std::memory_order_relaxed); }
  int64_t skipped() const { return skipped_.load(std::memory_order_relaxed); }

 private:
  void loop(Tick tick, void* context, double period_s);

  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::atomic<int64_t> ticks_{0};
  std::atomic<int64_t> skipped_{0};
};

}  // namespace mica
