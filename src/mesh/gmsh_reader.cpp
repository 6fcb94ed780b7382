// SPDX-License-Identifier: Apache-2.0
// Gmsh ASCII mesh reader, format versions 2.2 and 4.1: keeps the 4-node tetrahedra and the
// physical tag of each (its region: 2.2 lists it first among an element's tags, 4.1 in the
// $Entities record of the volume the element block belongs to; 0 without one).
// Nodes are renumbered 0..n-1 in the order the $Nodes section lists them; nodes that no
// tetrahedron uses are dropped. Memory reserved for a count read from the file is capped by
// what the bytes left can hold, so a lying header fails at the end of the text, unallocated.
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "mesh/mesh_io.hpp"
#include "mesh/text_scanner.hpp"

namespace mica {
namespace {

using detail::Fields;
using detail::first_token;
using detail::LineReader;

constexpr int kTet4 = 4;                   // Gmsh element type of the 4-node tetrahedron
constexpr std::int64_t kMinNodeBytes = 8;  // shortest node record: "1 0 0 0\n"

enum class Version { Legacy2, Modern4 };

class GmshParser {
 public:
  GmshParser(std::string_view text, const std::string& name) : lines_(text, name) {}

  TetMesh parse() {
    if (!lines_.advance() || lines_.line() != "$MeshFormat") {
      lines_.expected("$MeshFormat",
                      lines_.line().empty() ? "end of file" : first_token(lines_.line()));
    }
    read_format();
    while (lines_.advance()) {
      const std::string_view header = lines_.line();
      if (header.front() != '$') {
        lines_.expected("a section header such as $Nodes", first_token(header));
      }
      if (header == "$Nodes") {
        version_ == Version::Legacy2 ? read_nodes_v2() : read_nodes_v4();
      } else if (header == "$Elements") {
        version_ == Version::Legacy2 ? read_elements_v2() : read_elements_v4();
      } else if (header == "$Entities" && version_ == Version::Modern4) {
        read_entities_v4();
      } else {
        skip_section(header);
      }
    }
    if (tets_.empty()) {
      lines_.expected("at least one 4-node tetrahedron (element type 4)", "end of file");
    }
    TetMesh mesh = detail::drop_unused_nodes(nodes_, tets_);
    mesh.regions = std::move(regions_);
    if (version_ == Version::Modern4) {  // entity tags to physical tags ($Entities may come anywhere)
      for (std::int32_t& r : mesh.regions) {
        const auto it = volume_physical_.find(r);
        r = it == volume_physical_.end() ? 0 : it->second;
      }
    }
    return mesh;
  }

 private:
  void read_format() {
    Fields f(lines_, lines_.next("a version line 'version file-type data-size'"));
    const std::string_view version = f.token("a format version");
    if (version == "4.1") {
      version_ = Version::Modern4;
    } else if (version == "2.2" || version == "2.1" || version == "2.0" || version == "2") {
      version_ = Version::Legacy2;
    } else {
      lines_.expected("format version 2.2 or 4.1", version, Errc::Unsupported);
    }
    const std::string_view file_type = f.token("a file type");
    if (file_type != "0") {
      lines_.expected("file type 0 (ASCII; binary .msh files are not supported)", file_type,
                      file_type == "1" ? Errc::Unsupported : Errc::Parse);
    }
    f.integer("a data size");
    f.finish();
    expect_line("$EndMeshFormat");
  }

  void expect_line(std::string_view end_marker) {
    const std::string_view line = lines_.next(end_marker);
    if (line != end_marker) lines_.expected(end_marker, first_token(line));
  }

  void skip_section(std::string_view header) {
    const std::string end_marker = "$End" + std::string(header.substr(1));
    while (lines_.next(end_marker) != end_marker) {
    }
  }

  static constexpr std::int64_t kMinInt32 = std::numeric_limits<std::int32_t>::min();
  static constexpr std::int64_t kMaxInt32 = std::numeric_limits<std::int32_t>::max();

