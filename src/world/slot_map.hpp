// Objects named by 64-bit ids that carry a kind and a generation, so a stale or foreign id
// is detected instead of dereferenced: bits 0-31 slot + 1, 32-55 generation, 56-63 kind.
#pragma once
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace mica {

using Id = uint64_t;
enum class IdKind : uint8_t { Body = 1, Lpc = 2, Tool = 3, Device = 4 };

template <class T, IdKind Kind>
class SlotMap {
 public:
  Id insert(std::unique_ptr<T> item) {
    if (free_.empty()) {
      slots_.reserve(slots_.size() + 1);  // may throw: nothing changed yet
      slots_.push_back(Slot{});
      free_.push_back(uint32_t(slots_.size() - 1));
    }
    const uint32_t index = free_.back();
    free_.pop_back();
    slots_[index].item = std::move(item);
    return make_id(index, slots_[index].generation);
  }

  T* find(Id id) const {
    const uint32_t index = uint32_t(id & 0xffffffffu) - 1;
    if (id == 0 || (id >> 56) != uint64_t(Kind) || index >= slots_.size()) return nullptr;
    const Slot& s = slots_[index];
    return (s.item && s.generation == ((id >> 32) & 0xffffffu)) ? s.item.get() : nullptr;
  }

  T& get(Id id, const char* what) const {
    T* item = find(id);
    if (!item) fail(Errc::StaleId, std::string(what) + " id " + hex(id) + " is null, of another kind, or destroyed");
    return *item;
  }

  void erase(Id id) {
    if (!find(id)) return;
    const uint32_t index = uint32_t(id & 0xffffffffu) - 1;
    slots_[index].item.reset();
    slots_[index].generation = (slots_[index].generation + 1) & 0xffffffu;
    if (slots_[index].generation == 0) slots_[index].generation = 1;
    free_.reserve(slots_.size());
    free_.push_back(index);
  }

  // Visits live objects in slot order as f(id, T&).
  template <class F>
  void for_each(F&& f) const {
    for (uint32_t i = 0; i < slots_.size(); ++i)
      if (slots_[i].item) f(make_id(i, slots_[i].generation), *slots_[i].item);
  }

  static std::string hex(Id id) {
    char text[24];
    std::snprintf(text, sizeof text, "0x%llx", static_cast<unsigned long long>(id));
    return text;
  }

 private:
  struct Slot {
    std::unique_ptr<T> item;
    uint32_t generation = 1;
  };
  static Id make_id(uint32_t index, uint32_t generation) {
    return (uint64_t(Kind) << 56) | (uint64_t(generation) << 32) | (uint64_t(index) + 1);
  }
  std::vector<Slot> slots_;
  std::vector<uint32_t> free_;
};

}  // namespace mica
