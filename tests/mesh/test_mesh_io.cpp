// SPDX-License-Identifier: Apache-2.0
// Mesh files in and out: Gmsh 2.2 / 4.1 and TetGen readers, their error messages, load_mesh,
// and the VTK legacy writer read back by a small parser.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <locale>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "mesh/mesh_io.hpp"
#include "test_util.hpp"

using mica::Errc;
using mica::TetMesh;
using mica::Vec3;

namespace {

// ---------------------------------------------------------------- sample texts

// Five used nodes listed out of tag order, one unused node (50), and elements the reader
// ignores (a point and a triangle). Line numbers are on the right.
const std::string kGmsh22 =
    "$MeshFormat\n"            // 1
    "2.2 0 8\n"                // 2
    "$EndMeshFormat\n"         // 3
    "$PhysicalNames\n"         // 4
    "1\n"                      // 5
    "3 1 \"body\"\n"           // 6
    "$EndPhysicalNames\n"      // 7
    "$Nodes\n"                 // 8
    "6\n"                      // 9
    "30 0 1 0\n"               // 10
    "10 0 0 0\n"               // 11
    "50 5 5 5\n"               // 12
    "20 1 0 0\n"               // 13
    "60 1 1 1\n"               // 14
    "40 0 0 1\n"               // 15
    "$EndNodes\n"              // 16
    "$Elements\n"              // 17
    "4\n"                      // 18
    "1 15 2 0 1 50\n"          // 19
    "2 2 2 0 1 10 20 30\n"     // 20
    "3 4 2 1 1 10 20 30 40\n"  // 21
    "4 4 2 1 1 20 60 30 40\n"  // 22
    "$EndElements\n";          // 23

// The same mesh in 4.1: nodes in three entity blocks (the last one parametric, whose u v
// values are ignored), the same node order, elements in three blocks.
const std::string kGmsh41 =
    "$MeshFormat\n"          // 1
    "4.1 0 8\n"              // 2
    "$EndMeshFormat\n"       // 3
    "$PhysicalNames\n"       // 4
    "1\n"                    // 5
    "3 1 \"body\"\n"         // 6
    "$EndPhysicalNames\n"    // 7
    "$Entities\n"            // 8
    "1 0 0 1\n"              // 9
    "1 5 5 5 0\n"            // 10
    "1 0 0 0 1 1 1 1 1 0\n"  // 11
    "$EndEntities\n"         // 12
    "$Nodes\n"               // 13
    "3 6 10 60\n"            // 14
    "3 1 0 2\n"              // 15
    "30\n"                   // 16
    "10\n"                   // 17
    "0 1 0\n"                // 18
    "0 0 0\n"                // 19
    "0 1 0 1\n"              // 20
    "50\n"                   // 21
    "5 5 5\n"                // 22
    "2 1 1 3\n"              // 23
    "20\n"                   // 24
    "60\n"                   // 25
    "40\n"                   // 26
    "1 0 0 0.25 0.5\n"       // 27
    "1 1 1 0.5 0.5\n"        // 28
    "0 0 1 0.75 0.5\n"       // 29
    "$EndNodes\n"            // 30
    "$Elements\n"            // 31
    "3 4 1 4\n"              // 32
    "0 1 15 1\n"             // 33
    "1 50\n"                 // 34
    "2 1 2 1\n"              // 35
    "2 10 20 30\n"           // 36
    "3 1 4 2\n"              // 37
    "3 10 20 30 40\n"        // 38
    "4 20 60 30 40\n"        // 39
    "$EndElements\n";        // 40

// The mesh both Gmsh texts describe: used nodes in file order 30, 10, 20, 60, 40.
TetMesh expected_gmsh_mesh() {
  TetMesh m;
  m.nodes = {Vec3(0, 1, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 1), Vec3(0, 0, 1)};
  m.tets = {{1, 2, 0, 4}, {2, 3, 0, 4}};
  return m;
}

// TetGen, 1-based, with comments, a blank line, one attribute and boundary markers.
const std::string kNode1 =
    "# five points\n"                           // 1
    "5 3 1 1   # npoints dim nattr nmarkers\n"  // 2
    "\n"                                        // 3
    "1 0 0 0 0.5 1\n"                           // 4
    "2 1 0 0 0.5 1\n"                           // 5
    "3 0 1 0 0.5 0   # on the boundary\n"       // 6
    "4 0 0 1 0.5 1\n"                           // 7
    "5 1 1 1 0.5 1\n";                          // 8
const std::string kEle1 =
    "2 4 1\n"         // 1
    "# first tet\n"   // 2
    "1 1 2 3 4 7\n"   // 3
    "2 2 5 3 4 7\n";  // 4

// The same mesh, 0-based, no attributes or markers.
const std::string kNode0 = "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n";
const std::string kEle0 = "2 4 0\n0 0 1 2 3\n1 1 4 2 3\n";

TetMesh expected_tetgen_mesh() {
  TetMesh m;
  m.nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1)};
  m.tets = {{0, 1, 2, 3}, {1, 4, 2, 3}};
  return m;
}

// ---------------------------------------------------------------- helpers

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    lines.push_back(text.substr(pos, end - pos));
    pos = end + 1;
  }
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

// `text` with its 1-based line `n` replaced by `line`.
std::string with_line(const std::string& text, int n, const std::string& line) {
  std::vector<std::string> lines = split_lines(text);
  lines.at(static_cast<std::size_t>(n - 1)) = line;
  return join_lines(lines);
}

std::string without_line(const std::string& text, int n) {
  std::vector<std::string> lines = split_lines(text);
  lines.erase(lines.begin() + (n - 1));
  return join_lines(lines);
}

// The first `n` lines of `text`.
std::string first_lines(const std::string& text, int n) {
  std::vector<std::string> lines = split_lines(text);
  lines.resize(static_cast<std::size_t>(n));
  return join_lines(lines);
}