  // 4.1: "numPoints numCurves numSurfaces numVolumes", then one line per entity; a volume's line
  // is "tag minX minY minZ maxX maxY maxZ numPhysicalTags physicalTags... numSurfaces ...".
  // Keeps each volume's first physical tag; skips the points, curves and surfaces.
  void read_entities_v4() {
    Fields header(lines_, lines_.next("an $Entities header 'numPoints numCurves numSurfaces numVolumes'"));
    std::int64_t lower_dimensional = 0;
    for (const char* what : {"a point count", "a curve count", "a surface count"})
      lower_dimensional += header.count(what);
    const std::int64_t volumes = header.count("a volume count");
    header.finish();
    for (std::int64_t i = 0; i < lower_dimensional; ++i) lines_.next("a point, curve or surface entity line");
    for (std::int64_t i = 0; i < volumes; ++i) {
      Fields f(lines_, lines_.next("a volume entity line 'tag minX minY minZ maxX maxY maxZ numPhysicalTags ...'"));
      const std::int64_t tag = f.integer("a volume tag", kMinInt32 + 1, kMaxInt32);
      for (const char* what : {"minX", "minY", "minZ", "maxX", "maxY", "maxZ"}) f.real(what);
      const std::int64_t physical_count = f.count("a physical tag count");
      if (physical_count > 0)
        volume_physical_[std::int32_t(tag)] = std::int32_t(f.integer("a physical tag", kMinInt32, kMaxInt32));
    }
    expect_line("$EndEntities");
  }

  // Records that `tag` names the node that will sit at `index` of nodes_.
  void add_tag(std::int64_t tag, std::size_t index, const Fields& f) {
    if (!index_of_tag_.emplace(tag, static_cast<std::int32_t>(index)).second) {
      lines_.expected("a node tag not listed before", f.last());
    }
  }

  std::int32_t node_index(Fields& f) {
    const std::int64_t tag = f.integer("a node tag");
    const auto it = index_of_tag_.find(tag);
    if (it == index_of_tag_.end()) lines_.expected("a node tag listed in $Nodes", f.last());
    return it->second;
  }

  static Vec3 read_point(Fields& f) {
    const double x = f.real("a finite x coordinate");
    const double y = f.real("a finite y coordinate");
    const double z = f.real("a finite z coordinate");
    return {x, y, z};
  }

  // Room for `n` more nodes, but no more than the rest of the text can describe.
  void reserve_nodes(std::int64_t n) {
    nodes_.reserve(nodes_.size() + lines_.reservable(n, kMinNodeBytes));
  }

  static constexpr std::int64_t kMaxTag = std::numeric_limits<std::int64_t>::max();

  // 2.2: a count, then one "tag x y z" line per node.
  void read_nodes_v2() {
    Fields header(lines_, lines_.next("a node count"));
    const std::int64_t n = header.count("a node count");
    header.finish();
    reserve_nodes(n);
    for (std::int64_t i = 0; i < n; ++i) {
      Fields f(lines_, lines_.next("a node line 'tag x y z'"));
      add_tag(f.integer("a node tag", 1, kMaxTag), nodes_.size(), f);
      nodes_.push_back(read_point(f));
      f.finish();
    }
    expect_line("$EndNodes");
  }

  // 4.1: "numEntityBlocks numNodes minTag maxTag", then per block a header
  // "entityDim entityTag parametric numNodesInBlock", the block's tags one per line, then its
  // coordinates one node per line (parametric nodes add u [v [w]], which we ignore).
  void read_nodes_v4() {
    Fields header(lines_, lines_.next("a $Nodes header 'numEntityBlocks numNodes minTag maxTag'"));
    const std::int64_t blocks = header.count("an entity block count");
    const std::int64_t total = header.count("a node count");
    header.integer("a minimum node tag");
    header.integer("a maximum node tag");
    header.finish();
    reserve_nodes(total);
    std::int64_t seen = 0;
    for (std::int64_t b = 0; b < blocks; ++b) {
      Fields block(lines_,
                   lines_.next("a node block header 'entityDim entityTag parametric numNodes'"));
      block.integer("an entity dimension 0 to 3", 0, 3);
      block.integer("an entity tag");
      const bool parametric = block.integer("a parametric flag 0 or 1", 0, 1) == 1;
      const std::int64_t n =
          block.count("a block node count within the $Nodes total", total - seen);
      block.finish();
      seen += n;
      const std::size_t first = nodes_.size();
      for (std::int64_t i = 0; i < n; ++i) {
        Fields f(lines_, lines_.next("a node tag line"));
        add_tag(f.integer("a node tag", 1, kMaxTag), first + static_cast<std::size_t>(i), f);
        f.finish();
      }
      for (std::int64_t i = 0; i < n; ++i) {
        Fields f(lines_, lines_.next("a node coordinate line 'x y z'"));
        nodes_.push_back(read_point(f));
        if (!parametric) f.finish();
      }
    }
    if (seen != total) more_expected("node", total, seen);
    expect_line("$EndNodes");
  }

