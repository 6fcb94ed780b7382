// SPDX-License-Identifier: Apache-2.0
// Private to the mesh readers: walking a text file line by line and token by token, with
// errors of the shape "<name>: line <N>: expected <what>, got '<token>'" (Errc::Parse unless
// told otherwise), plus the file and mesh helpers the readers share.
#pragma once
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "mesh/mesh_io.hpp"
#include "mesh/tet_mesh.hpp"

namespace mica::detail {

// ---- Shared by the readers, defined in mesh_io.cpp.

// The whole file as text; Errc::Io naming the path and the system's reason on failure, for a
// path that is not a regular file (a FIFO, a device such as /dev/zero, a directory), and for a
// file above max_bytes.
std::string read_text_file(const std::string& path, std::size_t max_bytes = kMaxMeshFileBytes);

// True if `path` ends with `extension` (such as ".msh"), ignoring ASCII case.
bool has_extension(std::string_view path, std::string_view extension);

// The nodes the tets use, renumbered 0..n-1 in their order in `nodes`; the tets index `nodes`.
TetMesh drop_unused_nodes(const Vec3List& nodes, const std::vector<Tet>& tets);

// ---- The scanner, defined in text_scanner.cpp.

// The text up to the first blank (space, tab, CR, VT or FF).
std::string_view first_token(std::string_view line);

// Walks the text one line at a time, trimmed, comments removed and blank lines skipped, and
// formats errors with the line number.
class LineReader {
 public:
  // `comment`, if not empty, starts a comment that runs to the end of its line.
  // `text` and `name` must outlive the reader.
  LineReader(std::string_view text, const std::string& name, std::string_view comment = {});

  // Moves to the next line with content; false at the end of the text, where the line number
  // stays on the last line so that messages point at where the text stopped.
  bool advance();

  // Like advance(), but the end of the text is an error: `what` was expected there.
  std::string_view next(std::string_view what);

  // The rest of the text must be comments and blank lines.
  void expect_end(std::string_view what);

  // The current line; empty at the end of the text.
  std::string_view line() const { return line_; }

  // How many of `n` records to reserve room for: no more than the rest of the text can
  // describe at `min_record_bytes` each, so a lying count fails at the end, unallocated.
  std::size_t reservable(std::int64_t n, std::int64_t min_record_bytes) const;

  [[noreturn]] void expected(std::string_view what, std::string_view got,
                             Errc code = Errc::Parse) const;

 private:
  std::string_view text_;
  const std::string& name_;
  std::string_view comment_;
  std::size_t pos_ = 0;
  std::int64_t number_ = 0;
  std::string_view line_;
};

// Reads the whitespace-separated fields of one line, reporting errors on that line.
class Fields {
 public:
  Fields(const LineReader& at, std::string_view line) : at_(at), rest_(line) {}

  std::string_view token(std::string_view what);

  // The token read last, for messages about it.
  std::string_view last() const { return last_; }

  // An integer in [lo, hi]; anything else is reported as not being `what`.
  std::int64_t integer(std::string_view what,
                       std::int64_t lo = std::numeric_limits<std::int64_t>::min(),
                       std::int64_t hi = std::numeric_limits<std::int64_t>::max());

  // A record count in [0, max], small enough to index with int32 by default.
  std::int64_t count(std::string_view what,
                     std::int64_t max = std::numeric_limits<std::int32_t>::max()) {
    return integer(what, 0, max);
  }

  // A finite real number, read the same in every locale.
  double real(std::string_view what);

  // Nothing may follow on the line.
  void finish();

 private:
  const LineReader& at_;
  std::string_view rest_;
  std::string_view last_;
};

}  // namespace mica::detail
