// SPDX-License-Identifier: Apache-2.0
// The core reports failure by throwing mica::Error; the C layer turns it into a status.
#pragma once
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace mica {

enum class Errc {
  InvalidArgument,  // a value is out of its domain (NaN, negative size, bad enum)
  OutOfRange,       // an index is outside its array
  StaleId,          // an id refers to an object that was destroyed
  BadMesh,          // the mesh is unusable (degenerate or inverted rest element, ...)
  Io,               // a file cannot be opened or read
  Parse,            // a file is malformed
  Numerical,        // the step produced non-finite values
  WrongState,       // the call is not allowed now
  Unsupported,      // the feature is not available in this build or on this scene
  Device,           // a haptic device failed
  Internal,         // a bug in libmica
  Diverged,         // a replay did not reproduce its recording
  Truncated         // a recording ends before its end entry: it was cut short
};

class Error : public std::runtime_error {
 public:
  Error(Errc code, const std::string& message) : std::runtime_error(message), code_(code) {}
  Errc code() const { return code_; }

 private:
  Errc code_;
};

[[noreturn]] inline void fail(Errc code, const std::string& message) { throw Error(code, message); }

// A value as a message quotes it: the shortest text that reads back as the same double ("1e+300", "0.5").
inline std::string number_text(double value) {
  char text[32];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value || value != value) break;
  }
  return text;
}

}  // namespace mica