// Runs `f`, which must throw mica::Error with `code` and a message containing `text`.
template <class F>
void expect_error(F f, Errc code, const char* text) {
  std::string message;
  bool thrown = false;
  Errc got = Errc::Internal;
  try {
    f();
  } catch (const mica::Error& e) {
    thrown = true;
    got = e.code();
    message = e.what();
  }
  if (!thrown) fail_msg("no mica::Error thrown; wanted one saying \"%s\"", text);
  if (got != code) {
    fail_msg("error code %d, wanted %d; message \"%s\"", static_cast<int>(got),
             static_cast<int>(code), message.c_str());
  }
  if (message.find(text) == std::string::npos) {
    fail_msg("message \"%s\" does not contain \"%s\"", message.c_str(), text);
  }
}

void expect_gmsh_error(const std::string& text, Errc code, const char* message) {
  expect_error([&] { mica::parse_gmsh(text, "t.msh"); }, code, message);
}

void expect_tetgen_error(const std::string& node, const std::string& ele, Errc code,
                         const char* message) {
  expect_error([&] { mica::parse_tetgen(node, ele, "t.node", "t.ele"); }, code, message);
}

void assert_same_mesh(const TetMesh& a, const TetMesh& b) {
  assert_int_equal(a.nodes.size(), b.nodes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    if (a.nodes[i] != b.nodes[i]) {
      fail_msg("node %zu: (%.17g %.17g %.17g) vs (%.17g %.17g %.17g)", i, a.nodes[i].x(),
               a.nodes[i].y(), a.nodes[i].z(), b.nodes[i].x(), b.nodes[i].y(), b.nodes[i].z());
    }
  }
  assert_int_equal(a.tets.size(), b.tets.size());
  for (std::size_t e = 0; e < a.tets.size(); ++e) {
    const mica::Tet& s = a.tets[e];
    const mica::Tet& t = b.tets[e];
    if (s != t) {
      fail_msg("tet %zu: {%d %d %d %d} vs {%d %d %d %d}", e, s[0], s[1], s[2], s[3], t[0], t[1],
               t[2], t[3]);
    }
  }
}

// det[X1-X0, X2-X0, X3-X0], computed here rather than taken from the library.
double six_volume(const TetMesh& m, const mica::Tet& t) {
  const Vec3& x0 = m.nodes[static_cast<std::size_t>(t[0])];
  const Vec3 a = m.nodes[static_cast<std::size_t>(t[1])] - x0;
  const Vec3 b = m.nodes[static_cast<std::size_t>(t[2])] - x0;
  const Vec3 c = m.nodes[static_cast<std::size_t>(t[3])] - x0;
  return a.dot(b.cross(c));
}

std::string data_path(const char* file) { return std::string(MICA_TEST_DATA_DIR) + "/" + file; }

// ---------------------------------------------------------------- Gmsh

void gmsh22_keeps_tets_and_renumbers_in_file_order(void**) {
  assert_same_mesh(mica::parse_gmsh(kGmsh22, "t.msh"), expected_gmsh_mesh());
}

void gmsh41_blocks_give_the_same_mesh_as_22(void**) {
  const TetMesh v41 = mica::parse_gmsh(kGmsh41, "t.msh");
  assert_same_mesh(v41, mica::parse_gmsh(kGmsh22, "t.msh"));
  assert_same_mesh(v41, expected_gmsh_mesh());
}

// The region of a tet: 2.2 its first tag, 4.1 the first physical tag of its volume entity.
void gmsh_keeps_each_tets_physical_tag(void**) {
  const std::vector<int32_t> one = {1, 1};
  assert_true(mica::parse_gmsh(kGmsh22, "t.msh").regions == one);
  assert_true(mica::parse_gmsh(kGmsh41, "t.msh").regions == one);
  // 2.2: tags per element, none at all for the second tet.
  std::string v22 = kGmsh22;
  v22.replace(v22.find("3 4 2 1 1 10"), 12, "3 4 2 7 1 10");
  v22.replace(v22.find("4 4 2 1 1 20"), 12, "4 4 0 20");
  assert_true(mica::parse_gmsh(v22, "t.msh").regions == std::vector<int32_t>({7, 0}));
  // 4.1: the volume has no physical tag, or another volume has one.
  std::string untagged = kGmsh41;
  untagged.replace(untagged.find("1 0 0 0 1 1 1 1 1 0"), 19, "1 0 0 0 1 1 1 0 0");
  assert_true(mica::parse_gmsh(untagged, "t.msh").regions == std::vector<int32_t>({0, 0}));
  std::string other = kGmsh41;
  other.replace(other.find("1 0 0 1\n"), 8, "1 0 0 2\n");
  other.replace(other.find("1 0 0 0 1 1 1 1 1 0"), 19, "1 0 0 0 1 1 1 1 -4 0\n2 0 0 0 1 1 1 1 12 0");
  assert_true(mica::parse_gmsh(other, "t.msh").regions == std::vector<int32_t>({-4, -4}));
  other.replace(other.find("3 1 4 2\n"), 8, "3 2 4 2\n");
  assert_true(mica::parse_gmsh(other, "t.msh").regions == std::vector<int32_t>({12, 12}));
}

void gmsh_accepts_crlf_and_blank_lines(void**) {
  std::string crlf;
  for (const std::string& line : split_lines(kGmsh22)) crlf += line + "\r\n\r\n";
  assert_same_mesh(mica::parse_gmsh(crlf, "t.msh"), expected_gmsh_mesh());
}

void gmsh_truncated_section(void**) {
  expect_gmsh_error(first_lines(kGmsh22, 13), Errc::Parse,
                    "t.msh: line 13: expected a node line 'tag x y z', got 'end of file'");
  expect_gmsh_error(with_line(first_lines(kGmsh22, 13), 13, "20 1 0"), Errc::Parse,
                    "t.msh: line 13: expected a finite z coordinate, got 'end of line'");
  expect_gmsh_error(without_line(kGmsh22, 7), Errc::Parse,  // $EndPhysicalNames missing
                    "t.msh: line 22: expected $EndPhysicalNames, got 'end of file'");
  expect_gmsh_error("", Errc::Parse, "t.msh: line 1: expected $MeshFormat, got 'end of file'");
}

