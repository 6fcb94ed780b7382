// SPDX-License-Identifier: Apache-2.0
// BackgroundThread: a job runs on the one named thread, not the caller's, while the caller goes
// on; wait() returns once it is over, and at once when nothing was started; what a job throws is
// kept until the next start(); destruction waits for the job in flight; a warm thread starts and
// waits for jobs without allocating.
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "core/background_thread.hpp"
#include "haptics/alloc_counter.hpp"
#include "test_util.hpp"

using namespace mica;
using namespace mica_test;

namespace {

struct Probe {
  std::atomic<bool> release{false};  // the job spins until the caller sets it
  std::atomic<int> runs{0};
  std::thread::id ran_on;
  char name[16] = {};
  bool throws = false;
};

void job(void* context) {
  Probe& p = *static_cast<Probe*>(context);
  while (!p.release.load()) std::this_thread::yield();
  p.ran_on = std::this_thread::get_id();
  pthread_getname_np(pthread_self(), p.name, sizeof p.name);
  p.runs.fetch_add(1);
  if (p.throws) throw std::runtime_error("the job failed");
}

}  // namespace

static void test_runs_on_its_named_thread_while_the_caller_goes_on(void**) {
  BackgroundThread worker("mica-test");
  worker.wait();  // nothing started: returns at once
  assert_true(worker.error() == nullptr);
  Probe p;
  worker.start(job, &p);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  assert_int_equal(p.runs.load(), 0);  // held by the caller: start() did not run it here
  p.release = true;
  worker.wait();
  assert_int_equal(p.runs.load(), 1);
  assert_true(p.ran_on != std::this_thread::get_id());
  assert_string_equal(p.name, "mica-test");
  const std::thread::id first = p.ran_on;
  worker.start(job, &p);  // the same thread again
  worker.wait();
  assert_int_equal(p.runs.load(), 2);
  assert_true(p.ran_on == first);
}

static void test_a_throw_is_kept_until_the_next_start(void**) {
  BackgroundThread worker("mica-test");
  Probe p;
  p.release = true;
  p.throws = true;
  worker.start(job, &p);
  worker.wait();
  assert_true(worker.error() != nullptr);
  worker.wait();
  assert_true(worker.error() != nullptr);  // still there
  try {
    std::rethrow_exception(worker.error());
  } catch (const std::runtime_error& e) {
    assert_string_equal(e.what(), "the job failed");
  }
  p.throws = false;
  worker.start(job, &p);
  worker.wait();
  assert_true(worker.error() == nullptr);
  assert_int_equal(p.runs.load(), 2);
}

static void test_destruction_waits_for_the_job_in_flight(void**) {
  Probe p;
  std::thread releaser;
  {
    BackgroundThread worker("mica-test");
    worker.start(job, &p);
    releaser = std::thread([&p] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      p.release = true;
    });
  }  // joins after the job
  assert_int_equal(p.runs.load(), 1);
  releaser.join();
}

static void test_a_warm_thread_does_not_allocate(void**) {
  BackgroundThread worker("mica-test");
  Probe p;
  p.release = true;
  worker.start(job, &p);  // makes the thread
  worker.wait();
  start_counting_allocations();
  for (int k = 0; k < 10; ++k) {
    worker.start(job, &p);
    worker.wait();
  }
  assert_int_equal(stop_counting_allocations(), 0);
  assert_int_equal(p.runs.load(), 11);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_runs_on_its_named_thread_while_the_caller_goes_on),
      cmocka_unit_test(test_a_throw_is_kept_until_the_next_start),
      cmocka_unit_test(test_destruction_waits_for_the_job_in_flight),
      cmocka_unit_test(test_a_warm_thread_does_not_allocate),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
