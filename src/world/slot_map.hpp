// SPDX-License-Identifier: Apache-2.0
// Objects named by 64-bit ids that carry a kind and a generation, so a stale or foreign id
// is detected instead of dereferenced: bits 0-31 slot + 1, 32-55 generation, 56-63 kind.
//
// The slots live in fixed chunks that are never moved or freed while the map lives, and a slot's
// object pointer and generation are atomic: find() may run on other threads while the owning
// thread inserts (the devices: mica_device_get_stats on any thread while mica_device_create runs
// on the world's thread). An object may be erased while other threads look it up only if they do
// so inside a ReadGuard: erase() unlinks the object, then waits until no guard is open before it
// deletes it. A reader never allocates, locks or blocks (two atomic increments).
#pragma once
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"

namespace mica {

using Id = uint64_t;
enum class IdKind : uint8_t { Body = 1, Lpc = 2, Tool = 3, Device = 4, Embedding = 5 };
// The kind an id was made for (its top byte); not a check that the object lives.
inline IdKind id_kind(Id id) { return IdKind(uint8_t(id >> 56)); }

template <class T, IdKind Kind>
class SlotMap {
 public:
  static constexpr uint32_t kChunkSize = 256, kMaxChunks = 1024;
  static constexpr uint32_t kCapacity = kChunkSize * kMaxChunks;  // live objects of one kind, at most

  SlotMap() {
    for (auto& c : chunks_) c.store(nullptr, std::memory_order_relaxed);
  }
  ~SlotMap() { release(); }
  SlotMap(const SlotMap&) = delete;
  SlotMap& operator=(const SlotMap&) = delete;
  // Moving (a World returned by value) takes the chunks; no other thread may use either map.
  SlotMap(SlotMap&& o) noexcept { take(o); }
  SlotMap& operator=(SlotMap&& o) noexcept {
    if (this != &o) {
      release();
      take(o);
    }
    return *this;
  }

  // The owning thread.
  Id insert(std::unique_ptr<T> item) {
    if (free_.empty()) {
      if (size_ == kCapacity)
        fail(Errc::OutOfRange, "more than " + std::to_string(kCapacity) + " objects of one kind in a world");
      free_.reserve(size_t(size_) + 1);  // may throw: nothing changed yet
      const uint32_t chunk = size_ / kChunkSize;
      if (!chunks_[chunk].load(std::memory_order_relaxed))
        chunks_[chunk].store(new Slot[kChunkSize], std::memory_order_release);  // may throw: nothing changed yet
      free_.push_back(size_++);
      size_seen_.store(size_, std::memory_order_release);
    }
    const uint32_t index = free_.back();
    free_.pop_back();
    Slot& s = slot(index);
    s.item.store(item.release(), std::memory_order_release);
    return make_id(index, s.generation.load(std::memory_order_relaxed));
  }

  // Any thread; the object may be erased meanwhile unless the caller holds a ReadGuard.
  T* find(Id id) const {
    const uint32_t index = uint32_t(id & 0xffffffffu) - 1;
    if (id == 0 || (id >> 56) != uint64_t(Kind) || index >= size_seen_.load(std::memory_order_acquire)) return nullptr;
    const Slot& s = slot(index);
    // The object first, then its generation: a slot reused after an erase has its new generation
    // before its new object, so a stale id never matches the new object.
    T* item = s.item.load(std::memory_order_seq_cst);
    return (item && s.generation.load(std::memory_order_seq_cst) == ((id >> 32) & 0xffffffu)) ? item : nullptr;
  }

  // Slots ever used (0: nothing was ever inserted, so the next ids are the first ones).
  uint32_t slots_used() const { return size_; }

  T& get(Id id, const char* what) const {
    T* item = find(id);
    if (!item) fail(Errc::StaleId, std::string(what) + " id " + hex(id) + " is null, of another kind, or destroyed");
    return *item;
  }

