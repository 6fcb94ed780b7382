// SPDX-License-Identifier: Apache-2.0
// MICA_ASSERT(condition, what): an invariant of the library's own code (not a check of the
// caller's input, which fails with Error(InvalidArgument) and a message for the caller). A broken
// invariant is a bug in libmica: it throws Error(Internal) naming the condition, the place and
// `what`, in every build type (the C layer returns it as MICA_ERR_INTERNAL; a host is not
// aborted), so the step that found it is undone like any failed step.
#pragma once
#include <string>

#include "core/error.hpp"

namespace mica::detail {
[[noreturn]] inline void assertion_failed(const char* condition, const char* what, const char* file, int line) {
  fail(Errc::Internal, std::string("libmica internal error: ") + what + " (" + condition + " is false at " + file +
                           ":" + std::to_string(line) + ")");
}
}  // namespace mica::detail

#define MICA_ASSERT(condition, what)                                                        \
  do {                                                                                      \
    if (!(condition)) ::mica::detail::assertion_failed(#condition, what, __FILE__, __LINE__); \
  } while (0)
