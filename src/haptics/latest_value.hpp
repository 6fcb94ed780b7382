// The newest value of a small plain struct, from one writer thread to any number of reader
// threads: a sequence lock. The servo thread publishes the device state; the simulation thread
// and the statistics getter (any thread) read it.
//
// Why not TripleBuffer: its read() hands a slot back to the writer, so it has exactly one
// reader; the device state and the statistics are read from several threads. The writer here
// is wait-free (two counter stores around a copy); a reader retries while it overlaps a write
// (a copy of a few dozen bytes, once per millisecond), so reads are not for the servo thread.
//
// The value is stored as atomic 64-bit words: release stores and acquire loads order each word
// against the sequence counter without standalone fences (which ThreadSanitizer does not model).
// There is no data race, so the C++ memory model and ThreadSanitizer both accept it; on x86 these
// are plain moves. That needs a trivially copyable T (a C struct such as mica_device_state; not
// Eigen vectors, which are not trivially copyable: use TripleBuffer or plain double arrays).
//
// Servo path: store() never allocates, locks, blocks or makes a system call.
#pragma once
#include <atomic>
#include <cstdint>
#include <cstring>
#include <thread>
#include <type_traits>

namespace mica {

template <class T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue copies T as bytes");
  static_assert(std::is_default_constructible_v<T>, "load() builds a T to copy into");
  static_assert(std::atomic<uint64_t>::is_always_lock_free, "the words must be lock-free");

 public:
  explicit LatestValue(const T& initial = T()) { store(initial); }
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  // The writer thread only.
  void store(const T& value) noexcept {
    uint64_t buffer[kWords] = {};
    std::memcpy(buffer, &value, sizeof(T));
    const uint64_t seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);  // odd: a write is under way
    // Release: a reader that sees any new word also sees the odd count (and retries).
    for (size_t i = 0; i < kWords; ++i) words_[i].store(buffer[i], std::memory_order_release);
    sequence_.store(seq + 2, std::memory_order_release);  // even again: the words are complete
  }

  // Any thread: the newest complete value.
  T load() const noexcept {
    uint64_t buffer[kWords];
    for (;;) {
      const uint64_t before = sequence_.load(std::memory_order_acquire);
      if ((before & 1) == 0) {
        // Acquire: the recheck below cannot be done before the words are read.
        for (size_t i = 0; i < kWords; ++i) buffer[i] = words_[i].load(std::memory_order_acquire);
        if (sequence_.load(std::memory_order_relaxed) == before) break;
      }
      std::this_thread::yield();  // the writer may have been preempted mid-write
    }
    T value;
    std::memcpy(&value, buffer, sizeof(T));
    return value;
  }

  // How many values have been stored (the constructor's included).
  uint64_t version() const noexcept { return sequence_.load(std::memory_order_acquire) / 2; }

 private:
  static constexpr size_t kWords = (sizeof(T) + sizeof(uint64_t) - 1) / sizeof(uint64_t);
  std::atomic<uint64_t> sequence_{0};
  std::atomic<uint64_t> words_[kWords];
};

}  // namespace mica
