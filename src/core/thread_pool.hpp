// SPDX-License-Identifier: Apache-2.0
// A small persistent pool for the step's parallel loops, owned by one World.
//
// Why not OpenMP: libmica is embedded in hosts (game engines, simulators with their own job
// systems, a 1 kHz haptic servo thread). libgomp has one process-wide pool whose idle threads
// spin (GOMP_SPINCOUNT) after every region and which OMP_NUM_THREADS, OMP_WAIT_POLICY and a
// host's own OpenMP use all reconfigure behind the library's back; two OpenMP runtimes in one
// process (a clang-built host with libomp) do not mix; and libgomp's barriers are invisible to
// ThreadSanitizer. This pool belongs to its World: threads - 1 workers made with the world and
// joined when it is destroyed, nothing global, no environment variables, standard atomics that
// TSan understands. Idle workers spin for at most kSpin (back-to-back loops of one step cost no
// wake-up), then sleep on a condition variable: between steps they take no CPU from the host.
//
// No lockstep: a loop is cut into chunks of a fixed size that threads claim in order, the
// caller included, and a worker that is asleep, descheduled or late simply takes fewer chunks
// (none if it comes after the last). On a machine whose cores are busy with other work (the
// host's threads) the loop degrades towards the caller's serial speed instead of waiting at a
// barrier for a thread the OS has parked. A loop's result does not depend on which thread ran
// which chunk: chunks of one phase write disjoint data, and per-chunk sums are added in chunk
// order afterwards; as chunks are cut independently of the thread count, neither does it
// depend on the number of threads.
//
// A host with its own job system (a game engine's) lends its workers instead (HostTasks): the
// pool then starts no thread, and each loop is handed to the host as one task whose ranges join
// the loop as workers would. The chunks, and so the results, are the same bits either way.
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace mica {

// A host's job system: mica_world_def's enqueue_task, finish_task and task_user (mica.h says
// what each must do). Set, a pool starts no thread of its own.
struct HostTasks {
  using Task = void (*)(int32_t start, int32_t end, void* context);
  void* (*enqueue)(Task task, int32_t item_count, int32_t min_range, void* context, void* user) = nullptr;
  void (*finish)(void* handle, void* user) = nullptr;
  void* user = nullptr;
};

class ThreadPool {
 public:
  // threads >= 1 in all, the caller included: threads - 1 workers are started, or, with a
  // host's job system, its workers join each loop (at most threads - 1 of them).
  explicit ThreadPool(int32_t threads, const HostTasks& host = {});
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int32_t size() const { return size_; }

  // The items [start[p], start[p + 1]) of phases p = 0..phases-1, cut into chunks of `grain`
  // items: calls f(p, first, last, chunk) once per chunk, chunk numbering all chunks of all
  // phases in order (0..chunk_count-1). A phase starts once every chunk of the one before has
  // returned (and its writes are visible). f must not throw (a throw terminates). Not
  // reentrant: one caller at a time, no loop from inside f. Does not allocate once the pool has
  // seen a loop with as many phases.
  template <class F>
  void phased_for(const int32_t* start, int32_t phases, int32_t grain, F& f) {
    if (!prepare(start, phases, grain)) return;
    Loop<F> loop{this, start, grain, &f};
    run_erased(&Loop<F>::body, &loop);
  }

  static int32_t chunk_count(const int32_t* start, int32_t phases, int32_t grain) {
    int32_t chunks = 0;
    for (int32_t p = 0; p < phases; ++p) chunks += (start[p + 1] - start[p] + grain - 1) / grain;
    return chunks;
  }

  // The thread count a setting asks for: 0 means every CPU this process may run on.
  static int32_t resolve(int32_t requested);

  // How long an idle worker spins before it sleeps.
  static constexpr std::chrono::microseconds kSpin{50};

 private:
  template <class F>
  struct Loop {
    ThreadPool* pool;
    const int32_t* start;
    int32_t grain;
    F* f;
    static void body(void* ctx) {
      Loop& l = *static_cast<Loop*>(ctx);
      ThreadPool& pool = *l.pool;
      const std::vector<int32_t>& offsets = pool.offsets_;
      size_t p = 0;
      for (;;) {
        const int32_t k = pool.claimed_.fetch_add(1, std::memory_order_relaxed);
        if (k >= pool.chunks_) return;
        while (offsets[p + 1] <= k) ++p;
        pool.wait_completed(offsets[p]);
        const int32_t first = l.start[p] + (k - offsets[p]) * l.grain;
        const int32_t last = std::min(first + l.grain, l.start[p + 1]);
        (*l.f)(int32_t(p), first, last, k);
        pool.completed_.fetch_add(1, std::memory_order_acq_rel);
      }
    }
  };

  bool prepare(const int32_t* start, int32_t phases, int32_t grain);
  void run_erased(void (*fn)(void*), void* ctx);
  void run_on_host();
  static void host_range(int32_t start, int32_t end, void* pool);
  void wait_completed(int32_t chunks) const;
  void worker();

  int32_t size_;
  HostTasks host_;                       // enqueue set: the host's workers, none of our own
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::atomic<uint64_t> generation_{0};  // bumped (under mutex_) for each loop and to stop
  std::atomic<bool> stop_{false};        // set before the last bump
  std::atomic<uint64_t> open_{0};        // the generation of the loop threads may join, 0: none
  std::atomic<int32_t> active_{0};       // workers inside (or checking) a loop
  void (*fn_)(void*) = nullptr;          // the open loop, published by open_
  void* ctx_ = nullptr;
  std::vector<int32_t> offsets_;         // first chunk of each phase, and the chunk count
  int32_t chunks_ = 0;
  alignas(64) std::atomic<int32_t> claimed_{0};
  alignas(64) std::atomic<int32_t> completed_{0};
};

// Runs f(first, last) over [0, n) in chunks of `grain`: on the pool when there is one, else
// on the caller in one piece.
template <class F>
void parallel_for(ThreadPool* pool, int64_t n, int32_t grain, F&& f) {
  if (!pool || pool->size() == 1 || n <= grain) {
    f(int32_t(0), int32_t(n));
    return;
  }
  const int32_t start[2] = {0, int32_t(n)};
  auto chunk = [&](int32_t, int32_t first, int32_t last, int32_t) { f(first, last); };
  pool->phased_for(start, 1, grain, chunk);
}

}  // namespace mica