void gmsh_missing_end_markers(void**) {
  expect_gmsh_error(without_line(kGmsh22, 16), Errc::Parse,
                    "t.msh: line 16: expected $EndNodes, got '$Elements'");
  expect_gmsh_error(without_line(kGmsh22, 23), Errc::Parse,
                    "t.msh: line 22: expected $EndElements, got 'end of file'");
  expect_gmsh_error(without_line(kGmsh22, 3), Errc::Parse,
                    "t.msh: line 3: expected $EndMeshFormat, got '$PhysicalNames'");
  expect_gmsh_error(without_line(kGmsh22, 1), Errc::Parse,
                    "t.msh: line 1: expected $MeshFormat, got '2.2'");
}

void gmsh_wrong_counts(void**) {
  expect_gmsh_error(with_line(kGmsh22, 9, "7"), Errc::Parse,
                    "t.msh: line 16: expected a node tag, got '$EndNodes'");
  expect_gmsh_error(with_line(kGmsh22, 9, "5"), Errc::Parse,
                    "t.msh: line 15: expected $EndNodes, got '40'");
  expect_gmsh_error(with_line(kGmsh22, 18, "3"), Errc::Parse,
                    "t.msh: line 22: expected $EndElements, got '4'");
  // 4.1: the header promises more nodes than the blocks hold, or a block more than the header.
  expect_gmsh_error(
      with_line(kGmsh41, 14, "3 7 10 60"), Errc::Parse,
      "t.msh: line 30: expected another node block (the header lists 7 nodes, the blocks 6), "
      "got '$EndNodes'");
  expect_gmsh_error(with_line(kGmsh41, 14, "3 5 10 60"), Errc::Parse,
                    "t.msh: line 23: expected a block node count within the $Nodes total, got '3'");
  expect_gmsh_error(
      with_line(kGmsh41, 32, "3 5 1 4"), Errc::Parse,
      "t.msh: line 40: expected another element block (the header lists 5 elements, the "
      "blocks 4), got '$EndElements'");
  expect_gmsh_error(with_line(kGmsh41, 14, "4 6 10 60"), Errc::Parse,
                    "t.msh: line 30: expected an entity dimension 0 to 3, got '$EndNodes'");
}

void gmsh_bad_tokens(void**) {
  expect_gmsh_error(with_line(kGmsh22, 13, "20 1 zero 0"), Errc::Parse,
                    "t.msh: line 13: expected a finite y coordinate, got 'zero'");
  expect_gmsh_error(with_line(kGmsh22, 13, "20 1 0 nan"), Errc::Parse,
                    "t.msh: line 13: expected a finite z coordinate, got 'nan'");
  expect_gmsh_error(with_line(kGmsh22, 13, "20 1e999 0 0"), Errc::Parse,
                    "t.msh: line 13: expected a finite x coordinate, got '1e999'");
  expect_gmsh_error(with_line(kGmsh22, 13, "2x0 1 0 0"), Errc::Parse,
                    "t.msh: line 13: expected a node tag, got '2x0'");
  expect_gmsh_error(with_line(kGmsh22, 13, "20 1 0 0 7"), Errc::Parse,
                    "t.msh: line 13: expected end of line, got '7'");
  expect_gmsh_error(with_line(kGmsh22, 21, "3 4 2 1 1 10 20 30"), Errc::Parse,
                    "t.msh: line 21: expected a node tag, got 'end of line'");
  expect_gmsh_error(with_line(kGmsh41, 27, "1 0 zero"), Errc::Parse,
                    "t.msh: line 27: expected a finite z coordinate, got 'zero'");
  expect_gmsh_error(with_line(kGmsh41, 15, "3 1 2 2"), Errc::Parse,
                    "t.msh: line 15: expected a parametric flag 0 or 1, got '2'");
  expect_gmsh_error(with_line(kGmsh22, 17, "hello"), Errc::Parse,
                    "t.msh: line 17: expected a section header such as $Nodes, got 'hello'");
}

void gmsh_unknown_or_repeated_node_tags(void**) {
  expect_gmsh_error(with_line(kGmsh22, 22, "4 4 2 1 1 20 60 30 99"), Errc::Parse,
                    "t.msh: line 22: expected a node tag listed in $Nodes, got '99'");
  expect_gmsh_error(with_line(kGmsh41, 39, "4 20 60 99 40"), Errc::Parse,
                    "t.msh: line 39: expected a node tag listed in $Nodes, got '99'");
  expect_gmsh_error(with_line(kGmsh22, 13, "10 1 0 0"), Errc::Parse,
                    "t.msh: line 13: expected a node tag not listed before, got '10'");
  expect_gmsh_error(with_line(kGmsh41, 25, "30"), Errc::Parse,
                    "t.msh: line 25: expected a node tag not listed before, got '30'");
}

void gmsh_binary_and_other_versions_are_unsupported(void**) {
  expect_gmsh_error(
      with_line(kGmsh22, 2, "2.2 1 8"), Errc::Unsupported,
      "t.msh: line 2: expected file type 0 (ASCII; binary .msh files are not supported), got '1'");
  expect_gmsh_error(with_line(kGmsh41, 2, "4.1 1 8"), Errc::Unsupported, "got '1'");
  expect_gmsh_error(with_line(kGmsh22, 2, "4.0 0 8"), Errc::Unsupported,
                    "t.msh: line 2: expected format version 2.2 or 4.1, got '4.0'");
  expect_gmsh_error(with_line(kGmsh22, 2, "3 0 8"), Errc::Unsupported, "got '3'");
}

void gmsh_without_tets_is_rejected(void**) {
  const std::string no_tets = with_line(without_line(without_line(kGmsh22, 22), 21), 18, "2");
  expect_gmsh_error(no_tets, Errc::Parse,
                    "t.msh: line 21: expected at least one 4-node tetrahedron (element type 4), "
                    "got 'end of file'");
}

