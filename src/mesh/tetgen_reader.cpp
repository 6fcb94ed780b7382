// TetGen .node/.ele reader. '#' starts a comment anywhere on a line; blank lines are skipped.
// The first point index of the .node file (0 or 1) sets the numbering of both files.
// Memory reserved for a count read from a file is capped by what the bytes left can hold, so a
// lying header fails at the end of the text, unallocated.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "mesh/mesh_io.hpp"

namespace mica {
namespace detail {
std::string read_text_file(const std::string& path);  // defined in mesh_io.cpp
}

namespace {

constexpr std::int64_t kMinPointBytes = 8;  // shortest point line: "1 0 0 0\n"
constexpr std::int64_t kMinTetBytes = 10;   // shortest tetrahedron line: "1 1 2 3 4\n"
constexpr std::int64_t kMaxCount = std::numeric_limits<std::int32_t>::max();

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

std::string_view first_token(std::string_view line) {
  std::size_t end = 0;
  while (end < line.size() && !is_space(line[end])) ++end;
  return line.substr(0, end);
}

// A token as shown in a message: at most 40 characters, control characters replaced.
std::string shown(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string s;
  for (char c : token.substr(0, kMax)) {
    const auto u = static_cast<unsigned char>(c);
    s += (u < 0x20 || u == 0x7f) ? '?' : c;
  }
  if (token.size() > kMax) s += "...";
  return s;
}

// Walks the text one line at a time, comments removed and blank lines skipped, and formats
// errors with the line number.
class LineReader {
 public:
  LineReader(std::string_view text, const std::string& name) : text_(text), name_(name) {}

  // Moves to the next line with content; false at the end of the text, where the line number
  // stays on the last line so that messages point at where the text stopped.
  bool advance() {
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      std::string_view line = text_.substr(pos_, end - pos_);
      line = trim(line.substr(0, line.find('#')));
      pos_ = end < text_.size() ? end + 1 : end;
      ++number_;
      if (!line.empty()) {
        line_ = line;
        return true;
      }
    }
    line_ = {};
    return false;
  }

  // Like advance(), but the end of the text is an error: `what` was expected there.
  std::string_view next(std::string_view what) {
    if (!advance()) expected(what, "end of file");
    return line_;
  }

  // The rest of the text must be comments and blank lines.
  void expect_end(std::string_view what) {
    if (advance()) expected(what, first_token(line_));
  }

  std::int64_t bytes_left() const { return static_cast<std::int64_t>(text_.size() - pos_); }

  [[noreturn]] void expected(std::string_view what, std::string_view got,
                             Errc code = Errc::Parse) const {
    fail(code, name_ + ": line " + std::to_string(number_ > 0 ? number_ : 1) + ": expected " +
                   std::string(what) + ", got '" + shown(got) + "'");
  }

 private:
  std::string_view text_;
  const std::string& name_;
  std::size_t pos_ = 0;
  std::int64_t number_ = 0;
  std::string_view line_;
};

// Reads the whitespace-separated fields of one line, reporting errors on that line.
class Fields {
 public:
  Fields(const LineReader& at, std::string_view line) : at_(at), rest_(line) {}

  std::string_view token(std::string_view what) {
    rest_ = trim(rest_);
    if (rest_.empty()) at_.expected(what, "end of line");
    last_ = first_token(rest_);
    rest_.remove_prefix(last_.size());
    return last_;
  }

  // The token read last, for messages about it.
  std::string_view last() const { return last_; }

  // An integer in [lo, hi]; anything else is reported as not being `what`.
  std::int64_t integer(std::string_view what,
                       std::int64_t lo = std::numeric_limits<std::int64_t>::min(),
                       std::int64_t hi = std::numeric_limits<std::int64_t>::max()) {
    const std::string_view tok = token(what);
    std::int64_t value = 0;
    const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), value);
    if (ec != std::errc() || end != tok.data() + tok.size() || value < lo || value > hi) {
      at_.expected(what, tok);
    }
    return value;
  }

  // A positive record count, small enough to index with int32.
  std::int64_t count(std::string_view what) { return integer(what, 1, kMaxCount); }

  double real(std::string_view what) {
    const std::string tok(token(what));  // strtod needs a null-terminated string
    char* end = nullptr;
    const double value = std::strtod(tok.c_str(), &end);
    if (end != tok.c_str() + tok.size() || !std::isfinite(value)) at_.expected(what, tok);
    return value;
  }

  void finish() {
    rest_ = trim(rest_);
    if (!rest_.empty()) at_.expected("end of line", first_token(rest_));
  }

 private:
  const LineReader& at_;
  std::string_view rest_;
  std::string_view last_;
};

// How many of `n` records to reserve room for: no more than the rest of the text can describe.
std::size_t reservable(std::int64_t n, const LineReader& lines, std::int64_t min_bytes) {
  return static_cast<std::size_t>(std::min(n, lines.bytes_left() / min_bytes));
}

struct PointList {
  Vec3List points;
  std::int64_t first_index = 0;  // 0 or 1
};

// .node: "npoints dim nattr nmarkers", then "index x y z [attributes] [marker]" per point.
PointList read_points(std::string_view text, const std::string& name) {
  LineReader lines(text, name);
  Fields header(lines, lines.next("a header 'npoints dim nattr nmarkers'"));
  const std::int64_t n = header.count("a positive point count");
  if (header.integer("a dimension") != 3) {
    lines.expected("dimension 3", header.last(), Errc::Unsupported);
  }
  const std::int64_t num_attributes = header.integer("an attribute count", 0, kMaxCount);
  const std::int64_t num_markers = header.integer("a boundary marker count 0 or 1", 0, 1);
  header.finish();

  PointList out;
  out.points.reserve(reservable(n, lines, kMinPointBytes));
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
std::vector<Tet> read_tets(std::string_view text, const std::string& name,
                           const PointList& points) {
  LineReader lines(text, name);
  Fields header(lines, lines.next("a header 'ntets nodes_per_tet nattr'"));
  const std::int64_t n = header.count("a positive tetrahedron count");
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
  tets.reserve(reservable(n, lines, kMinTetBytes));
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
    for (std::int64_t a = 0; a < num_attributes; ++a) f.real("a finite tetrahedron attribute");
    f.finish();
    tets.push_back(t);
  }
  lines.expect_end("end of file after " + std::to_string(n) + " tetrahedra");
  return tets;
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

TetMesh parse_tetgen(std::string_view node_text, std::string_view ele_text,
                     const std::string& node_name, const std::string& ele_name) {
  PointList points = read_points(node_text, node_name);
  TetMesh mesh;
  mesh.tets = read_tets(ele_text, ele_name, points);
  mesh.nodes = std::move(points.points);
  return mesh;
}

TetMesh read_tetgen(const std::string& path) {
  std::string stem = path;
  if (ends_with(path, ".node")) {
    stem.resize(path.size() - 5);
  } else if (ends_with(path, ".ele")) {
    stem.resize(path.size() - 4);
  }
  const std::string node_path = stem + ".node";
  const std::string ele_path = stem + ".ele";
  const std::string node_text = detail::read_text_file(node_path);
  const std::string ele_text = detail::read_text_file(ele_path);
  return parse_tetgen(node_text, ele_text, node_path, ele_path);
}

}  // namespace mica