  // The owning thread: puts `item` in the place of the live object `id` (same id); returns the old one.
  std::unique_ptr<T> replace(Id id, std::unique_ptr<T> item) noexcept {
    const uint32_t index = uint32_t(id & 0xffffffffu) - 1;
    return std::unique_ptr<T>(slot(index).item.exchange(item.release(), std::memory_order_seq_cst));
  }

  // The owning thread: after this, erase() allocates nothing.
  void reserve_free() { free_.reserve(size_); }

  // The owning thread. Waits (yielding) for open ReadGuards before it deletes the object.
  void erase(Id id) {
    if (!find(id)) return;
    const uint32_t index = uint32_t(id & 0xffffffffu) - 1;
    free_.reserve(size_);  // may throw: nothing changed yet
    Slot& s = slot(index);
    T* item = s.item.exchange(nullptr, std::memory_order_seq_cst);
    uint32_t generation = (s.generation.load(std::memory_order_relaxed) + 1) & 0xffffffu;
    if (generation == 0) generation = 1;
    s.generation.store(generation, std::memory_order_seq_cst);
    while (readers_.load(std::memory_order_seq_cst) != 0) std::this_thread::yield();
    delete item;
    free_.push_back(index);
  }

  // While one is alive, an object found on this thread is not deleted by erase() on another.
  class ReadGuard {
   public:
    explicit ReadGuard(const SlotMap& map) : map_(map) { map_.readers_.fetch_add(1, std::memory_order_seq_cst); }
    ~ReadGuard() { map_.readers_.fetch_sub(1, std::memory_order_release); }
    ReadGuard(const ReadGuard&) = delete;
    ReadGuard& operator=(const ReadGuard&) = delete;

   private:
    const SlotMap& map_;
  };

  // The owning thread. Visits live objects in slot order as f(id, T&).
  template <class F>
  void for_each(F&& f) const {
    for (uint32_t i = 0; i < size_; ++i) {
      const Slot& s = slot(i);
      if (T* item = s.item.load(std::memory_order_relaxed))
        f(make_id(i, s.generation.load(std::memory_order_relaxed)), *item);
    }
  }

  static std::string hex(Id id) {
    char text[24];
    std::snprintf(text, sizeof text, "0x%llx", static_cast<unsigned long long>(id));
    return text;
  }

 private:
  struct Slot {
    std::atomic<T*> item{nullptr};
    std::atomic<uint32_t> generation{1};
  };
  static Id make_id(uint32_t index, uint32_t generation) {
    return (uint64_t(Kind) << 56) | (uint64_t(generation) << 32) | (uint64_t(index) + 1);
  }
  void release() noexcept {
    for (uint32_t i = 0; i < size_; ++i) delete slot(i).item.load(std::memory_order_relaxed);
    for (auto& c : chunks_) delete[] c.exchange(nullptr, std::memory_order_relaxed);
    size_ = 0;
    size_seen_.store(0, std::memory_order_relaxed);
    free_.clear();
  }
  void take(SlotMap& o) noexcept {
    for (uint32_t c = 0; c < kMaxChunks; ++c)
      chunks_[c].store(o.chunks_[c].exchange(nullptr, std::memory_order_relaxed), std::memory_order_relaxed);
    size_ = o.size_;
    size_seen_.store(o.size_seen_.load(std::memory_order_relaxed), std::memory_order_relaxed);
    free_ = std::move(o.free_);
    readers_.store(0, std::memory_order_relaxed);
    o.size_ = 0;
    o.size_seen_.store(0, std::memory_order_relaxed);
    o.free_.clear();
  }
  Slot& slot(uint32_t index) const {
    return chunks_[index / kChunkSize].load(std::memory_order_acquire)[index % kChunkSize];
  }

  std::array<std::atomic<Slot*>, kMaxChunks> chunks_;  // allocated as needed, never moved
  uint32_t size_ = 0;                                   // slots in use or free (the owning thread's)
  std::atomic<uint32_t> size_seen_{0};                  // the same, for readers
  std::vector<uint32_t> free_;
  mutable std::atomic<int32_t> readers_{0};
};

}  // namespace mica