void gmsh_huge_counts_fail_before_allocating(void**) {
  // A header may claim up to 2^31 - 1 records; only what the text can hold is reserved, so a
  // lying header ends at the end of the text (ASan would abort on a 48 GB reservation).
  const std::string tiny = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2147483647\n1 0 0 0\n";
  expect_gmsh_error(tiny, Errc::Parse,
                    "t.msh: line 6: expected a node line 'tag x y z', got 'end of file'");
  expect_gmsh_error(with_line(kGmsh22, 9, "3000000"), Errc::Parse,
                    "t.msh: line 16: expected a node tag, got '$EndNodes'");
  expect_gmsh_error(
      with_line(kGmsh41, 14, "1 2147483647 1 2147483647"), Errc::Parse,
      "t.msh: line 20: expected another node block (the header lists 2147483647 nodes, the "
      "blocks 2), got '0'");
  // Counts beyond int32 indices, negative or unreadable, are rejected where they stand.
  expect_gmsh_error(with_line(kGmsh22, 9, "2147483648"), Errc::Parse,
                    "t.msh: line 9: expected a node count, got '2147483648'");
  expect_gmsh_error(with_line(kGmsh22, 9, "-1"), Errc::Parse,
                    "t.msh: line 9: expected a node count, got '-1'");
  expect_gmsh_error(with_line(kGmsh22, 18, "99999999999999999999"), Errc::Parse,
                    "t.msh: line 18: expected an element count, got '99999999999999999999'");
  expect_gmsh_error(with_line(kGmsh22, 21, "3 4 2000000000 1 1 10 20 30 40"), Errc::Parse,
                    "t.msh: line 21: expected an element tag value, got 'end of line'");
}

// ---------------------------------------------------------------- TetGen

void tetgen_one_based_with_comments(void**) {
  assert_same_mesh(mica::parse_tetgen(kNode1, kEle1, "t.node", "t.ele"), expected_tetgen_mesh());
}

void tetgen_zero_based(void**) {
  assert_same_mesh(mica::parse_tetgen(kNode0, kEle0, "t.node", "t.ele"), expected_tetgen_mesh());
}

void tetgen_ten_node_tets_keep_their_corners(void**) {
  const std::string ele10 =
      "2 10 0\n"
      "1 1 2 3 4  2 3 4 5 5 5   # corners, then edge nodes (any valid indices here)\n"
      "2 2 5 3 4  1 1 1 1 1 1\n";
  assert_same_mesh(mica::parse_tetgen(kNode1, ele10, "t.node", "t.ele"), expected_tetgen_mesh());
}

void tetgen_keeps_file_orientation(void**) {
  // TetGen and libmica share the right-hand-rule orientation: a positive tet stays positive
  // and a negative one is passed through for the quality check to reject.
  const TetMesh m = mica::parse_tetgen(kNode0, "2 4 0\n0 0 1 2 3\n1 0 2 1 3\n", "t.node", "t.ele");
  assert_true(six_volume(m, m.tets[0]) > 0);
  assert_true(six_volume(m, m.tets[1]) < 0);
}

void tetgen_drops_unused_points_and_renumbers(void**) {
  // Points 0 and 4 are used by no tet: the rest keep their file order, renumbered from 0.
  const std::string node =
      "6 3 0 0\n0 9 9 9\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 5 5 5\n5 0 0 1\n";
  TetMesh expected;
  expected.nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  expected.tets = {{0, 1, 2, 3}};
  assert_same_mesh(mica::parse_tetgen(node, "1 4 0\n0 1 2 3 5\n", "t.node", "t.ele"), expected);
  // Edge nodes of 10-node tets are not kept: point 5 is only an edge node here.
  const TetMesh m =
      mica::parse_tetgen(kNode1, "1 10 0\n1 1 2 3 4  5 5 5 5 5 5\n", "t.node", "t.ele");
  expected.tets = {{0, 1, 2, 3}};
  assert_same_mesh(m, expected);
}

// The first tet attribute is the region when every tet's is an integer; otherwise none is.
void tetgen_region_attributes(void**) {
  const std::string two = "2 4 2\n0 0 1 2 3 %s 0.5\n1 1 4 2 3 %s 0.25\n";
  const auto regions = [&](const char* a, const char* b) {
    char ele[128];
    std::snprintf(ele, sizeof ele, two.c_str(), a, b);
    return mica::parse_tetgen("5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n", ele, "t.node", "t.ele")
        .regions;
  };
  assert_true(regions("3", "-2") == std::vector<int32_t>({3, -2}));
  assert_true(regions("3", "2.5").empty());
  assert_true(regions("3", "1e10").empty());
  assert_true(mica::parse_tetgen("4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n", "1 4 0\n0 0 1 2 3\n", "t.node",
                                 "t.ele")
                  .regions.empty());  // no attributes
}

void tetgen_reals_read_like_strtod_in_the_c_locale(void**) {
  const std::string ele = "1 4 0\n0 0 1 2 3\n";
  const TetMesh m = mica::parse_tetgen(
      "4 3 0 0\n0 +1 -0.5 1e-400\n1 0x1p1 .25 2.\n2 1E2 -1e-400 4.9e-324\n3 0 0 1\n", ele,
      "t.node", "t.ele");
  assert_true(m.nodes[0] == Vec3(1, -0.5, 0));
  assert_true(m.nodes[1] == Vec3(2, 0.25, 2));
  assert_true(m.nodes[2].x() == 100 && m.nodes[2].y() == 0 && std::signbit(m.nodes[2].y()));
  assert_true(m.nodes[2].z() > 0);
  const std::string node = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
  for (const char* bad : {"1e400", "-1e999999999999999999999", "nan", "inf", "+-1", "--1", "1,5",
                          "0x", "1e", "+", "0.5x"}) {
    const std::string message =
        std::string("t.node: line 2: expected a finite x coordinate, got '") + bad + "'";
    expect_tetgen_error(with_line(node, 2, std::string("1 ") + bad + " 0 0"), ele, Errc::Parse,
                        message.c_str());
  }
}

