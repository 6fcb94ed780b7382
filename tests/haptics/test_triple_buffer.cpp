// SPDX-License-Identifier: Apache-2.0
// The lock-free hand-over from the simulation thread to the servo thread: the reader always
// gets the newest whole value, never a torn one, and never goes back in time. Also run under
// ThreadSanitizer (-DMICA_SANITIZE=thread).
#include "haptics/triple_buffer.hpp"
#include "test_util.hpp"

#include <atomic>
#include <chrono>
#include <thread>

using namespace mica;

namespace {

// Every field equals the sequence number: a torn read shows up as a mismatch.
struct Sample {
  int64_t seq = 0;
  int64_t words[13] = {};
  double values[8] = {};

  void fill(int64_t s) {
    seq = s;
    for (int64_t& w : words) w = s;
    for (double& v : values) v = double(s);
  }
  bool consistent() const {
    for (int64_t w : words)
      if (w != seq) return false;
    for (double v : values)
      if (v != double(seq)) return false;
    return true;
  }
};

}  // namespace

static void test_single_thread_semantics(void**) {
  Sample initial;
  initial.fill(-1);
  TripleBuffer<Sample> buffer(initial);
  assert_int_equal(buffer.read()->seq, -1);  // nothing published yet: the initial value
  assert_false(buffer.has_new());

  buffer.write_slot().fill(1);
  buffer.publish();
  assert_true(buffer.has_new());
  const Sample* first = buffer.read();
  assert_int_equal(first->seq, 1);
  assert_false(buffer.has_new());
  assert_ptr_equal(buffer.read(), first);  // nothing new: the same value, same slot

  // Several publishes between reads: the reader gets the newest.
  for (int64_t s = 2; s <= 5; ++s) {
    buffer.write_slot().fill(s);
    buffer.publish();
  }
  assert_int_equal(buffer.read()->seq, 5);
  assert_true(buffer.read()->consistent());
}

static void test_concurrent_reads_are_whole_and_monotonic(void**) {
  TripleBuffer<Sample> buffer;
  std::atomic<bool> done{false};
  std::atomic<int64_t> published{0};

  std::thread writer([&] {
    int64_t s = 0;
    while (!done.load(std::memory_order_relaxed)) {
      buffer.write_slot().fill(++s);
      buffer.publish();
      if (s % 64 == 0) std::this_thread::yield();  // let the reader in on a loaded machine
    }
    published.store(s);
  });

  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
  int64_t reads = 0, changes = 0, last = 0, torn = 0, backwards = 0;
  while (std::chrono::steady_clock::now() < end) {
    const Sample* s = buffer.read();
    ++reads;
    if (!s->consistent()) ++torn;
    if (s->seq < last) ++backwards;
    if (s->seq != last) ++changes;
    last = s->seq;
  }
  done.store(true);
  writer.join();

  printf("# %lld reads, %lld distinct values, %lld published\n", (long long)reads, (long long)changes,
         (long long)published.load());
  assert_int_equal(torn, 0);
  assert_int_equal(backwards, 0);
  assert_true(changes >= 2);                 // the reader did see the writer's progress
  assert_true(last <= published.load());
  // After the writer stops, the reader gets its final value.
  assert_int_equal(buffer.read()->seq, published.load());
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_single_thread_semantics),
      cmocka_unit_test(test_concurrent_reads_are_whole_and_monotonic),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