  // The blocks held fewer records than their section header promised.
  [[noreturn]] void more_expected(const std::string& kind, std::int64_t total, std::int64_t seen) {
    const std::string what = "another " + kind + " block (the header lists " +
                             std::to_string(total) + " " + kind + "s, the blocks " +
                             std::to_string(seen) + ")";
    lines_.expected(what, first_token(lines_.next(what)));
  }

  // 2.2: a count, then "tag type numTags tags... nodes..." per element.
  void read_elements_v2() {
    Fields header(lines_, lines_.next("an element count"));
    const std::int64_t n = header.count("an element count");
    header.finish();
    for (std::int64_t i = 0; i < n; ++i) {
      Fields f(lines_, lines_.next("an element line 'tag type numTags tags... nodes...'"));
      f.integer("an element tag");
      const std::int64_t type = f.integer("an element type");
      const std::int64_t num_tags = f.integer("a tag count", 0, kMaxTag);
      std::int32_t physical = 0;  // the first tag, 0 when there is none
      for (std::int64_t t = 0; t < num_tags; ++t) {
        const std::int64_t value = f.integer("an element tag value");
        if (t == 0) {
          if (value < kMinInt32 || value > kMaxInt32) lines_.expected("a physical tag within int32", f.last());
          physical = std::int32_t(value);
        }
      }
      if (type == kTet4) read_tet(f, physical);
    }
    expect_line("$EndElements");
  }

  // 4.1: "numEntityBlocks numElements minTag maxTag", then per block a header
  // "entityDim entityTag elementType numElementsInBlock" and one "tag nodes..." line per element.
  void read_elements_v4() {
    Fields header(lines_,
                  lines_.next("an $Elements header 'numEntityBlocks numElements minTag maxTag'"));
    const std::int64_t blocks = header.count("an entity block count");
    const std::int64_t total = header.count("an element count");
    header.integer("a minimum element tag");
    header.integer("a maximum element tag");
    header.finish();
    std::int64_t seen = 0;
    for (std::int64_t b = 0; b < blocks; ++b) {
      Fields block(lines_,
                   lines_.next("an element block header 'entityDim entityTag type numElements'"));
      const std::int64_t dimension = block.integer("an entity dimension 0 to 3", 0, 3);
      const std::int64_t entity = block.integer("an entity tag");
      const std::int64_t type = block.integer("an element type");
      const std::int64_t n =
          block.count("a block element count within the $Elements total", total - seen);
      block.finish();
      seen += n;
      for (std::int64_t i = 0; i < n; ++i) {
        Fields f(lines_, lines_.next("an element line 'tag nodes...'"));
        f.integer("an element tag");
        // The volume's entity tag for now; parse() turns it into its physical tag.
        const bool in_volume = dimension == 3 && entity > kMinInt32 && entity <= kMaxInt32;
        if (type == kTet4) read_tet(f, in_volume ? std::int32_t(entity) : kNoEntity);
      }
    }
    if (seen != total) more_expected("element", total, seen);
    expect_line("$EndElements");
  }

  void read_tet(Fields& f, std::int32_t region) {
    Tet t;
    for (auto& v : t) v = node_index(f);
    f.finish();
    tets_.push_back(t);
    regions_.push_back(region);
  }

  // 4.1: a tet block not in a volume entity (no such entity: no physical tag, region 0).
  static constexpr std::int32_t kNoEntity = std::numeric_limits<std::int32_t>::min();

  LineReader lines_;
  Version version_ = Version::Legacy2;
  Vec3List nodes_;                                               // in file order
  std::unordered_map<std::int64_t, std::int32_t> index_of_tag_;  // tag -> position in nodes_
  std::vector<Tet> tets_;                                        // positions in nodes_
  std::vector<std::int32_t> regions_;                            // per tet (4.1: entity tag until parse() ends)
  std::unordered_map<std::int32_t, std::int32_t> volume_physical_;  // 4.1: volume tag -> first physical tag
};

}  // namespace

TetMesh parse_gmsh(std::string_view text, const std::string& name) {
  return GmshParser(text, name).parse();
}

TetMesh read_gmsh(const std::string& path) {
  return parse_gmsh(detail::read_text_file(path), path);
}

}  // namespace mica
