// SPDX-License-Identifier: Apache-2.0
// One persistent thread that runs one job at a time while its owner goes on (LaggedFactor's
// refresh of a factor). Made at the first start() and joined when destroyed. Unlike std::async,
// which made a thread and a shared state on the heap for every job, start() and wait() allocate
// nothing once the thread exists: a job is a function pointer and its context. The thread is
// named (pthread_setname_np), so a host finds it among /proc/self/task/*/comm to pin or
// prioritise it; it inherits the affinity and policy of the thread that first calls start().
#pragma once
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

namespace mica {

class BackgroundThread {
 public:
  // `name`: at most 15 characters (Linux's limit), a static string.
  explicit BackgroundThread(const char* name) : name_(name) {}
  ~BackgroundThread();  // waits for the job in flight, then joins
  BackgroundThread(const BackgroundThread&) = delete;
  BackgroundThread& operator=(const BackgroundThread&) = delete;

  // Runs job(context) on the thread. The job before it must be over (wait()).
  void start(void (*job)(void*), void* context);
  // Blocks until the last job started is over (at once if none is running).
  void wait();
  // Whether the last job started is still running (a look, not a wait).
  bool busy();
  // What the last job threw (null: it returned, or none ran); kept until the next start().
  std::exception_ptr error() const { return error_; }

 private:
  void run();

  const char* name_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  void (*job_)(void*) = nullptr;  // the job to run or running; null when over
  void* context_ = nullptr;
  bool stop_ = false;
  std::exception_ptr error_;  // written by the thread before it clears job_
};

}  // namespace mica
