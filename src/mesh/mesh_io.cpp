// Loading a mesh file: choose the reader from the extension, read whole files into memory,
// and the other helpers the readers share (declared in text_scanner.hpp).
#include "mesh/mesh_io.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "mesh/text_scanner.hpp"

namespace mica {
namespace detail {

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

bool has_extension(std::string_view path, std::string_view extension) {
  if (path.size() < extension.size()) return false;
  const std::string_view tail = path.substr(path.size() - extension.size());
  const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
  for (std::size_t i = 0; i < tail.size(); ++i) {
    if (lower(tail[i]) != lower(extension[i])) return false;
  }
  return true;
}

TetMesh drop_unused_nodes(const Vec3List& nodes, const std::vector<Tet>& tets) {
  std::vector<std::int32_t> new_index(nodes.size(), -1);
  for (const Tet& t : tets) {
    for (std::int32_t v : t) new_index[static_cast<std::size_t>(v)] = 0;
  }
  TetMesh mesh;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (new_index[i] < 0) continue;
    new_index[i] = static_cast<std::int32_t>(mesh.nodes.size());
    mesh.nodes.push_back(nodes[i]);
  }
  mesh.tets.reserve(tets.size());
  for (const Tet& t : tets) {
    Tet renumbered;
    for (std::size_t k = 0; k < 4; ++k) renumbered[k] = new_index[static_cast<std::size_t>(t[k])];
    mesh.tets.push_back(renumbered);
  }
  return mesh;
}

}  // namespace detail

TetMesh load_mesh(const std::string& path) {
  if (detail::has_extension(path, ".msh")) return read_gmsh(path);
  if (detail::has_extension(path, ".node") || detail::has_extension(path, ".ele")) {
    return read_tetgen(path);
  }
  fail(Errc::Unsupported,
       path +
           ": unsupported mesh file extension (accepted: .msh for Gmsh, .node or .ele for TetGen)");
}

}  // namespace mica
