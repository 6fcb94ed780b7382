// SPDX-License-Identifier: Apache-2.0
// Shared by the libFuzzer targets: what counts as a clean rejection, what counts as a bug.
//
// A loader given any bytes must either return a mesh that keeps its documented promises or
// throw mica::Error. Everything else is a bug and is turned into a crash that libFuzzer
// records: a sanitizer report, any other exception (std::bad_alloc, std::out_of_range, ...),
// Errc::Internal, a parse error that does not name the file and line, or a returned mesh or
// FEM model that breaks an invariant (index out of range, non-finite value).
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>
#include <typeinfo>

#include "core/error.hpp"
#include "mesh/tet_mesh.hpp"

namespace mica_fuzz {

// Prints why the input is a bug and aborts, so libFuzzer saves it as a crash artifact.
[[noreturn]] inline void bug(const std::string& what) {
  std::fprintf(stderr, "\n==== mica fuzz: BUG: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

inline bool starts_with(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}

// The bytes as text: std::string_view does not stop at NUL bytes, and neither do the parsers.
inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// TetGen input from one buffer: the .node text up to the first NUL byte, the .ele text after.
struct TetgenTexts {
  std::string_view node;
  std::string_view ele;
};
inline TetgenTexts split_tetgen(std::string_view text) {
  const std::size_t nul = text.find('\0');
  if (nul == std::string_view::npos) return {text, {}};
  return {text.substr(0, nul), text.substr(nul + 1)};
}

// Runs `f`; a mica::Error is a clean rejection, handed to `check_error` (which may call bug());
// every other exception is a bug.
template <class F, class CheckError>
void run_guarded(F&& f, CheckError&& check_error) {
  try {
    f();
  } catch (const mica::Error& e) {
    if (e.code() == mica::Errc::Internal) bug(std::string("Errc::Internal: ") + e.what());
    check_error(e);
  } catch (const std::exception& e) {
    bug(std::string("uncaught ") + typeid(e).name() + ": " + e.what());
  } catch (...) {
    bug("uncaught exception of unknown type");
  }
}

// Parser errors come from LineReader::expected: "<name>: line <N>: expected ..." with code
// Parse or Unsupported (mesh_io.hpp: "Every parse error names the file, the line and what was
// expected"). `names` are the file names the parser was given.
template <class... Names>
void check_parse_error(const mica::Error& e, const Names&... names) {
  const std::string_view msg = e.what();
  if (e.code() != mica::Errc::Parse && e.code() != mica::Errc::Unsupported) {
    bug("parser threw a code other than Parse/Unsupported: " + std::string(msg));
  }
  const bool named = (... || starts_with(msg, std::string(names) + ": line "));
  if (!named || msg.find(": expected ") == std::string_view::npos) {
    bug("parse error without '<file>: line <N>: expected ...': " + std::string(msg));
  }
}

// What a parser promises of a mesh it returns (mesh_io.hpp): at least one tet, nodes numbered
// 0..n-1 with every node used (unused ones dropped), finite coordinates. Repeated nodes in one
// tet and bad volumes are left to validate_topology / check_rest_quality.
inline void check_parsed_mesh(const mica::TetMesh& mesh) {
  if (mesh.tets.empty()) bug("parser returned a mesh without tetrahedra");
  const auto n = static_cast<std::int64_t>(mesh.nodes.size());
  std::string used(mesh.nodes.size(), '\0');
  for (const mica::Tet& t : mesh.tets) {
    for (const std::int32_t v : t) {
      if (v < 0 || v >= n) bug("parser returned a tet index out of range: " + std::to_string(v));
      used[static_cast<std::size_t>(v)] = 1;
    }
  }
  if (used.find('\0') != std::string::npos) bug("parser returned an unused node");
  for (const mica::Vec3& p : mesh.nodes) {
    if (!p.allFinite()) bug("parser returned a non-finite coordinate");
  }
}

}  // namespace mica_fuzz
