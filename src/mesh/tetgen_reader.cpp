// SPDX-License-Identifier: Apache-2.0
// TetGen .node/.ele reader. '#' starts a comment anywhere on a line; blank lines are skipped.
// The first point index of the .node file (0 or 1) sets the numbering of both files. Points
// are renumbered 0..n-1 in file order; points that no tetrahedron uses (such as the edge
// nodes of 10-node tets) are dropped. A tet's first attribute is its region (tetgen -A) when
// every tet's first attribute is an integer in int32; otherwise every region is 0.
// Memory reserved for a count read from a file is capped by what the bytes left can hold, so a
// lying header fails at the end of the text, unallocated.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "mesh/mesh_io.hpp"
#include "mesh/text_scanner.hpp"

namespace mica {
namespace {

using detail::Fields;
using detail::LineReader;

constexpr std::int64_t kMinPointBytes = 8;  // shortest point line: "1 0 0 0\n"
constexpr std::int64_t kMinTetBytes = 10;   // shortest tetrahedron line: "1 1 2 3 4\n"
constexpr std::int64_t kMaxCount = std::numeric_limits<std::int32_t>::max();

struct PointList {
  Vec3List points;
  std::int64_t first_index = 0;  // 0 or 1
};

// .node: "npoints dim nattr nmarkers", then "index x y z [attributes] [marker]" per point.
PointList read_points(std::string_view text, const std::string& name) {
  LineReader lines(text, name, "#");
  Fields header(lines, lines.next("a header 'npoints dim nattr nmarkers'"));
  const std::int64_t n = header.integer("a positive point count", 1, kMaxCount);
  if (header.integer("a dimension") != 3) {
    lines.expected("dimension 3", header.last(), Errc::Unsupported);
  }
  const std::int64_t num_attributes = header.integer("an attribute count", 0, kMaxCount);
  const std::int64_t num_markers = header.integer("a boundary marker count 0 or 1", 0, 1);
  header.finish();

  PointList out;
  out.points.reserve(lines.reservable(n, kMinPointBytes));
  for (std::int64_t i = 0; i < n; ++i) {
    Fields f(lines, lines.next("a point line 'index x y z'"));
    if (i == 0) {
      out.first_index = f.integer("a first point index 0 or 1", 0, 1);
    } else {
      const std::int64_t index = out.first_index + i;
      f.integer("point index " + std::to_string(index), index, index);
    }
    const double x = f.real("a finite x coordinate");
    const double y = f.real("a finite y coordinate");
    const double z = f.real("a finite z coordinate");
    out.points.emplace_back(x, y, z);
    for (std::int64_t a = 0; a < num_attributes; ++a) f.real("a finite point attribute");
    if (num_markers == 1) f.integer("a boundary marker");
    f.finish();
  }
  lines.expect_end("end of file after " + std::to_string(n) + " points");
  return out;
}

// .ele: "ntets nodes_per_tet nattr", then "index n1 n2 n3 n4 [6 more] [attributes]" per tet.
// `first_attribute` receives each tet's first attribute (empty when there are none).
std::vector<Tet> read_tets(std::string_view text, const std::string& name,
                           const PointList& points, std::vector<double>& first_attribute) {
  LineReader lines(text, name, "#");
  Fields header(lines, lines.next("a header 'ntets nodes_per_tet nattr'"));
  const std::int64_t n = header.integer("a positive tetrahedron count", 1, kMaxCount);
  const std::int64_t nodes_per_tet = header.integer("4 or 10 nodes per tetrahedron", 4, 10);
  if (nodes_per_tet != 4 && nodes_per_tet != 10) {
    lines.expected("4 or 10 nodes per tetrahedron", header.last());
  }
  const std::int64_t num_attributes = header.integer("an attribute count", 0, kMaxCount);
  header.finish();

  const std::int64_t lo = points.first_index;
  const std::int64_t hi = lo + static_cast<std::int64_t>(points.points.size()) - 1;
  const std::string node_what =
      "a point index from " + std::to_string(lo) + " to " + std::to_string(hi);
  std::vector<Tet> tets;
  tets.reserve(lines.reservable(n, kMinTetBytes));
  for (std::int64_t i = 0; i < n; ++i) {
    Fields f(lines, lines.next("a tetrahedron line 'index n1 n2 n3 n4'"));
    const std::int64_t index = lo + i;
    f.integer("tetrahedron index " + std::to_string(index), index, index);
    // TetGen's tets follow the right-hand rule, det[X1-X0,X2-X0,X3-X0] > 0 as ours, so no swap
    // (TetGen 1.5 tetgen.cxx: reconstructmesh swaps corners 0,1 when orient3d > 0; -R reverses).
    Tet t;
    for (auto& v : t) v = static_cast<std::int32_t>(f.integer(node_what, lo, hi) - lo);
    for (std::int64_t k = 4; k < nodes_per_tet; ++k) {
      f.integer(node_what, lo, hi);  // edge midpoints
    }
    for (std::int64_t a = 0; a < num_attributes; ++a) {
      const double value = f.real("a finite tetrahedron attribute");
      if (a == 0) first_attribute.push_back(value);
    }
    f.finish();
    tets.push_back(t);
  }
  lines.expect_end("end of file after " + std::to_string(n) + " tetrahedra");
  return tets;
}

}  // namespace

TetMesh parse_tetgen(std::string_view node_text, std::string_view ele_text,
                     const std::string& node_name, const std::string& ele_name) {
  const PointList points = read_points(node_text, node_name);
  std::vector<double> attribute;
  TetMesh mesh = detail::drop_unused_nodes(points.points, read_tets(ele_text, ele_name, points, attribute));
  const auto is_region = [](double a) {
    return a == std::floor(a) && a >= std::numeric_limits<std::int32_t>::min() &&
           a <= std::numeric_limits<std::int32_t>::max();
  };
  if (!attribute.empty() && std::all_of(attribute.begin(), attribute.end(), is_region))
    for (double a : attribute) mesh.regions.push_back(static_cast<std::int32_t>(a));
  return mesh;
}

TetMesh read_tetgen(const std::string& path) {
  // Suffixes match in any case; a suffix not in lower case pairs with an upper-case sibling,
  // so cube.NODE goes with cube.ELE.
  std::string stem = path;
  bool upper = false;
  for (const std::string_view suffix : {".node", ".ele"}) {
    if (!detail::has_extension(path, suffix)) continue;
    stem.resize(path.size() - suffix.size());
    upper = path.compare(stem.size(), suffix.size(), suffix) != 0;
  }
  const std::string node_path = upper ? stem + ".NODE" : stem + ".node";
  const std::string ele_path = upper ? stem + ".ELE" : stem + ".ele";
  const std::string node_text = detail::read_text_file(node_path);
  const std::string ele_text = detail::read_text_file(ele_path);
  return parse_tetgen(node_text, ele_text, node_path, ele_path);
}

}  // namespace mica
