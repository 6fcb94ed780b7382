// SPDX-License-Identifier: Apache-2.0
#include "mesh/tet_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace mica {

namespace {

// Outward faces of a positively oriented tet (a, b, c, d).
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct TetFace {
  Tri nodes;    // sorted: equal for the two tets that share the face
  int32_t tet;
  int32_t face;  // which of the tet's faces (kFace)
};

// Every tet's four faces, ordered by their sorted nodes and then by tet: the two sides of an
// interior face side by side. Placed by first node (counting), then sorted within each node's few:
// a sort of the whole took 2.6 ms on the nidus's 38672 faces, which a cut's rebuild does twice.
std::vector<TetFace> sorted_faces(const TetMesh& mesh) {
  std::vector<int32_t> start(mesh.nodes.size() + 1, 0);
  for (const Tet& t : mesh.tets)
    for (const auto& f : kFace) ++start[size_t(std::min({t[f[0]], t[f[1]], t[f[2]]})) + 1];
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<TetFace> faces(4 * mesh.tets.size());
  std::vector<int32_t> next(start.begin(), start.end() - 1);
  for (size_t e = 0; e < mesh.tets.size(); ++e)
    for (int32_t f = 0; f < 4; ++f) {
      const Tet& t = mesh.tets[e];
      TetFace face{{t[kFace[f][0]], t[kFace[f][1]], t[kFace[f][2]]}, int32_t(e), f};
      std::sort(face.nodes.begin(), face.nodes.end());
      faces[size_t(next[size_t(face.nodes[0])]++)] = face;
    }
  const auto before = [](const TetFace& a, const TetFace& b) {
    return a.nodes != b.nodes ? a.nodes < b.nodes : a.tet != b.tet ? a.tet < b.tet : a.face < b.face;
  };
  for (size_t i = 0; i + 1 < start.size(); ++i) std::sort(faces.begin() + start[i], faces.begin() + start[i + 1], before);
  return faces;
}

}  // namespace

double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

void validate_topology(const TetMesh& mesh, const std::string& source) {
  const auto n = int64_t(mesh.nodes.size());
  if (mesh.tets.empty()) fail(Errc::BadMesh, source + ": the mesh has no tetrahedra");
  if (!mesh.regions.empty() && mesh.regions.size() != mesh.tets.size())
    fail(Errc::InvalidArgument, source + ": " + std::to_string(mesh.regions.size()) + " regions for " +
                                    std::to_string(mesh.tets.size()) + " tets");
  for (int64_t i = 0; i < n; ++i) {
    if (!mesh.nodes[i].allFinite())
      fail(Errc::InvalidArgument, source + ": node " + std::to_string(i) + " has a non-finite coordinate");
  }
  std::vector<uint8_t> used(mesh.nodes.size(), 0);
  for (size_t e = 0; e < mesh.tets.size(); ++e) {
    const Tet& t = mesh.tets[e];
    for (int a = 0; a < 4; ++a) {
      if (t[a] < 0 || t[a] >= n)
        fail(Errc::OutOfRange, source + ": tet " + std::to_string(e) + " refers to node " +
                                   std::to_string(t[a]) + ", outside 0.." + std::to_string(n - 1));
      for (int b = 0; b < a; ++b)
        if (t[a] == t[b])
          fail(Errc::BadMesh, source + ": tet " + std::to_string(e) + " repeats node " + std::to_string(t[a]));
      used[t[a]] = 1;
    }
  }
  // A node outside every tet has no mass: the system would be singular.
  const auto unused = std::find(used.begin(), used.end(), 0);
  if (unused != used.end())
    fail(Errc::BadMesh, source + ": node " + std::to_string(unused - used.begin()) + " belongs to no tet");
  // Faces: in a valid mesh each is shared by at most two tets, and some belong to one (the
  // surface, which collision and contact need). A tet listed twice shares all four faces with
  // its copy and leaves no surface at all.
  const std::vector<TetFace> faces = sorted_faces(mesh);
  bool boundary = false;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].nodes == faces[i].nodes) ++j;
    if (j - i == 1) boundary = true;
    if (j - i > 1) {
      Tet a = mesh.tets[size_t(faces[i].tet)], b = mesh.tets[size_t(faces[i + 1].tet)];
      std::sort(a.begin(), a.end());
      std::sort(b.begin(), b.end());
      if (a == b)
        fail(Errc::BadMesh, source + ": tet " + std::to_string(faces[i + 1].tet) + " has the same four nodes as tet " +
                                std::to_string(faces[i].tet) + " (a duplicate element)");
    }
    if (j - i > 2)
      fail(Errc::BadMesh, source + ": the face of nodes " + std::to_string(faces[i].nodes[0]) + ", " +
                              std::to_string(faces[i].nodes[1]) + ", " + std::to_string(faces[i].nodes[2]) +
                              " belongs to " + std::to_string(j - i) + " tets (at most two may share a face), tets " +
                              std::to_string(faces[i].tet) + ", " + std::to_string(faces[i + 1].tet) + ", " +
                              std::to_string(faces[i + 2].tet));
    i = j;
  }
  if (!boundary) fail(Errc::BadMesh, source + ": the mesh has no boundary surface (every face is shared by two tets)");
}

