// The C layer's shared pieces: the world handle, the exception guard, and the struct
// translation helpers. Validate, translate, call, catch: nothing else lives here.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>
#include <string>

#include "mica/mica.h"
#include "world/world.hpp"

struct mica_world {
  explicit mica_world(const mica::WorldSettings& s) : world(s) {}
  mica::World world;
  mutable std::string last_error;
  mica_log_fn log = nullptr;
  void* log_user = nullptr;
};

namespace mica_capi {

// The message of the last failure of a call that had no world (creation), per thread.
std::string& thread_last_error();

mica_status to_status(mica::Errc code);

// Records "function: message" on the world (or the thread) and logs it.
mica_status report(const mica_world* world, mica_status status, const char* function, const std::string& message);

// A refusal by the C layer's own checks, with the status to return.
struct Refusal {
  mica_status status;
  std::string message;
};
[[noreturn]] inline void refuse(mica_status status, std::string message) { throw Refusal{status, std::move(message)}; }

// Runs f() and turns every exception into a status: no exception crosses the C boundary.
template <class F>
mica_status guarded(const mica_world* world, const char* function, F&& f) noexcept {
  try {
    return f();
  } catch (const Refusal& r) {
    return report(world, r.status, function, r.message);
  } catch (const mica::Error& e) {
    return report(world, to_status(e.code()), function, e.what());
  } catch (const std::bad_alloc&) {
    return report(world, MICA_ERR_OUT_OF_MEMORY, function, "out of memory");
  } catch (const std::exception& e) {
    return report(world, MICA_ERR_INTERNAL, function, std::string("internal error: ") + e.what());
  } catch (...) {
    return report(world, MICA_ERR_INTERNAL, function, "internal error: unknown exception");
  }
}

inline void require(const void* p, const char* name) {
  if (!p) refuse(MICA_ERR_NULL_ARGUMENT, std::string(name) + " is NULL");
}

// Copies the first struct_size bytes of a caller's def over the defaults. A def from an
// older caller (smaller) keeps the defaults for the fields it lacks; a larger or a too
// small one is refused.
template <class T>
T read_def(const T* def, T defaults, uint32_t min_size, const char* name) {
  require(def, name);
  if (def->struct_size < min_size || def->struct_size > sizeof(T))
    refuse(MICA_ERR_STRUCT_SIZE, std::string(name) + "->struct_size is " + std::to_string(def->struct_size) +
               ", this libmica knows sizes " + std::to_string(min_size) + ".." + std::to_string(sizeof(T)) +
               " (initialise it with the *_default() function)");
  std::memcpy(static_cast<void*>(&defaults), def, def->struct_size);
  return defaults;
}

// Writes defaults into the first struct_size bytes of *def (the *_init functions).
template <class T>
mica_status init_def(T* def, uint32_t struct_size, uint32_t min_size, const T& defaults, const char* function) {
  return guarded(nullptr, function, [&] {
    require(def, "def");
    if (struct_size < min_size || struct_size > sizeof(T))
      refuse(MICA_ERR_STRUCT_SIZE, "struct_size is " + std::to_string(struct_size) + ", this libmica knows sizes " +
                                       std::to_string(min_size) + ".." + std::to_string(sizeof(T)));
    std::memcpy(static_cast<void*>(def), &defaults, struct_size);
    def->struct_size = struct_size;
    return MICA_OK;
  });
}

inline mica::Vec3 vec3(const double* v, const char* name) {
  require(v, name);
  return {v[0], v[1], v[2]};
}

inline Eigen::Quaterniond quaternion(const double* q, const char* name) {
  require(q, name);
  return {q[0], q[1], q[2], q[3]};  // (w, x, y, z)
}

// Copies `count` items of `width` values to a caller buffer with the size-query protocol.
template <class T>
mica_status copy_out(const T* source, int32_t count, int32_t width, T* out, int32_t capacity, int32_t* out_count) {
  if (!out && !out_count) require(out_count, "out_count");
  if (capacity < 0) refuse(MICA_ERR_INVALID_ARGUMENT, "capacity is " + std::to_string(capacity) + ", must be >= 0");
  if (out_count) *out_count = count;
  if (!out) return MICA_OK;
  if (capacity < count)
    refuse(MICA_ERR_BUFFER_TOO_SMALL, "buffer too small: capacity " + std::to_string(capacity) + ", needed " +
                                          std::to_string(count));
  std::copy(source, source + size_t(count) * size_t(width), out);
  return MICA_OK;
}

}  // namespace mica_capi
