// SPDX-License-Identifier: Apache-2.0
// The C layer's shared pieces: the world handle, the exception guard, and the struct
// translation helpers. Validate, translate, call, catch: nothing else lives here.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <new>
#include <string>

#include "mica/mica.h"
#include "mica/mica_device.h"
#include "embedding/embedding.hpp"
#include "world/world.hpp"

struct mica_world;

namespace mica_capi {
// The world's topology listener (capi/embedding.cpp): each embedding of the changed body follows
// the change; never throws (an embedding that cannot follow is left with every vertex unbound).
void follow_topology(mica_world* world, const mica::TopologyChange& change, const mica::Body& body) noexcept;
}  // namespace mica_capi

struct mica_world {
  explicit mica_world(const mica::WorldSettings& s) : world(s) {
    world.set_topology_listener([this](const mica::TopologyChange& change, const mica::Body& body) {
      mica_capi::follow_topology(this, change, body);
    });
  }
  mica_world(const mica_world&) = delete;  // the listener holds this address
  mica_world& operator=(const mica_world&) = delete;
  mica::World world;
  // Render meshes bound to the world's bodies (capi/embedding.cpp): they read bodies, never change
  // them, and follow a change of their body's tets (follow_topology).
  mica::SlotMap<mica::Embedding, mica::IdKind::Embedding> embeddings;
  // What the last topology change left unbound in the embeddings, for the call that made it to
  // return as a warning ("" when nothing).
  std::string topology_warning;
  mutable std::string last_error;
  mica_log_fn log = nullptr;
  void* log_user = nullptr;
};

namespace mica_capi {

// This library's version as text ("0.5.0"), for messages.
inline std::string version_text(uint32_t number = MICA_VERSION_NUMBER) {
  return std::to_string(number / 10000) + "." + std::to_string(number / 100 % 100) + "." + std::to_string(number % 100);
}

// The message of the last failure of a call that had no world (creation), per thread.
std::string& thread_last_error();

mica_status to_status(mica::Errc code);

// Records "function: message" on the world (or the thread) and logs it.
mica_status report(const mica_world* world, mica_status status, const char* function, const std::string& message);

// After a call that changed a body's tets: MICA_OK, or MICA_WARN_UNBOUND_VERTICES with the
// listener's message as the world's last error (capi/embedding.cpp).
mica_status topology_warning(mica_world* world, const char* function);

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

// The size each def had in the first release that had it: 0.2.0, the first release with an
// ABI promise (its header is tests/abi_fixtures/0.2). A caller's struct_size may be anything
// from this to sizeof(T): a program built against an older 0.x header keeps working, and the
// fields its header lacked keep their defaults. Never move these: a field appended later
// changes sizeof(T), not the first size. Written as "the end of the last field 0.2.0 had" so
// that they hold on every ABI (the numbers are x86-64's).
#define MICA_CAPI_END_OF(T, field) (offsetof(T, field) + sizeof(static_cast<T*>(nullptr)->field))
constexpr uint32_t first_size(const mica_world_def*) { return MICA_CAPI_END_OF(mica_world_def, body_friction); }
constexpr uint32_t first_size(const mica_body_def*) { return MICA_CAPI_END_OF(mica_body_def, velocity); }
constexpr uint32_t first_size(const mica_lpc_def*) { return MICA_CAPI_END_OF(mica_lpc_def, velocity); }
constexpr uint32_t first_size(const mica_tool_def*) { return MICA_CAPI_END_OF(mica_tool_def, reserved0); }
constexpr uint32_t first_size(const mica_device_def*) { return MICA_CAPI_END_OF(mica_device_def, hand_damping); }
constexpr uint32_t first_size(const mica_embedding_def*) { return MICA_CAPI_END_OF(mica_embedding_def, radius); }  // 0.7
#undef MICA_CAPI_END_OF
template <class T>
constexpr uint32_t first_size() {
  return first_size(static_cast<const T*>(nullptr));
}
static_assert(sizeof(void*) != 8 || (first_size<mica_world_def>() == 112 && first_size<mica_body_def>() == 104 &&
                                     first_size<mica_lpc_def>() == 80 && first_size<mica_tool_def>() == 160 &&
                                     first_size<mica_device_def>() == 200),
              "the first released sizes (0.2.0, x86-64) must never change");

// Refuses a struct_size this library does not accept ("<name>->struct_size" or "struct_size"
// in the message): smaller than the def's first release, or larger than this library's def (a
// newer header).
template <class T>
void check_struct_size(uint32_t struct_size, const std::string& field) {
  const uint32_t first = first_size<T>(), last = sizeof(T);
  const std::string range = std::to_string(first) + ".." + std::to_string(last);
  if (struct_size > last)
    refuse(MICA_ERR_STRUCT_SIZE,
           field + " is " + std::to_string(struct_size) + ", larger than any this libmica " + version_text() +
               " knows (" + range + "): the program was built against a newer libmica header than the library it "
               "loaded; run it with that libmica or a newer one");
  if (struct_size < first)
    refuse(MICA_ERR_STRUCT_SIZE, field + " is " + std::to_string(struct_size) + ", this libmica knows sizes " + range +
                                     " (the first from 0.2.0); initialise the def with its *_default() or *_init() function");
}

// Copies the first struct_size bytes of a caller's def over the defaults. A def from an
// older caller (smaller) keeps the defaults for the fields it lacks; a larger one (a newer
// header) or one smaller than the first release's is refused.
template <class T>
T read_def(const T* def, T defaults, const char* name) {
  require(def, name);
  check_struct_size<T>(def->struct_size, std::string(name) + "->struct_size");
  std::memcpy(static_cast<void*>(&defaults), def, def->struct_size);
  return defaults;
}

// Writes defaults into the first struct_size bytes of *def (the *_init functions), any size
// read_def accepts; on a refusal *def is left untouched.
template <class T>
mica_status init_def(T* def, uint32_t struct_size, const T& defaults, const char* function) {
  return guarded(nullptr, function, [&] {
    require(def, "def");
    check_struct_size<T>(struct_size, "struct_size");
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
