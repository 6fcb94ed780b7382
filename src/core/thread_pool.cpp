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

// Spins while `waiting()` holds, yielding the CPU after a short while: on an oversubscribed
// machine the thread it waits for may need this core.
template <class P>
void spin_while(P waiting) {
  for (int k = 0; waiting(); ++k) {
    if (k < 4096)
      cpu_relax();
    else
      std::this_thread::yield();
  }
}

}  // namespace

ThreadPool::ThreadPool(int32_t threads) : size_(threads < 1 ? 1 : threads) {
  workers_.reserve(size_t(size_ - 1));
  for (int32_t t = 1; t < size_; ++t) workers_.emplace_back([this, t] { worker(t); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
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

void ThreadPool::run_erased(void (*fn)(void*, int32_t), void* ctx) {
  if (size_ == 1) {
    fn(ctx, 0);
    return;
  }
  fn_ = fn;
  ctx_ = ctx;
  pending_.store(size_ - 1, std::memory_order_relaxed);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.fetch_add(1, std::memory_order_release);
  }
  wake_.notify_all();  // no syscall when every worker is still spinning
  [&]() noexcept { fn(ctx, 0); }();
  spin_while([&] { return pending_.load(std::memory_order_acquire) != 0; });
}

void ThreadPool::barrier() {
  if (size_ == 1) return;
  const uint32_t generation = barrier_generation_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) == size_ - 1) {
    arrived_.store(0, std::memory_order_relaxed);
    barrier_generation_.fetch_add(1, std::memory_order_acq_rel);
    return;
  }
  spin_while([&] { return barrier_generation_.load(std::memory_order_acquire) == generation; });
}

void ThreadPool::worker(int32_t index) {
  uint64_t seen = 0;
  for (;;) {
    // Spin for a region for up to kSpin, then sleep until one is published.
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
    if (stop_) return;  // published by the bump we just saw
    [&]() noexcept { fn_(ctx_, index); }();
    pending_.fetch_sub(1, std::memory_order_release);
  }
}

}  // namespace mica
