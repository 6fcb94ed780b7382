// SPDX-License-Identifier: Apache-2.0
#include "core/thread_pool.hpp"

#if defined(__linux__)
#include <sched.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace mica {

namespace {

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#elif defined(__aarch64__)
  asm volatile("yield" ::: "memory");
#endif
}

// Spins while `waiting()` holds, yielding the CPU after a short while: on a busy machine the
// thread it waits for may need this core.
template <class P>
void spin_while(P waiting) {
  for (int k = 0; waiting(); ++k) {
    if (k < 256)
      cpu_relax();
    else
      std::this_thread::yield();
  }
}

}  // namespace

ThreadPool::ThreadPool(int32_t threads, const HostTasks& host) : size_(threads < 1 ? 1 : threads), host_(host) {
  if (host_.enqueue) return;  // the host's workers join each loop
  workers_.reserve(size_t(size_ - 1));
  for (int32_t t = 1; t < size_; ++t) workers_.emplace_back([this] { worker(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_.store(true, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();
  for (std::thread& w : workers_) w.join();
}

int32_t ThreadPool::resolve(int32_t requested) {
  if (requested > 0) return requested;
#if defined(__linux__)
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
#endif
  const unsigned n = std::thread::hardware_concurrency();
  return n > 0 ? int32_t(n) : 1;
}

bool ThreadPool::prepare(const int32_t* start, int32_t phases, int32_t grain) {
  if (grain < 1) grain = 1;
  offsets_.resize(size_t(phases) + 1);  // grows only
  offsets_[0] = 0;
  for (int32_t p = 0; p < phases; ++p) offsets_[p + 1] = offsets_[p] + (start[p + 1] - start[p] + grain - 1) / grain;
  chunks_ = offsets_[phases];
  claimed_.store(0, std::memory_order_relaxed);
  completed_.store(0, std::memory_order_relaxed);
  return chunks_ > 0;
}

void ThreadPool::wait_completed(int32_t chunks) const {
  if (completed_.load(std::memory_order_acquire) >= chunks) return;
  spin_while([&] { return completed_.load(std::memory_order_acquire) < chunks; });
}

void ThreadPool::run_erased(void (*fn)(void*), void* ctx) {
  if (size_ == 1 || chunks_ == 1) {
    [&]() noexcept { fn(ctx); }();
    return;
  }
  fn_ = fn;
  ctx_ = ctx;
  if (host_.enqueue) {
    run_on_host();
    return;
  }
  // Open the loop (it publishes fn_, ctx_ and the counters), then wake whoever sleeps.
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const uint64_t g = generation_.load(std::memory_order_relaxed) + 1;
    open_.store(g, std::memory_order_seq_cst);
    generation_.store(g, std::memory_order_release);
  }
  wake_.notify_all();  // no syscall when no worker sleeps
  [&]() noexcept { fn(ctx); }();
  wait_completed(chunks_);
  // Close it: a worker that comes later sees it closed and never touches fn_ or ctx_; wait for
  // those that came in time to leave.
  open_.store(0, std::memory_order_seq_cst);
  spin_while([&] { return active_.load(std::memory_order_seq_cst) != 0; });
}

// One task of up to size_ - 1 items, each standing for a worker: any range runs the loop body once, taking
// chunks in order with the caller until none is left (a range that starts late finds none). A
// range only waits for chunks that a running thread has claimed, so the host may run the ranges
// in any order, on any thread, the caller's included (inside enqueue or finish), without a
// deadlock; and which thread ran a chunk does not change its result.
void ThreadPool::run_on_host() {
  const int32_t workers = std::min(size_, chunks_) - 1;
  void* const handle = host_.enqueue(&ThreadPool::host_range, workers, 1, this, host_.user);
  [&]() noexcept { fn_(ctx_); }();
  if (handle) host_.finish(handle, host_.user);  // null: the host ran every range in enqueue
  wait_completed(chunks_);  // done already; orders the ranges' writes before the caller's reads
}

void ThreadPool::host_range(int32_t, int32_t, void* pool) {
  ThreadPool& p = *static_cast<ThreadPool*>(pool);
  [&]() noexcept { p.fn_(p.ctx_); }();
}

void ThreadPool::worker() {
  uint64_t seen = 0;
  for (;;) {
    // Spin for a new loop for up to kSpin, then sleep until one is opened.
    const auto deadline = std::chrono::steady_clock::now() + kSpin;
    uint64_t g = generation_.load(std::memory_order_acquire);
    for (int k = 1; g == seen; ++k) {
      cpu_relax();
      if (k % 256 == 0 && std::chrono::steady_clock::now() > deadline) {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
      }
      g = generation_.load(std::memory_order_acquire);
    }
    seen = g;
    if (stop_.load(std::memory_order_relaxed)) return;  // ordered by the bump we just saw
    active_.fetch_add(1, std::memory_order_seq_cst);
    if (open_.load(std::memory_order_seq_cst) == seen) [&]() noexcept { fn_(ctx_); }();
    active_.fetch_sub(1, std::memory_order_seq_cst);
  }
}

}  // namespace mica
