// SPDX-License-Identifier: Apache-2.0
// Loading a mesh file: choose the reader from the extension, read whole files into memory,
// and the other helpers the readers share (declared in text_scanner.hpp).
#include "mesh/mesh_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "mesh/text_scanner.hpp"

namespace mica {
namespace detail {

std::string read_text_file(const std::string& path, std::size_t max_bytes) {
  // Opened without blocking (a FIFO would wait for a writer in open), then only a regular file
  // is read: a FIFO, a device (/dev/zero never ends), a socket or a directory is refused, and so
  // is a file above the cap (checked before reading, and again while reading: it may grow).
  errno = 0;
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) fail(Errc::Io, path + ": cannot open: " + std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) fail(Errc::Io, path + ": cannot read: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) fail(Errc::Io, path + ": cannot read: it is a directory");
  if (!S_ISREG(st.st_mode))
    fail(Errc::Io, path + ": not a regular file (a FIFO, socket or device): libmica reads only regular files");
  const auto too_large = [&] {
    fail(Errc::Io, path + ": the file is larger than " + std::to_string(max_bytes) +
                       " bytes, the most libmica reads (a mesh of some million tetrahedra)");
  };
  if (st.st_size < 0 || std::uint64_t(st.st_size) > max_bytes) too_large();
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  std::string text;
  text.reserve(std::size_t(st.st_size));
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(Errc::Io, path + ": cannot read: " + std::strerror(errno));
    if (n == 0) break;
    if (text.size() + std::size_t(n) > max_bytes) too_large();
    text.append(buffer, std::size_t(n));
  }
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
