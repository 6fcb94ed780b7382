// SPDX-License-Identifier: Apache-2.0
// Counts heap allocations made by the current thread, so a test can assert that a servo-path
// call allocates nothing:
//
//   start_counting_allocations();
//   filter.filter(x, true);
//   assert_int_equal(stop_counting_allocations(), 0);
//
// It replaces the global operator new and delete (every form) of the test binary, so include
// it in exactly one translation unit of a binary (each tests/<concern>/test_*.cpp is its own
// binary). Only operator new is counted; a direct malloc() is not, unless the binary defines
// MICA_TEST_COUNT_MALLOC before including this: then malloc and its kin (calloc, realloc,
// posix_memalign, ...) are replaced too and every heap block counts once, whoever asks for it
// (Eigen allocates with malloc, not new). To see who allocates: a breakpoint on
// mica_test::note_allocation.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace mica_test {

// Per thread, and constant-initialised so operator new can use them at any point of a thread's life.
inline thread_local bool counting_allocations = false;
inline thread_local int64_t allocations_counted = 0;

inline void start_counting_allocations() {
  allocations_counted = 0;
  counting_allocations = true;
}

// The allocations made on this thread since start_counting_allocations().
inline int64_t stop_counting_allocations() {
  counting_allocations = false;
  return allocations_counted;
}

// Called for each allocation counted (a place for a debugger's breakpoint).
[[gnu::noinline]] inline void note_allocation() {
  ++allocations_counted;
  asm volatile("");
}

inline void* counted_allocation(std::size_t size, std::size_t alignment) noexcept {
#ifndef MICA_TEST_COUNT_MALLOC  // else malloc counts it
  if (counting_allocations) note_allocation();
#endif
  if (size == 0) size = 1;  // new must return a distinct pointer for size 0
  if (alignment <= alignof(std::max_align_t)) return std::malloc(size);
  void* p = nullptr;
  return posix_memalign(&p, alignment, size) == 0 ? p : nullptr;
}

inline void* counted_allocation_or_throw(std::size_t size, std::size_t alignment) {
  void* p = counted_allocation(size, alignment);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace mica_test

// Replacement functions may not be inline: hence the one-translation-unit rule above.
void* operator new(std::size_t n) { return mica_test::counted_allocation_or_throw(n, 0); }
void* operator new[](std::size_t n) { return mica_test::counted_allocation_or_throw(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) {
  return mica_test::counted_allocation_or_throw(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return mica_test::counted_allocation_or_throw(n, std::size_t(a));
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return mica_test::counted_allocation(n, 0); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return mica_test::counted_allocation(n, 0); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return mica_test::counted_allocation(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return mica_test::counted_allocation(n, std::size_t(a));
}

// Both kinds of block come from malloc or posix_memalign, so free() releases either.
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

#ifdef MICA_TEST_COUNT_MALLOC
// glibc's own allocator under its exported internal names; the replacements count, then forward
// (so free, malloc_usable_size and the rest of glibc see ordinary glibc blocks).
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);

void* malloc(std::size_t n) noexcept {
  if (mica_test::counting_allocations) mica_test::note_allocation();
  return __libc_malloc(n);
}
void* calloc(std::size_t count, std::size_t n) noexcept {
  if (mica_test::counting_allocations) mica_test::note_allocation();
  return __libc_calloc(count, n);
}
void* realloc(void* p, std::size_t n) noexcept {
  if (mica_test::counting_allocations) mica_test::note_allocation();
  return __libc_realloc(p, n);
}
void* memalign(std::size_t alignment, std::size_t n) noexcept {
  if (mica_test::counting_allocations) mica_test::note_allocation();
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) noexcept { return memalign(alignment, n); }
int posix_memalign(void** out, std::size_t alignment, std::size_t n) noexcept {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return 22;  // EINVAL
  void* p = memalign(alignment, n);
  if (!p) return 12;  // ENOMEM
  *out = p;
  return 0;
}
}
#endif
