// A small persistent fork-join pool for the step's parallel loops, owned by one World.
//
// Why not OpenMP: libmica is embedded in hosts (game engines, simulators with their own job
// systems, a 1 kHz haptic servo thread). libgomp has one process-wide pool whose idle threads
// spin (GOMP_SPINCOUNT, up to ~ms) after every region and which OMP_NUM_THREADS, OMP_WAIT_POLICY
// and a host's own OpenMP use all reconfigure behind the library's back; two OpenMP runtimes in
// one process (a clang-built host with libomp) do not mix; and libgomp's barriers are invisible
// to ThreadSanitizer (false reports unless libgomp is rebuilt instrumented). This pool belongs to
// its World: threads - 1 workers made when the world is made and joined when it is destroyed,
// nothing global, no environment variables, and standard atomics that TSan understands. Idle
// workers spin for at most kSpin (so back-to-back regions of one step cost no wake-up), then
// sleep on a condition variable: between steps they take no CPU from the host.
//
// Regions are static: thread t of T always gets the same share of the same loop, so a result
// never depends on scheduling (and, for the loops the step runs, not on T either).
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace mica {

class ThreadPool {
 public:
  // threads >= 1 in all, the caller included (threads - 1 workers are started).
  explicit ThreadPool(int32_t threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int32_t size() const { return size_; }

  // Runs task(t) on every thread t = 0..size()-1 (t = 0 is the caller) and returns when all
  // have returned. The task must not throw (a throw terminates). Not reentrant: one caller at a
  // time, and no run() from inside a task.
  template <class F>
  void run(F& task) {
    run_erased([](void* ctx, int32_t t) { (*static_cast<F*>(ctx))(t); }, &task);
  }

  // Inside a task: returns once every thread of the pool has called it (and everything each
  // wrote before it is visible to all after it).
  void barrier();

  // Thread t's share [first, last) of the items [begin, end) split among `threads` in order.
  static std::pair<int64_t, int64_t> share(int64_t begin, int64_t end, int32_t t, int32_t threads) {
    const int64_t n = end - begin;
    return {begin + n * t / threads, begin + n * (t + 1) / threads};
  }

  // The thread count a setting asks for: 0 means every CPU this process may run on.
  static int32_t resolve(int32_t requested);

  // How long an idle worker spins before it sleeps.
  static constexpr std::chrono::microseconds kSpin{50};

 private:
  void run_erased(void (*fn)(void*, int32_t), void* ctx);
  void worker(int32_t index);

  int32_t size_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<uint64_t> generation_{0};  // bumped (under mutex_) for each region and to stop
  bool stop_ = false;                    // written under mutex_ before the last bump
  void (*fn_)(void*, int32_t) = nullptr; // the region's task, published by generation_
  void* ctx_ = nullptr;
  std::atomic<int32_t> pending_{0};      // workers still inside the region
  alignas(64) std::atomic<int32_t> arrived_{0};
  alignas(64) std::atomic<uint32_t> barrier_generation_{0};
};

// Runs f(first, last, t) over [0, n) split among the pool's threads; on the caller alone when
// there is no pool.
template <class F>
void parallel_for(ThreadPool* pool, int64_t n, F&& f) {
  if (!pool || pool->size() == 1) {
    f(int64_t(0), n, int32_t(0));
    return;
  }
  auto task = [&](int32_t t) {
    const auto range = ThreadPool::share(0, n, t, pool->size());
    f(range.first, range.second, t);
  };
  pool->run(task);
}

}  // namespace mica
