// SPDX-License-Identifier: Apache-2.0
// Reading tetrahedral meshes from files and writing VTK for ParaView.
// Every parse error names the file, the line and what was expected.
#pragma once
#include <cstddef>
#include <iosfwd>
#include <string>
#include <string_view>

#include "mesh/tet_mesh.hpp"

namespace mica {

// The largest mesh file the loaders read (bytes): 256 MiB, some million tetrahedra in ASCII.
// A larger file, and anything that is not a regular file (a FIFO, a device), is refused with
// Errc::Io before it is read.
constexpr std::size_t kMaxMeshFileBytes = std::size_t(256) << 20;

// Dispatch on the extension: .msh (Gmsh 2.2 or 4.1 ASCII), .node or .ele (TetGen pair).
TetMesh load_mesh(const std::string& path);

// Gmsh ASCII, versions 2.2 and 4.1; keeps 4-node tetrahedra (type 4), ignores other elements,
// renumbers nodes to 0..n-1 (unused nodes dropped). `name` is used in messages.
TetMesh parse_gmsh(std::string_view text, const std::string& name);
TetMesh read_gmsh(const std::string& path);

// TetGen .node + .ele; 0- or 1-based numbering as the files declare it.
TetMesh parse_tetgen(std::string_view node_text, std::string_view ele_text,
                     const std::string& node_name, const std::string& ele_name);
TetMesh read_tetgen(const std::string& path);  // path to the .node or the .ele (or no suffix)

// One piece of a VTK legacy unstructured grid: a body's current positions and its tets,
// with optional per-node vectors (name, values) written as POINT_DATA and per-tet scalars
// (name, values) written as CELL_DATA after "piece".
struct VtkPiece {
  const Vec3List* positions = nullptr;
  const std::vector<Tet>* tets = nullptr;
  std::vector<std::pair<std::string, const Vec3List*>> point_vectors;
  std::vector<std::pair<std::string, const std::vector<double>*>> cell_scalars;
};

// Writes all pieces as one grid (a cell scalar "piece" tells them apart).
void write_vtk(std::ostream& out, const std::vector<VtkPiece>& pieces, const std::string& title);
void write_vtk_file(const std::string& path, const std::vector<VtkPiece>& pieces,
                    const std::string& title);

}  // namespace mica
