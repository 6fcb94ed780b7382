// The sequence lock that carries the device state from the servo thread to any number of
// readers: every load is a whole value, and each reader sees the sequence only move forward.
// Also run under ThreadSanitizer (-DMICA_SANITIZE=thread).
#include "haptics/latest_value.hpp"
#include "test_util.hpp"

#include <atomic>
#include <chrono>
#include <thread>

using namespace mica;

namespace {

// A plain struct like mica_device_state, every field equal to the sequence number. 60 bytes:
// not a multiple of the 8-byte words.
struct Pose {
  int32_t seq = 0;
  int32_t buttons = 0;
  double position[3] = {};
  double orientation[3] = {};
  int32_t tail = 0;
};

Pose pose(int32_t s) {
  Pose p;
  p.seq = p.buttons = p.tail = s;
  for (double& x : p.position) x = s;
  for (double& x : p.orientation) x = -s;
  return p;
}

bool consistent(const Pose& p) {
  bool ok = p.buttons == p.seq && p.tail == p.seq;
  for (double x : p.position) ok = ok && x == p.seq;
  for (double x : p.orientation) ok = ok && x == -p.seq;
  return ok;
}

struct ReaderResult {
  int64_t reads = 0, torn = 0, backwards = 0, changes = 0;
};

}  // namespace

static void test_single_thread_semantics(void**) {
  LatestValue<Pose> value(pose(7));
  assert_int_equal(value.load().seq, 7);
  assert_int_equal(value.version(), 1);
  value.store(pose(8));
  value.store(pose(9));
  const Pose p = value.load();
  assert_int_equal(p.seq, 9);
  assert_true(consistent(p));
  assert_int_equal(value.version(), 3);
}

static void test_concurrent_loads_are_whole_and_monotonic(void**) {
  LatestValue<Pose> value;
  std::atomic<bool> done{false};

  std::thread writer([&] {
    int32_t s = 0;
    while (!done.load(std::memory_order_relaxed)) value.store(pose(++s));
  });
  auto read_for = [&](ReaderResult& r) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    int32_t last = 0;
    while (std::chrono::steady_clock::now() < end) {
      const Pose p = value.load();
      ++r.reads;
      if (!consistent(p)) ++r.torn;
      if (p.seq < last) ++r.backwards;
      if (p.seq != last) ++r.changes;
      last = p.seq;
      if (r.reads % 1024 == 0) std::this_thread::yield();  // three threads share two cores: let the writer run
    }
  };
  ReaderResult a, b;
  std::thread other([&] { read_for(b); });
  read_for(a);
  other.join();
  done.store(true);
  writer.join();

  printf("# readers: %lld and %lld loads, %lld and %lld distinct values\n", (long long)a.reads, (long long)b.reads,
         (long long)a.changes, (long long)b.changes);
  for (const ReaderResult* r : {&a, &b}) {
    assert_int_equal(r->torn, 0);
    assert_int_equal(r->backwards, 0);
    assert_true(r->changes >= 2);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_single_thread_semantics),
      cmocka_unit_test(test_concurrent_loads_are_whole_and_monotonic),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