void tetgen_dimension_must_be_3(void**) {
  expect_tetgen_error(with_line(kNode1, 2, "5 2 1 1"), kEle1, Errc::Unsupported,
                      "t.node: line 2: expected dimension 3, got '2'");
}

void tetgen_node_index_out_of_range(void**) {
  expect_tetgen_error(kNode1, with_line(kEle1, 4, "2 2 6 3 4 7"), Errc::Parse,
                      "t.ele: line 4: expected a point index from 1 to 5, got '6'");
  expect_tetgen_error(kNode1, with_line(kEle1, 3, "1 0 2 3 4 7"), Errc::Parse,
                      "t.ele: line 3: expected a point index from 1 to 5, got '0'");
  expect_tetgen_error(kNode0, "2 4 0\n0 0 1 2 3\n1 1 5 2 3\n", Errc::Parse,
                      "t.ele: line 3: expected a point index from 0 to 4, got '5'");
}

void tetgen_numbering(void**) {
  expect_tetgen_error(with_line(kNode1, 4, "2 0 0 0 0.5 1"), kEle1, Errc::Parse,
                      "t.node: line 4: expected a first point index 0 or 1, got '2'");
  expect_tetgen_error(with_line(kNode1, 6, "4 0 1 0 0.5 0"), kEle1, Errc::Parse,
                      "t.node: line 6: expected point index 3, got '4'");
  expect_tetgen_error(kNode0, kEle1, Errc::Parse,
                      "t.ele: line 3: expected tetrahedron index 0, got '1'");
}

void tetgen_wrong_counts_and_truncation(void**) {
  expect_tetgen_error(with_line(kNode1, 2, "6 3 1 1"), kEle1, Errc::Parse,
                      "t.node: line 8: expected a point line 'index x y z', got 'end of file'");
  expect_tetgen_error(with_line(kNode1, 2, "4 3 1 1"), kEle1, Errc::Parse,
                      "t.node: line 8: expected end of file after 4 points, got '5'");
  expect_tetgen_error(
      kNode1, with_line(kEle1, 1, "3 4 1"), Errc::Parse,
      "t.ele: line 4: expected a tetrahedron line 'index n1 n2 n3 n4', got 'end of file'");
  expect_tetgen_error(with_line(kNode1, 5, "2 1 0 0 0.5"), kEle1, Errc::Parse,
                      "t.node: line 5: expected a boundary marker, got 'end of line'");
  expect_tetgen_error(kNode1, with_line(kEle1, 4, "2 2 5 3 4 7 8"), Errc::Parse,
                      "t.ele: line 4: expected end of line, got '8'");
  expect_tetgen_error(kNode1, with_line(kEle1, 1, "2 8 1"), Errc::Parse,
                      "t.ele: line 1: expected 4 or 10 nodes per tetrahedron, got '8'");
  expect_tetgen_error(
      kNode1, "", Errc::Parse,
      "t.ele: line 1: expected a header 'ntets nodes_per_tet nattr', got 'end of file'");
  expect_tetgen_error(kNode1, "# nothing\n\n", Errc::Parse, "t.ele: line 2: expected a header");
}

void tetgen_bad_tokens(void**) {
  expect_tetgen_error(with_line(kNode1, 5, "2 x 0 0 0.5 1"), kEle1, Errc::Parse,
                      "t.node: line 5: expected a finite x coordinate, got 'x'");
  expect_tetgen_error(with_line(kNode1, 5, "2 1 0 inf 0.5 1"), kEle1, Errc::Parse,
                      "t.node: line 5: expected a finite z coordinate, got 'inf'");
  expect_tetgen_error(kNode1, with_line(kEle1, 3, "1 1 2 3.0 4 7"), Errc::Parse,
                      "t.ele: line 3: expected a point index from 1 to 5, got '3.0'");
  expect_tetgen_error(with_line(kNode1, 2, "5 3 1 2"), kEle1, Errc::Parse,
                      "t.node: line 2: expected a boundary marker count 0 or 1, got '2'");
}

void tetgen_huge_counts_fail_before_allocating(void**) {
  expect_tetgen_error("2147483647 3 0 0\n1 0 0 0\n", kEle1, Errc::Parse,
                      "t.node: line 2: expected a point line 'index x y z', got 'end of file'");
  expect_tetgen_error(
      kNode1, with_line(kEle1, 1, "2000000000 4 1"), Errc::Parse,
      "t.ele: line 4: expected a tetrahedron line 'index n1 n2 n3 n4', got 'end of file'");
  expect_tetgen_error(with_line(kNode1, 2, "2147483648 3 0 0"), kEle1, Errc::Parse,
                      "t.node: line 2: expected a positive point count, got '2147483648'");
  expect_tetgen_error(with_line(kNode1, 2, "0 3 0 0"), kEle1, Errc::Parse,
                      "t.node: line 2: expected a positive point count, got '0'");
  expect_tetgen_error(with_line(kNode1, 2, "5 3 2000000000 1"), kEle1, Errc::Parse,
                      "t.node: line 4: expected a finite point attribute, got 'end of line'");
}

// ---------------------------------------------------------------- never crash

// Every prefix and many one-byte changes of a valid text either parse or throw mica::Error.
template <class Parse>
void survives_damage(const std::string& text, Parse parse) {
  const char replacements[] = {'\0', '\n', ' ', '#', '$', '-', '9', 'e', '.', '\x80'};
  std::vector<std::string> inputs;
  for (std::size_t n = 0; n <= text.size(); ++n) inputs.push_back(text.substr(0, n));
  for (std::size_t i = 0; i < text.size(); ++i) {
    for (char c : replacements) {
      std::string damaged = text;
      damaged[i] = c;
      inputs.push_back(damaged);
    }
  }
  for (const std::string& input : inputs) {
    try {
      parse(input);
    } catch (const mica::Error&) {
    }
  }
}

