// SPDX-License-Identifier: Apache-2.0
// A linear tetrahedral mesh: node positions and 4-node elements (0-based indices).
// Convention: a valid rest element has positive signed volume,
// det[X1-X0, X2-X0, X3-X0] > 0 (X0, X1, X2 counter-clockwise seen from X3).
#pragma once
#include <string>
#include <vector>

#include "core/types.hpp"

namespace mica {

struct TetMesh {
  Vec3List nodes;
  std::vector<Tet> tets;
  // Per tet, the region it belongs to (Gmsh physical tag, TetGen region attribute); empty: all 0.
  std::vector<int32_t> regions;
};

// Signed volume of a tetrahedron, positive for the convention above.
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Checks indices are in range and distinct, coordinates are finite, every node is used, no tet
// repeats another's four nodes, no face is shared by more than two tets, and the mesh has a
// boundary surface; throws Error naming the first offending element or node. `source` prefixes
// messages (file name or "body").
void validate_topology(const TetMesh& mesh, const std::string& source);

struct QualityReport {
  double min_volume = 0;
  double worst_aspect = 0;           // longest edge / inradius-based height, 1-ish for regular
  std::vector<int32_t> slivers;      // elements whose aspect exceeds the sliver threshold
};

// Rejects (throws BadMesh, naming the element) rest elements with volume <= tiny or negative;
// reports slivers without rejecting them.
QualityReport check_rest_quality(const TetMesh& mesh, const std::string& source,
                                 double sliver_aspect = 100.0);

// Boundary faces (those belonging to exactly one tet), oriented with outward normals.
std::vector<Tri> extract_surface(const TetMesh& mesh);

// Nodes lying on the surface, sorted.
std::vector<int32_t> surface_nodes(const std::vector<Tri>& surface);

// A structured box [lo, hi] split into cells[0] x cells[1] x cells[2] cubes, each cut into
// 5 (alternating, conforming) or 6 (Kuhn) positively oriented tetrahedra.
TetMesh make_box_grid(const Vec3& lo, const Vec3& hi, const std::array<int32_t, 3>& cells,
                      int32_t tets_per_cell);

}  // namespace mica
