// SPDX-License-Identifier: Apache-2.0
// The fixed-rate loop: every deadline ticked or skipped, never burst, a measured rate, an overrun that skips deadlines instead of bursting, and start/stop
// bookkeeping. Only bounds that hold however late the scheduler runs the thread are asserted (a
// loaded CI machine may starve it for tens of milliseconds): how many ticks a machine manages is
// bench/bench_servo.c's business.
#include "haptics/servo_thread.hpp"
#include "test_util.hpp"

#include <atomic>
#include <cmath>
#include <chrono>
#include <thread>

using namespace mica;

namespace {

struct Counter {
  std::atomic<int64_t> ticks{0};
  int64_t slow_tick = -1;  // this tick sleeps 10 ms
};

void count_tick(void* context) {
  Counter& c = *static_cast<Counter*>(context);
  const int64_t n = c.ticks.fetch_add(1, std::memory_order_relaxed);
  if (n == c.slow_tick) std::this_thread::sleep_for(std::chrono::milliseconds(10));
}

}  // namespace

// Timing-independent: every 1 ms deadline over the run is either ticked or skipped (never
// burst). How many ticks a loaded machine
// manages is a benchmark's business (bench/bench_servo.c), not a unit test's.
static void test_accounts_for_every_deadline(void**) {
  Counter counter;
  ServoThread servo;
  assert_false(servo.running());
  // Before start(): the loop's grid begins inside it, and a test thread descheduled right after
  // it would otherwise start its clock late and count more deadlines than "elapsed" allows.
  const auto t0 = std::chrono::steady_clock::now();
  servo.start(count_tick, &counter, 1e-3);
  assert_true(servo.running());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  servo.stop();
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  assert_false(servo.running());

  const int64_t ticks = counter.ticks.load();
  printf("# %lld ticks in %.3f s, %lld deadlines skipped\n", (long long)ticks, elapsed, (long long)servo.skipped());
  assert_true(ticks > 0);
  assert_int_equal(servo.ticks(), ticks);
  const double deadlines = double(ticks + servo.skipped());
  assert_le(deadlines, 1e3 * elapsed + 2);  // never more ticks than the grid has deadlines
  // No more ticks after stop().
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  assert_int_equal(counter.ticks.load(), ticks);
}

static void test_overrun_skips_instead_of_bursting(void**) {
  Counter counter;
  counter.slow_tick = 20;
  ServoThread servo;
  const auto t0 = std::chrono::steady_clock::now();
  servo.start(count_tick, &counter, 1e-3);
  // Past the slow tick and a few more, however long the scheduler makes us wait.
  while (counter.ticks.load() < counter.slow_tick + 3 &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  servo.stop();
  const double elapsed_ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // The 10 ms tick missed about ten deadlines, which were dropped rather than run late: every
  // deadline of the grid was either ticked or skipped, never both.
  printf("# %lld ticks, %lld deadlines skipped in %.1f ms\n", (long long)servo.ticks(), (long long)servo.skipped(),
         elapsed_ms);
  assert_true(servo.skipped() >= 8);
  assert_le(double(servo.ticks() + servo.skipped()), elapsed_ms + 2);
}

static void test_start_stop_bookkeeping(void**) {
  Counter counter;
  ServoThread servo;
  servo.stop();  // not running: nothing to do
  servo.start(count_tick, &counter, 2e-3);
  bool thrown = false;
  try {
    servo.start(count_tick, &counter);
  } catch (const Error& e) {
    thrown = e.code() == Errc::WrongState;
  }
  assert_true(thrown);
  servo.stop();
  servo.stop();
  // Restartable.
  const int64_t before = counter.ticks.load();
  servo.start(count_tick, &counter, 1e-3);
  // Until it ticks, however long the scheduler makes it wait (a loaded machine may not run the
  // thread within a fixed 20 ms).
  const auto t0 = std::chrono::steady_clock::now();
  while (counter.ticks.load() == before && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  servo.stop();
  assert_true(counter.ticks.load() > before);

  for (double bad : {0.0, -1e-3, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    thrown = false;
    try {
      servo.start(count_tick, &counter, bad);
    } catch (const Error& e) {
      thrown = e.code() == Errc::InvalidArgument;
    }
    assert_true(thrown);
    assert_false(servo.running());
  }
  thrown = false;
  try {
    servo.start(nullptr, &counter);
  } catch (const Error& e) {
    thrown = e.code() == Errc::InvalidArgument;
  }
  assert_true(thrown);
}

static void test_destructor_stops(void**) {
  Counter counter;
  {
    ServoThread servo;
    servo.start(count_tick, &counter);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const int64_t ticks = counter.ticks.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  assert_int_equal(counter.ticks.load(), ticks);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_accounts_for_every_deadline),
      cmocka_unit_test(test_overrun_skips_instead_of_bursting),
      cmocka_unit_test(test_start_stop_bookkeeping),
      cmocka_unit_test(test_destructor_stops),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