void parsers_survive_damaged_input(void**) {
  survives_damage(kGmsh22, [](const std::string& s) { mica::parse_gmsh(s, "t.msh"); });
  survives_damage(kGmsh41, [](const std::string& s) { mica::parse_gmsh(s, "t.msh"); });
  survives_damage(kNode1,
                  [](const std::string& s) { mica::parse_tetgen(s, kEle1, "t.node", "t.ele"); });
  survives_damage(kEle1,
                  [](const std::string& s) { mica::parse_tetgen(kNode1, s, "t.node", "t.ele"); });
}

// ---------------------------------------------------------------- load_mesh and sample files

// The unit cube of tests/data: 8 corners, 6 tets of volume 1/6 each.
void assert_unit_cube(const TetMesh& m) {
  assert_int_equal(m.nodes.size(), 8);
  assert_int_equal(m.tets.size(), 6);
  for (std::size_t i = 0; i < 8; ++i) {
    assert_true(m.nodes[i] == Vec3(double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)));
  }
  double total = 0;
  for (const mica::Tet& t : m.tets) {
    const double v = six_volume(m, t) / 6;
    assert_near(v, 1.0 / 6.0, 1e-15);
    total += v;
  }
  assert_near(total, 1.0, 1e-14);
}

void load_mesh_reads_the_sample_cubes(void**) {
  const TetMesh v22 = mica::load_mesh(data_path("cube_v22.msh"));
  assert_unit_cube(v22);
  assert_same_mesh(mica::load_mesh(data_path("cube_v41.msh")), v22);
  assert_same_mesh(mica::load_mesh(data_path("cube.node")), v22);
  assert_same_mesh(mica::load_mesh(data_path("cube.ele")), v22);
  assert_same_mesh(mica::read_tetgen(data_path("cube")), v22);
}

void load_mesh_missing_file_is_io(void**) {
  const std::string path = data_path("no_such_mesh.msh");
  expect_error([&] { mica::load_mesh(path); }, Errc::Io,
               (path + ": cannot open: No such file or directory").c_str());
  const std::string node = data_path("no_such_mesh.node");
  expect_error([&] { mica::load_mesh(data_path("no_such_mesh.ele")); }, Errc::Io, node.c_str());
  // A directory opens but cannot be read.
  const std::string dir = std::string(MICA_TEST_DATA_DIR) + "/.";
  expect_error([&] { mica::read_gmsh(dir); }, Errc::Io, (dir + ": cannot read").c_str());
}

void load_mesh_unknown_extension_is_unsupported(void**) {
  const std::string path = data_path("cube.stl");
  expect_error([&] { mica::load_mesh(path); }, Errc::Unsupported,
               (path + ": unsupported mesh file extension").c_str());
  expect_error([&] { mica::load_mesh(path); }, Errc::Unsupported, ".msh");
  expect_error([&] { mica::load_mesh("cube"); }, Errc::Unsupported, ".node or .ele");
}

// Copies the sample `file` to a temporary path ending in `name`, which the caller removes.
std::string temp_copy(const char* file, const std::string& name) {
  const std::string path = "/tmp/mica_test_mesh_io_" + std::to_string(getpid()) + "_" + name;
  std::ifstream in(data_path(file), std::ios::binary);
  std::ofstream out(path, std::ios::binary);
  out << in.rdbuf();
  assert_true(in.good() && out.good());
  return path;
}

void load_mesh_extensions_ignore_case(void**) {
  const TetMesh cube = mica::load_mesh(data_path("cube_v22.msh"));
  const std::string msh = temp_copy("cube_v22.msh", "cube.MSH");
  const std::string mixed = temp_copy("cube_v41.msh", "cube.Msh");
  const std::string node = temp_copy("cube.node", "cube.NODE");
  const std::string ele = temp_copy("cube.ele", "cube.ELE");
  const TetMesh from_msh = mica::load_mesh(msh);
  const TetMesh from_mixed = mica::load_mesh(mixed);
  const TetMesh from_node = mica::load_mesh(node);
  const TetMesh from_ele = mica::load_mesh(ele);
  for (const std::string& path : {msh, mixed, node, ele}) std::remove(path.c_str());
  assert_same_mesh(from_msh, cube);
  assert_same_mesh(from_mixed, cube);
  assert_same_mesh(from_node, cube);
  assert_same_mesh(from_ele, cube);
  expect_error([&] { mica::load_mesh("cube.MSH2"); }, Errc::Unsupported,
               "cube.MSH2: unsupported mesh file extension");
}

// ---------------------------------------------------------------- VTK

// What a VTK legacy unstructured grid holds, read back token by token.
struct VtkGrid {
  std::string title;
  std::vector<double> points;  // 3 per point
  std::vector<std::vector<long>> cells;
  std::vector<long> cell_types;
  std::vector<long> piece;
  std::vector<std::pair<std::string, std::vector<double>>> vectors;
};

double to_double(const std::string& token) {
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size()) fail_msg("not a number: '%s'", token.c_str());
  return v;
}