QualityReport check_rest_quality(const TetMesh& mesh, const std::string& source, double sliver_aspect) {
  QualityReport report;
  report.min_volume = HUGE_VAL;
  for (size_t e = 0; e < mesh.tets.size(); ++e) {
    const Tet& t = mesh.tets[e];
    const Vec3 *p[4] = {&mesh.nodes[t[0]], &mesh.nodes[t[1]], &mesh.nodes[t[2]], &mesh.nodes[t[3]]};
    double longest = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (*p[a] - *p[b]).norm());
    const double v = signed_volume(*p[0], *p[1], *p[2], *p[3]);
    // Volume relative to the longest edge's cube: scale-free, 1/(6 sqrt 2) for a regular tet.
    const double relative = v / (longest * longest * longest);
    if (!(relative > 1e-14)) {
      const char* what = relative < -1e-14 ? "negative volume (inverted: swap two nodes)" : "zero volume";
      fail(Errc::BadMesh, source + ": tet " + std::to_string(e) + " has " + what + " (" +
                              std::to_string(v) + " m^3)");
    }
    const double aspect = 1.0 / (6.0 * std::sqrt(2.0) * relative);  // 1 for a regular tet
    report.min_volume = std::min(report.min_volume, v);
    report.worst_aspect = std::max(report.worst_aspect, aspect);
    if (aspect > sliver_aspect) report.slivers.push_back(int32_t(e));
  }
  return report;
}

std::vector<Tri> extract_surface(const TetMesh& mesh) {
  const std::vector<TetFace> faces = sorted_faces(mesh);
  std::vector<Tri> surface;
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].nodes == faces[i].nodes) ++j;
    if (j - i == 1) {
      const Tet& t = mesh.tets[size_t(faces[i].tet)];
      const int* f = kFace[faces[i].face];
      surface.push_back({t[f[0]], t[f[1]], t[f[2]]});
    }
    i = j;
  }
  return surface;
}

std::vector<int32_t> surface_nodes(const std::vector<Tri>& surface) {
  std::vector<int32_t> nodes;
  nodes.reserve(3 * surface.size());
  for (const Tri& t : surface) nodes.insert(nodes.end(), t.begin(), t.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

TetMesh make_box_grid(const Vec3& lo, const Vec3& hi, const std::array<int32_t, 3>& cells,
                      int32_t tets_per_cell) {
  if (tets_per_cell != 5 && tets_per_cell != 6)
    fail(Errc::InvalidArgument, "box: tets_per_cell must be 5 or 6, got " + std::to_string(tets_per_cell));
  if (!lo.allFinite() || !hi.allFinite()) fail(Errc::InvalidArgument, "box: corners must be finite");
  for (int k = 0; k < 3; ++k) {
    if (cells[k] < 1) fail(Errc::InvalidArgument, "box: cells[" + std::to_string(k) + "] must be >= 1, got " + std::to_string(cells[k]));
    if (!(hi[k] > lo[k]))
      fail(Errc::InvalidArgument, "box: hi[" + std::to_string(k) + "] must exceed lo[" + std::to_string(k) + "], got " +
                                      number_text(hi[k]) + " and " + number_text(lo[k]));
  }
  const int64_t nx = cells[0], ny = cells[1], nz = cells[2];
  // Checked in floating point first: the integer products can overflow 64 bits.
  const double tets_wanted = double(nx) * double(ny) * double(nz) * tets_per_cell;
  if (tets_wanted > double(INT32_MAX / 4))
    fail(Errc::InvalidArgument, "box: " + std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz) +
                                    " cells is more than one body can hold");
  const int64_t node_count = (nx + 1) * (ny + 1) * (nz + 1);
  const int64_t tet_count = nx * ny * nz * tets_per_cell;

  TetMesh mesh;
  mesh.nodes.reserve(size_t(node_count));
  // The last layer gets hi exactly, so faces select cleanly by plane.
  auto coord = [&](int axis, int64_t i, int64_t n) {
    return i == n ? hi[axis] : lo[axis] + (hi[axis] - lo[axis]) * double(i) / double(n);
  };
  for (int64_t k = 0; k <= nz; ++k)
    for (int64_t j = 0; j <= ny; ++j)
      for (int64_t i = 0; i <= nx; ++i)
        mesh.nodes.emplace_back(coord(0, i, nx), coord(1, j, ny), coord(2, k, nz));
  auto id = [&](int64_t i, int64_t j, int64_t k) { return int32_t(i + (nx + 1) * (j + (ny + 1) * k)); };

  mesh.tets.reserve(size_t(tet_count));
  for (int64_t k = 0; k < nz; ++k)
    for (int64_t j = 0; j < ny; ++j)
      for (int64_t i = 0; i < nx; ++i) {
        int32_t c[8];  // corner (dx, dy, dz) at index dx + 2 dy + 4 dz
        for (int q = 0; q < 8; ++q) c[q] = id(i + (q & 1), j + ((q >> 1) & 1), k + ((q >> 2) & 1));
        auto add = [&](int a, int b, int d, int e) {
          Tet t{c[a], c[b], c[d], c[e]};
          const Vec3 *p = mesh.nodes.data();
          if (signed_volume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]) < 0) std::swap(t[2], t[3]);
          mesh.tets.push_back(t);
        };
        if (tets_per_cell == 6) {
          // Kuhn split along the 0-7 diagonal: conforming because every cell uses it.
          static const int kPaths[6][2] = {{1, 3}, {1, 5}, {2, 3}, {2, 6}, {4, 5}, {4, 6}};
          for (const auto& p : kPaths) add(0, p[0], p[1], 7);
        } else {
          // Four corner tets and a central one; alternating parity keeps face diagonals matched.
          const bool even = ((i + j + k) & 1) == 0;
          const int corners[4] = {even ? 0 : 1, even ? 3 : 2, even ? 5 : 4, even ? 6 : 7};
          for (int q : corners) add(q, q ^ 1, q ^ 2, q ^ 4);
          add(corners[0] ^ 1, corners[1] ^ 1, corners[2] ^ 1, corners[3] ^ 1);
        }
      }
  return mesh;
}

}  // namespace mica
