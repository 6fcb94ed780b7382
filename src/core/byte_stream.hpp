// SPDX-License-Identifier: Apache-2.0
// Plain bytes in and out, for the world's saved state (world/state_io.cpp): values are copied
// as they are in memory (the state is restored by the same build on the same machine kind, and
// its header says which). A read past the end throws Error(Parse) naming what was being read.
// Plain values: scalars, PODs and Eigen's fixed-size matrices and quaternions (plain storage,
// though not trivially copyable by the standard's letter).
#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"

namespace mica {

class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_standard_layout<T>::value, "plain values only");
    put_bytes(&value, sizeof value);
  }
  // A count, then the items.
  template <class T, class A>
  void put_vector(const std::vector<T, A>& items) {
    static_assert(std::is_standard_layout<T>::value, "plain values only");
    put(uint64_t(items.size()));
    put_bytes(items.data(), items.size() * sizeof(T));
  }
  void put_bytes(const void* data, size_t size) {
    const auto* p = static_cast<const uint8_t*>(data);
    bytes_.insert(bytes_.end(), p, p + size);
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

class ByteReader {
 public:
  // `source` names what is read in messages ("the state", "the recording").
  ByteReader(const uint8_t* data, size_t size, const char* source = "the state")
      : data_(data), size_(size), source_(source) {}
  template <class T>
  T get(const char* what) {
    static_assert(std::is_standard_layout<T>::value, "plain values only");
    T value;
    get_bytes(&value, sizeof value, what);
    return value;
  }
  template <class T, class A>
  void get_vector(std::vector<T, A>& items, const char* what) {
    const uint64_t n = get<uint64_t>(what);
    if (n > (size_ - at_) / sizeof(T)) truncated(what);
    items.resize(size_t(n));
    get_bytes(items.data(), size_t(n) * sizeof(T), what);
  }
  void get_bytes(void* out, size_t size, const char* what) {
    if (size > size_ - at_) truncated(what);
    if (size) std::memcpy(out, data_ + at_, size);
    at_ += size;
  }
  size_t position() const { return at_; }
  size_t remaining() const { return size_ - at_; }

 private:
  [[noreturn]] void truncated(const char* what) const {
    fail(Errc::Parse, std::string(source_) + " ends inside " + std::string(what) + " (at byte " + std::to_string(at_) + " of " +
                          std::to_string(size_) + "): truncated or corrupt");
  }
  const uint8_t* data_;
  size_t size_;
  const char* source_;
  size_t at_ = 0;
};

// Byte order and the size of a double, written in a file's header: a saved state or a recording is
// read back only on a machine where its values read back alike.
constexpr uint32_t kByteLayout = 0x01020304u ^ uint32_t(sizeof(double) << 24);

// FNV-1a over bytes, continuing from `hash` (chain calls to hash several arrays).
inline uint64_t fnv1a(const void* data, size_t size, uint64_t hash = 0xcbf29ce484222325ull) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < size; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  return hash;
}

}  // namespace mica
