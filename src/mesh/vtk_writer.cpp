// SPDX-License-Identifier: Apache-2.0
// VTK legacy ASCII writer: all pieces as one unstructured grid of linear tetrahedra
// (VTK cell type 10, whose positive orientation is ours), a cell scalar "piece" telling the
// pieces apart, the requested per-tet scalars and the requested per-node vectors. Doubles are written with 17 significant
// digits so that they read back exactly.
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <locale>
#include <ostream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "mesh/mesh_io.hpp"

namespace mica {
namespace {

constexpr int kVtkTetra = 10;

bool has_space(const std::string& s) {
  for (char c : s) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') return true;
  }
  return false;
}

// Every piece must carry the same fields, in the same order, as piece 0, each a one-word name
// and one value per node (per tet).
template <class Field>
void check_fields(const std::string& where, const std::string& kind, const std::vector<Field>& fields,
                  const std::vector<Field>& reference, std::size_t count, const char* per) {
  if (fields.size() != reference.size()) {
    fail(Errc::InvalidArgument, where + " has " + std::to_string(fields.size()) + " " + kind +
                                    " fields, piece 0 has " + std::to_string(reference.size()));
  }
  for (std::size_t f = 0; f < fields.size(); ++f) {
    const std::string& name = fields[f].first;
    if (name.empty() || has_space(name)) {
      fail(Errc::InvalidArgument, where + ": " + kind + " name '" + name + "' must be one word");
    }
    if (name != reference[f].first) {
      fail(Errc::InvalidArgument, where + ": " + kind + " " + std::to_string(f) + " is '" + name +
                                      "', piece 0 has '" + reference[f].first + "'");
    }
    if (!fields[f].second || fields[f].second->size() != count) {
      fail(Errc::InvalidArgument, where + ": " + kind + " '" + name + "' needs one value per " + per + " (" +
                                      std::to_string(count) + ")");
    }
  }
}

// Throws InvalidArgument / OutOfRange for a piece the grid cannot be written from.
void check_pieces(const std::vector<VtkPiece>& pieces) {
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const VtkPiece& piece = pieces[p];
    const std::string where = "write_vtk: piece " + std::to_string(p);
    if (!piece.positions || !piece.tets) {
      fail(Errc::InvalidArgument, where + " has no positions or no tets");
    }
    const auto n = static_cast<std::int64_t>(piece.positions->size());
    for (std::size_t e = 0; e < piece.tets->size(); ++e) {
      for (std::int32_t v : (*piece.tets)[e]) {
        if (v < 0 || v >= n) {
          fail(Errc::OutOfRange, where + ", tet " + std::to_string(e) + ": node " +
                                     std::to_string(v) + " is outside [0, " + std::to_string(n) +
                                     ")");
        }
      }
    }
    check_fields(where, "point vector", piece.point_vectors, pieces[0].point_vectors, piece.positions->size(),
                 "node");
    check_fields(where, "cell scalar", piece.cell_scalars, pieces[0].cell_scalars, piece.tets->size(), "tet");
  }
}

// Writes numbers in the classic locale with 17 significant digits, and gives the caller's
// stream its own settings back afterwards.
class NumberFormat {
 public:
  explicit NumberFormat(std::ostream& out)
      : out_(out), locale_(out.getloc()), flags_(out.flags()), precision_(out.precision()) {
    out_.imbue(std::locale::classic());
    out_.unsetf(std::ios::floatfield);
    out_.precision(17);
  }
  ~NumberFormat() {
    out_.imbue(locale_);
    out_.flags(flags_);
    out_.precision(precision_);
  }
  NumberFormat(const NumberFormat&) = delete;
  NumberFormat& operator=(const NumberFormat&) = delete;

 private:
  std::ostream& out_;
  std::locale locale_;
  std::ios::fmtflags flags_;
  std::streamsize precision_;
};

// The header title is one line of at most 256 characters.
std::string title_line(const std::string& title) {
  std::string line = title.empty() ? std::string("libmica") : title.substr(0, 255);
  for (char& c : line) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return line;
}

void write_vec3(std::ostream& out, const Vec3& v) {
  out << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
}

void write_grid(std::ostream& out, const std::vector<VtkPiece>& pieces, const std::string& title) {
  const NumberFormat format(out);
  std::size_t num_points = 0;
  std::size_t num_cells = 0;
  for (const VtkPiece& piece : pieces) {
    num_points += piece.positions->size();
    num_cells += piece.tets->size();
  }

  out << "# vtk DataFile Version 3.0\n"
      << title_line(title) << "\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  out << "POINTS " << num_points << " double\n";
  for (const VtkPiece& piece : pieces) {
    for (const Vec3& x : *piece.positions) write_vec3(out, x);
  }

  out << "CELLS " << num_cells << ' ' << 5 * num_cells << '\n';
  std::size_t offset = 0;  // index of the piece's first point in the grid
  for (const VtkPiece& piece : pieces) {
    for (const Tet& t : *piece.tets) {
      out << 4;
      for (std::int32_t v : t) out << ' ' << offset + static_cast<std::size_t>(v);
      out << '\n';
    }
    offset += piece.positions->size();
  }
  out << "CELL_TYPES " << num_cells << '\n';
  for (std::size_t c = 0; c < num_cells; ++c) out << kVtkTetra << '\n';

  if (num_cells > 0) {
    out << "CELL_DATA " << num_cells << "\nSCALARS piece int 1\nLOOKUP_TABLE default\n";
    for (std::size_t p = 0; p < pieces.size(); ++p) {
      for (std::size_t c = 0; c < pieces[p].tets->size(); ++c) out << p << '\n';
    }
    for (std::size_t f = 0; f < pieces[0].cell_scalars.size(); ++f) {
      out << "SCALARS " << pieces[0].cell_scalars[f].first << " double 1\nLOOKUP_TABLE default\n";
      for (const VtkPiece& piece : pieces) {
        for (double v : *piece.cell_scalars[f].second) out << v << '\n';
      }
    }
  }

  if (num_points > 0 && !pieces[0].point_vectors.empty()) {
    out << "POINT_DATA " << num_points << '\n';
    for (std::size_t f = 0; f < pieces[0].point_vectors.size(); ++f) {
      out << "VECTORS " << pieces[0].point_vectors[f].first << " double\n";
      for (const VtkPiece& piece : pieces) {
        for (const Vec3& v : *piece.point_vectors[f].second) write_vec3(out, v);
      }
    }
  }
}

std::string reason() { return errno != 0 ? std::strerror(errno) : "unknown error"; }

}  // namespace

void write_vtk(std::ostream& out, const std::vector<VtkPiece>& pieces, const std::string& title) {
  check_pieces(pieces);
  write_grid(out, pieces, title);
  if (!out) fail(Errc::Io, "write_vtk: the output stream failed");
}

void write_vtk_file(const std::string& path, const std::vector<VtkPiece>& pieces,
                    const std::string& title) {
  check_pieces(pieces);  // before opening, so that bad input leaves an existing file alone
  errno = 0;
  std::ofstream out(path);
  if (!out) fail(Errc::Io, path + ": cannot open for writing: " + reason());
  write_grid(out, pieces, title);
  out.close();
  if (!out) fail(Errc::Io, path + ": cannot write: " + reason());
}

}  // namespace mica
