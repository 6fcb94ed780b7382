// SPDX-License-Identifier: Apache-2.0
// Hands the newest value from one writer thread to one reader thread without locks: the
// simulation thread publishes a force model, the servo thread reads the newest one.
//
// Three slots: the writer owns one, the reader owns one, the third is shared and swapped
// atomically (acquire/release) on publish and read. Both sides are wait-free; neither ever
// sees a slot the other is using, so a value is never torn. Nothing is copied: the writer
// fills its slot in place and the reader gets a pointer to its own slot.
//
// Servo path: write_slot(), publish() and read() never allocate, lock, block or make a system
// call. The slots are constructed once; a T that owns heap storage must have that storage
// reserved in all three slots before use (then T need not be trivially copyable).
#pragma once
#include <atomic>
#include <cstdint>

namespace mica {

template <class T>
class TripleBuffer {
 public:
  // Every slot starts as `initial`: read() returns it until the first publish().
  explicit TripleBuffer(const T& initial = T()) : slots_{{initial}, {initial}, {initial}} {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // Writer thread only. The slot holds an older value (not the last published one): set every
  // field the reader uses.
  T& write_slot() noexcept { return slots_[write_].value; }

  // Writer thread only: makes the slot the newest value and takes a free slot to write next.
  void publish() noexcept {
    const uint8_t previous = shared_.exchange(uint8_t(write_ | kFresh), std::memory_order_acq_rel);
    write_ = previous & kIndex;
  }

  // Reader thread only: the newest published value (the same one as last time if nothing was
  // published since). The pointer stays valid and unchanged until the reader's next read().
  const T* read() noexcept {
    if (shared_.load(std::memory_order_relaxed) & kFresh) {
      const uint8_t previous = shared_.exchange(read_, std::memory_order_acq_rel);
      read_ = previous & kIndex;
    }
    return &slots_[read_].value;
  }

  // Reader thread only: whether read() would return a newer value than last time.
  bool has_new() const noexcept { return shared_.load(std::memory_order_relaxed) & kFresh; }

 private:
  static constexpr uint8_t kIndex = 0x3;  // low bits of shared_: the slot index
  static constexpr uint8_t kFresh = 0x4;  // the shared slot holds a value the reader has not taken
  static_assert(std::atomic<uint8_t>::is_always_lock_free, "the exchange must be lock-free");

  // Its own cache line per slot, so the two threads do not false-share.
  struct alignas(64) Slot {
    T value;
  };
  Slot slots_[3];
  uint8_t write_ = 0;                         // the writer's slot (writer thread only)
  alignas(64) std::atomic<uint8_t> shared_{1};  // the middle slot, plus kFresh
  alignas(64) uint8_t read_ = 2;              // the reader's slot (reader thread only)
};

}  // namespace mica