VtkGrid read_vtk(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  VtkGrid g;
  std::getline(in, line);
  assert_string_equal(line.c_str(), "# vtk DataFile Version 3.0");
  std::getline(in, g.title);
  std::string word;
  auto expect = [&](const char* w) {
    in >> word;
    assert_string_equal(word.c_str(), w);
  };
  expect("ASCII");
  expect("DATASET");
  expect("UNSTRUCTURED_GRID");
  expect("POINTS");
  std::size_t n = 0;
  in >> n;
  expect("double");
  for (std::size_t i = 0; i < 3 * n; ++i) {
    in >> word;
    g.points.push_back(to_double(word));
  }
  expect("CELLS");
  std::size_t m = 0, size = 0;
  in >> m >> size;
  assert_int_equal(size, 5 * m);
  for (std::size_t c = 0; c < m; ++c) {
    long k = 0;
    in >> k;
    std::vector<long> cell(static_cast<std::size_t>(k));
    for (long& v : cell) in >> v;
    g.cells.push_back(cell);
  }
  expect("CELL_TYPES");
  in >> size;
  assert_int_equal(size, m);
  g.cell_types.resize(m);
  for (long& t : g.cell_types) in >> t;
  expect("CELL_DATA");
  in >> size;
  assert_int_equal(size, m);
  expect("SCALARS");
  expect("piece");
  expect("int");
  expect("1");
  expect("LOOKUP_TABLE");
  expect("default");
  g.piece.resize(m);
  for (long& p : g.piece) in >> p;
  if (in >> word) {
    assert_string_equal(word.c_str(), "POINT_DATA");
    in >> size;
    assert_int_equal(size, n);
    while (in >> word) {
      assert_string_equal(word.c_str(), "VECTORS");
      std::string name;
      in >> name;
      expect("double");
      std::vector<double> values;
      for (std::size_t i = 0; i < 3 * n; ++i) {
        in >> word;
        values.push_back(to_double(word));
      }
      g.vectors.emplace_back(name, values);
    }
  }
  assert_false(in.bad());
  return g;
}

// A locale that writes 1,5 for 1.5: the writer must not use it.
struct CommaDecimal : std::numpunct<char> {
  char do_decimal_point() const override { return ','; }
};

void vtk_round_trips_exactly(void**) {
  const mica::Vec3List a_pos = {Vec3(0.1, 1.0 / 3.0, -2.5e-300), Vec3(6.02214076e23, -0.0, 1e-5),
                                Vec3(0.7, 0.2, 0.3), Vec3(std::nextafter(1.0, 2.0), 2, 3),
                                Vec3(-1, -2, -3)};
  const std::vector<mica::Tet> a_tets = {{0, 1, 2, 3}, {1, 4, 2, 3}};
  const mica::Vec3List a_vel = {Vec3(1, 2, 3), Vec3(0.1, 0.2, 0.3), Vec3(1e300, -1e-300, 0),
                                Vec3(4, 5, 6), Vec3(7, 8, 9)};
  const mica::Vec3List a_force = {Vec3(-1, 0, 0), Vec3(0, -1, 0), Vec3(0, 0, -1),
                                  Vec3(1.0 / 7.0, 0, 0), Vec3(0, 2.0 / 3.0, 0)};
  const mica::Vec3List b_pos = {Vec3(10, 0, 0), Vec3(11, 0, 0), Vec3(10, 1, 0), Vec3(10, 0, 1)};
  const std::vector<mica::Tet> b_tets = {{0, 1, 2, 3}};
  const mica::Vec3List b_vel = {Vec3(0.5, 0.25, 0.125), Vec3(0, 0, 0), Vec3(3.14159, 0, 0),
                                Vec3(0, 0, 2.718281828)};
  const mica::Vec3List b_force = {Vec3(9, 9, 9), Vec3(8, 8, 8), Vec3(7, 7, 7), Vec3(6, 6, 6)};

  mica::VtkPiece a{&a_pos, &a_tets, {{"velocity", &a_vel}, {"force", &a_force}}};
  mica::VtkPiece b{&b_pos, &b_tets, {{"velocity", &b_vel}, {"force", &b_force}}};
  std::ostringstream out;
  const std::locale comma(std::locale::classic(), new CommaDecimal);
  out.imbue(comma);
  out.precision(3);
  mica::write_vtk(out, {a, b}, "two\nbodies");
  assert_int_equal(out.precision(), 3);  // the caller's settings are given back
  assert_true(std::has_facet<CommaDecimal>(out.getloc()));

  const VtkGrid g = read_vtk(out.str());
  assert_string_equal(g.title.c_str(), "two bodies");
  std::vector<Vec3> all_pos(a_pos);
  all_pos.insert(all_pos.end(), b_pos.begin(), b_pos.end());
  assert_int_equal(g.points.size(), 3 * all_pos.size());
  for (std::size_t i = 0; i < all_pos.size(); ++i) {
    for (int k = 0; k < 3; ++k) assert_true(g.points[3 * i + k] == all_pos[i][k]);
  }
  assert_true(std::signbit(g.points[3 * 1 + 1]));  // -0.0 stays negative
  const std::vector<std::vector<long>> cells = {{0, 1, 2, 3}, {1, 4, 2, 3}, {5, 6, 7, 8}};
  assert_true(g.cells == cells);
  for (long t : g.cell_types) assert_int_equal(t, 10);
  assert_true(g.piece == std::vector<long>({0, 0, 1}));
  assert_int_equal(g.vectors.size(), 2);
  const mica::Vec3List* expected[2][2] = {{&a_vel, &b_vel}, {&a_force, &b_force}};
  const char* names[2] = {"velocity", "force"};
  for (std::size_t f = 0; f < 2; ++f) {
    assert_string_equal(g.vectors[f].first.c_str(), names[f]);
    std::vector<Vec3> values(*expected[f][0]);
    values.insert(values.end(), expected[f][1]->begin(), expected[f][1]->end());
    for (std::size_t i = 0; i < values.size(); ++i) {
      for (int k = 0; k < 3; ++k) assert_true(g.vectors[f].second[3 * i + k] == values[i][k]);
    }
  }
}

void vtk_file_matches_stream_and_reports_io(void**) {
  const TetMesh m = expected_gmsh_mesh();
  const std::vector<mica::VtkPiece> pieces = {{&m.nodes, &m.tets, {}}};
  std::ostringstream expected;
  mica::write_vtk(expected, pieces, "cube");
  const std::string path = "/tmp/mica_test_mesh_io_" + std::to_string(getpid()) + ".vtk";
  mica::write_vtk_file(path, pieces, "cube");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  assert_non_null(f);
  std::string text;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) text.append(buffer, n);
  std::fclose(f);
  std::remove(path.c_str());
  assert_string_equal(text.c_str(), expected.str().c_str());
  const VtkGrid g = read_vtk(text);
  assert_int_equal(g.cells.size(), 2);
  assert_true(g.vectors.empty());

  const std::string bad = "/nonexistent_dir_for_mica/out.vtk";
  expect_error([&] { mica::write_vtk_file(bad, pieces, "x"); }, Errc::Io,
               (bad + ": cannot open for writing").c_str());
}

