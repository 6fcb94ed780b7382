// SPDX-License-Identifier: Apache-2.0
#include "core/background_thread.hpp"

#include <pthread.h>

namespace mica {

BackgroundThread::~BackgroundThread() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;  // the thread ends after the job in flight, if any
  }
  changed_.notify_all();
  thread_.join();
}

void BackgroundThread::start(void (*job)(void*), void* context) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = job;
    context_ = context;
    error_ = nullptr;
  }
  if (!thread_.joinable()) {
    thread_ = std::thread([this] { run(); });
    pthread_setname_np(thread_.native_handle(), name_);  // best effort: a name is only a help
  }
  changed_.notify_all();
}

void BackgroundThread::wait() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return job_ == nullptr; });
}

bool BackgroundThread::busy() {
  std::lock_guard<std::mutex> lock(mutex_);
  return job_ != nullptr;
}

void BackgroundThread::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return job_ != nullptr || stop_; });
    if (!job_) return;  // stopped, nothing left to run
    void (*job)(void*) = job_;
    void* context = context_;
    lock.unlock();
    std::exception_ptr error;
    try {
      job(context);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    error_ = error;
    job_ = nullptr;
    changed_.notify_all();
  }
}

}  // namespace mica
