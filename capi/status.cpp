// SPDX-License-Identifier: Apache-2.0
// Version, status text, error reporting.
#include "capi_internal.hpp"

using namespace mica_capi;

namespace mica_capi {

std::string& thread_last_error() {
  thread_local std::string message;
  return message;
}

mica_status to_status(mica::Errc code) {
  switch (code) {
    case mica::Errc::InvalidArgument: return MICA_ERR_INVALID_ARGUMENT;
    case mica::Errc::OutOfRange: return MICA_ERR_OUT_OF_RANGE;
    case mica::Errc::StaleId: return MICA_ERR_STALE_ID;
    case mica::Errc::BadMesh: return MICA_ERR_BAD_MESH;
    case mica::Errc::Io: return MICA_ERR_IO;
    case mica::Errc::Parse: return MICA_ERR_PARSE;
    case mica::Errc::Numerical: return MICA_ERR_NUMERICAL;
    case mica::Errc::WrongState: return MICA_ERR_WRONG_STATE;
    case mica::Errc::Unsupported: return MICA_ERR_UNSUPPORTED;
    case mica::Errc::Device: return MICA_ERR_DEVICE;
    case mica::Errc::Internal: return MICA_ERR_INTERNAL;
    case mica::Errc::Diverged: return MICA_ERR_DIVERGED;
    case mica::Errc::Truncated: return MICA_ERR_TRUNCATED;
  }
  return MICA_ERR_INTERNAL;
}

mica_status report(const mica_world* world, mica_status status, const char* function, const std::string& message) {
  try {
    std::string& target = world ? world->last_error : thread_last_error();
    target = std::string(function) + ": " + message;
    if (world && world->log) world->log(MICA_LOG_ERROR, target.c_str(), world->log_user);
  } catch (...) {
    // Out of memory while reporting: the status still says what happened.
  }
  return status;
}

}  // namespace mica_capi

extern "C" {

MICA_API int32_t mica_version(void) { return MICA_VERSION_NUMBER; }

MICA_API const char* mica_status_string(mica_status status) {
  switch (status) {
    case MICA_OK: return "MICA_OK: success";
    case MICA_WARN_NOT_CONVERGED: return "MICA_WARN_NOT_CONVERGED: the solver stopped at its cap before its tolerance";
    case MICA_WARN_DEVICE: return "MICA_WARN_DEVICE: the haptic device reported a warning";
    case MICA_WARN_BODIES_OVERLAP:
      return "MICA_WARN_BODIES_OVERLAP: the body was created deep inside another; the two do not collide until they part";
    case MICA_WARN_UNBOUND_VERTICES:
      return "MICA_WARN_UNBOUND_VERTICES: the embedding was made, but some vertices are too far from the body and unbound";
    case MICA_ERR_NULL_ARGUMENT: return "MICA_ERR_NULL_ARGUMENT: a required pointer is NULL";
    case MICA_ERR_INVALID_ARGUMENT: return "MICA_ERR_INVALID_ARGUMENT: a value is outside its domain";
    case MICA_ERR_OUT_OF_RANGE: return "MICA_ERR_OUT_OF_RANGE: an index is outside its array";
    case MICA_ERR_STALE_ID: return "MICA_ERR_STALE_ID: the id is null, of another kind, or destroyed";
    case MICA_ERR_VERSION_MISMATCH: return "MICA_ERR_VERSION_MISMATCH: header and library versions differ";
    case MICA_ERR_STRUCT_SIZE: return "MICA_ERR_STRUCT_SIZE: unknown struct_size";
    case MICA_ERR_BAD_MESH: return "MICA_ERR_BAD_MESH: degenerate or inverted rest element";
    case MICA_ERR_IO: return "MICA_ERR_IO: file cannot be opened, read or written";
    case MICA_ERR_PARSE: return "MICA_ERR_PARSE: malformed file";
    case MICA_ERR_NUMERICAL: return "MICA_ERR_NUMERICAL: non-finite result, step undone";
    case MICA_ERR_WRONG_STATE: return "MICA_ERR_WRONG_STATE: call not allowed now";
    case MICA_ERR_UNSUPPORTED: return "MICA_ERR_UNSUPPORTED: not available";
    case MICA_ERR_BUFFER_TOO_SMALL: return "MICA_ERR_BUFFER_TOO_SMALL: buffer smaller than the result";
    case MICA_ERR_DEVICE: return "MICA_ERR_DEVICE: haptic device failure";
    case MICA_ERR_OUT_OF_MEMORY: return "MICA_ERR_OUT_OF_MEMORY: allocation failed";
    case MICA_ERR_INTERNAL: return "MICA_ERR_INTERNAL: internal error";
    case MICA_ERR_DIVERGED: return "MICA_ERR_DIVERGED: the replay did not reproduce its recording";
    case MICA_ERR_TRUNCATED: return "MICA_ERR_TRUNCATED: the recording was cut short (no end entry)";
    default: return "unknown mica_status";
  }
}

MICA_API const char* mica_stage_name(int32_t stage) {
  static const char* const kNames[MICA_STAGE_COUNT] = {"loads", "rotations", "elements", "damping", "constraints",
                                                        "solve", "integrate", "collide",  "forces"};
  return (stage >= 0 && stage < MICA_STAGE_COUNT) ? kNames[stage] : "unknown";
}

MICA_API const char* mica_world_last_error(const mica_world* world) {
  return world ? world->last_error.c_str() : thread_last_error().c_str();
}

}  // extern "C"
