// Loading a mesh file: choose the reader from the extension, read whole files into memory.
#include "mesh/mesh_io.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "core/error.hpp"

namespace mica {
namespace detail {

// The whole file as text; Errc::Io naming the path and the system's reason on failure.
// (Shared by the readers, which declare it themselves: there is no private header for it.)
std::string read_text_file(const std::string& path) {
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  errno = 0;
  const std::unique_ptr<std::FILE, Closer> file(std::fopen(path.c_str(), "rb"));
  if (!file) fail(Errc::Io, path + ": cannot open: " + std::strerror(errno));
  std::string text;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) text.append(buffer, n);
  // Opening a directory succeeds; reading it fails with EISDIR.
  if (std::ferror(file.get())) fail(Errc::Io, path + ": cannot read: " + std::strerror(errno));
  return text;
}

}  // namespace detail

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

TetMesh load_mesh(const std::string& path) {
  if (ends_with(path, ".msh")) return read_gmsh(path);
  if (ends_with(path, ".node") || ends_with(path, ".ele")) return read_tetgen(path);
  fail(Errc::Unsupported,
       path +
           ": unsupported mesh file extension (accepted: .msh for Gmsh, .node or .ele for TetGen)");
}

}  // namespace mica