// Per-tet scalars follow "piece" in CELL_DATA, both pieces' values in order, read back exactly.
void vtk_writes_cell_scalars(void**) {
  const TetMesh m = expected_gmsh_mesh();
  const std::vector<double> a = {1.0 / 3.0, -2.5}, b = {7, 1e-300};
  std::ostringstream o;
  mica::write_vtk(o, {{&m.nodes, &m.tets, {}, {{"von_mises", &a}}}, {&m.nodes, &m.tets, {}, {{"von_mises", &b}}}},
                  "x");
  const std::string text = o.str();
  const std::size_t at = text.find("SCALARS von_mises double 1\nLOOKUP_TABLE default\n");
  assert_true(at != std::string::npos);
  assert_true(text.find("SCALARS piece int 1") < at);
  std::istringstream values(text.substr(text.find("default\n", at) + 8));
  for (double expected : {a[0], a[1], b[0], b[1]}) {
    double v = 0;
    values >> v;
    assert_true(v == expected);
  }
}

void vtk_rejects_inconsistent_pieces(void**) {
  const TetMesh m = expected_gmsh_mesh();
  const std::vector<mica::Tet> bad_tets = {{0, 1, 2, 5}};
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(o, {{&m.nodes, &bad_tets, {}}}, "x");
      },
      Errc::OutOfRange, "write_vtk: piece 0, tet 0: node 5 is outside [0, 5)");
  const mica::Vec3List short_field(3);
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(o, {{&m.nodes, &m.tets, {{"v", &short_field}}}}, "x");
      },
      Errc::InvalidArgument, "point vector 'v' needs one value per node");
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(o, {{&m.nodes, &m.tets, {{"my v", &m.nodes}}}}, "x");
      },
      Errc::InvalidArgument, "must be one word");
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(
            o, {{&m.nodes, &m.tets, {{"v", &m.nodes}}}, {&m.nodes, &m.tets, {{"w", &m.nodes}}}},
            "x");
      },
      Errc::InvalidArgument, "write_vtk: piece 1: point vector 0 is 'w', piece 0 has 'v'");
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(o, {{nullptr, &m.tets, {}}}, "x");
      },
      Errc::InvalidArgument, "piece 0 has no positions");
  const std::vector<double> one = {1.0}, two = {1.0, 2.0};
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(o, {{&m.nodes, &m.tets, {}, {{"s", &one}}}}, "x");
      },
      Errc::InvalidArgument, "cell scalar 's' needs one value per tet (2)");
  expect_error(
      [&] {
        std::ostringstream o;
        mica::write_vtk(o, {{&m.nodes, &m.tets, {}, {{"s", &two}}}, {&m.nodes, &m.tets, {}, {}}}, "x");
      },
      Errc::InvalidArgument, "write_vtk: piece 1 has 0 cell scalar fields, piece 0 has 1");
  std::ostringstream failed;
  failed.setstate(std::ios::badbit);
  expect_error(
      [&] {
        mica::write_vtk(failed, {{&m.nodes, &m.tets, {}}}, "x");
      },
      Errc::Io, "write_vtk");
}

}  // namespace

int main() {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(gmsh22_keeps_tets_and_renumbers_in_file_order),
      cmocka_unit_test(gmsh41_blocks_give_the_same_mesh_as_22),
      cmocka_unit_test(gmsh_keeps_each_tets_physical_tag),
      cmocka_unit_test(gmsh_accepts_crlf_and_blank_lines),
      cmocka_unit_test(gmsh_truncated_section),
      cmocka_unit_test(gmsh_missing_end_markers),
      cmocka_unit_test(gmsh_wrong_counts),
      cmocka_unit_test(gmsh_bad_tokens),
      cmocka_unit_test(gmsh_unknown_or_repeated_node_tags),
      cmocka_unit_test(gmsh_binary_and_other_versions_are_unsupported),
      cmocka_unit_test(gmsh_without_tets_is_rejected),
      cmocka_unit_test(gmsh_huge_counts_fail_before_allocating),
      cmocka_unit_test(tetgen_one_based_with_comments),
      cmocka_unit_test(tetgen_zero_based),
      cmocka_unit_test(tetgen_ten_node_tets_keep_their_corners),
      cmocka_unit_test(tetgen_keeps_file_orientation),
      cmocka_unit_test(tetgen_drops_unused_points_and_renumbers),
      cmocka_unit_test(tetgen_region_attributes),
      cmocka_unit_test(tetgen_reals_read_like_strtod_in_the_c_locale),
      cmocka_unit_test(tetgen_dimension_must_be_3),
      cmocka_unit_test(tetgen_node_index_out_of_range),
      cmocka_unit_test(tetgen_numbering),
      cmocka_unit_test(tetgen_wrong_counts_and_truncation),
      cmocka_unit_test(tetgen_bad_tokens),
      cmocka_unit_test(tetgen_huge_counts_fail_before_allocating),
      cmocka_unit_test(parsers_survive_damaged_input),
      cmocka_unit_test(load_mesh_reads_the_sample_cubes),
      cmocka_unit_test(load_mesh_missing_file_is_io),
      cmocka_unit_test(load_mesh_unknown_extension_is_unsupported),
      cmocka_unit_test(load_mesh_extensions_ignore_case),
      cmocka_unit_test(vtk_round_trips_exactly),
      cmocka_unit_test(vtk_file_matches_stream_and_reports_io),
      cmocka_unit_test(vtk_writes_cell_scalars),
      cmocka_unit_test(vtk_rejects_inconsistent_pieces),
  };
  return cmocka_run_group_tests_name("mesh_io", tests, nullptr, nullptr);
}
