// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the whole load path of a body. The input is Gmsh text when its first
// non-blank byte is '$', else TetGen (.node, NUL byte, .ele as in fuzz_tetgen), so both seed
// corpora work unchanged. A parsed mesh goes through validate_topology, check_rest_quality,
// extract_surface and build_fem_model (consistent mass for an even input length, lumped for
// an odd one). A model that build_fem_model returns must be usable: finite positive volumes,
// finite shape-function gradients and rest inverse, finite positive masses, and finite
// rotations, forces and stiffness at rest. A mesh that cannot give such a model must be
// rejected with mica::Error, not handed on to the solver.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fem/fem_model.hpp"
#include "fuzz_common.hpp"
#include "mesh/mesh_io.hpp"

namespace {

using mica_fuzz::bug;

bool is_gmsh(std::string_view text) {
  const std::size_t first = text.find_first_not_of(" \t\r\n\v\f");
  return first != std::string_view::npos && text[first] == '$';
}

mica::TetMesh parse(std::string_view text) {
  if (is_gmsh(text)) return mica::parse_gmsh(text, "fuzz.msh");
  const mica_fuzz::TetgenTexts in = mica_fuzz::split_tetgen(text);
  return mica::parse_tetgen(in.node, in.ele, "fuzz.node", "fuzz.ele");
}

bool finite(const mica::Mat3& m) { return m.allFinite(); }

void check_model(const mica::TetMesh& mesh, const mica::FemModel& m) {
  const auto n = static_cast<std::size_t>(m.node_count());
  if (n != mesh.nodes.size() || m.elements.size() != mesh.tets.size()) {
    bug("FEM model sizes differ from the mesh");
  }
  if (!(m.quality.min_volume > 0) || !std::isfinite(m.quality.min_volume)) {
    bug("accepted mesh with min rest volume " + std::to_string(m.quality.min_volume));
  }
  for (std::size_t e = 0; e < m.elements.size(); ++e) {
    const mica::TetElement& el = m.elements[e];
    const std::string at = "element " + std::to_string(e) + ": ";
    if (!(el.volume > 0) || !std::isfinite(el.volume)) {
      bug(at + "rest volume " + std::to_string(el.volume) + " accepted");
    }
    if (!finite(el.dm_inv)) bug(at + "non-finite inverse rest matrix dm_inv accepted");
    for (const mica::Vec3& g : el.grad) {
      if (!g.allFinite()) bug(at + "non-finite shape-function gradient accepted");
    }
    for (const std::int32_t slot : m.slots[e]) {
      if (slot < 0 || static_cast<std::size_t>(slot) >= m.mass.size()) {
        bug(at + "block slot out of range");
      }
    }
  }
  for (const double mass : m.mass) {
    if (!std::isfinite(mass)) bug("non-finite mass matrix entry " + std::to_string(mass));
  }
  for (std::size_t i = 0; i < m.node_mass.size(); ++i) {
    if (!(m.node_mass[i] > 0) || !std::isfinite(m.node_mass[i])) {
      bug("node " + std::to_string(i) + " has mass " + std::to_string(m.node_mass[i]));
    }
  }
  const double total = m.total_mass();
  if (!(total > 0) || !std::isfinite(total)) bug("total mass " + std::to_string(total));

  // The first thing a solver does with the model: rotations, forces and stiffness at rest.
  // At rest every rotation is a rotation, and forces and stiffness are finite.
  std::vector<mica::Mat3> R(m.elements.size());
  mica::compute_rotations(m, m.rest, R);
  for (std::size_t e = 0; e < R.size(); ++e) {
    if (!finite(R[e])) bug("element " + std::to_string(e) + ": non-finite rotation at rest");
  }
  mica::BlockValues K(m.pattern.block_count(), mica::Mat3::Zero());
  mica::Vec3List f(n);
  mica::assemble_elastic(m, m.rest, &R, 1.0, &K, f);
  for (const mica::Vec3& fi : f) {
    if (!fi.allFinite()) bug("non-finite elastic force at rest");
  }
  for (const mica::Mat3& k : K) {
    if (!finite(k)) bug("non-finite stiffness block at rest");
  }
}

void load(std::string_view text, mica::MassKind mass_kind) {
  const mica::TetMesh mesh = parse(text);
  mica_fuzz::check_parsed_mesh(mesh);
  mica::validate_topology(mesh, "fuzz");
  const mica::QualityReport quality = mica::check_rest_quality(mesh, "fuzz");
  if (!(quality.min_volume > 0) || !std::isfinite(quality.worst_aspect)) {
    bug("check_rest_quality accepted min volume " + std::to_string(quality.min_volume) +
        ", worst aspect " + std::to_string(quality.worst_aspect));
  }
  const auto surface = mica::extract_surface(mesh);
  const auto n = static_cast<std::int32_t>(mesh.nodes.size());
  for (const mica::Tri& t : surface) {
    for (const std::int32_t v : t) {
      if (v < 0 || v >= n) bug("surface triangle index out of range");
    }
  }
  mica::surface_nodes(surface);
  const mica::FemModel model = mica::build_fem_model(mesh, mica::Material{}, mass_kind, "fuzz");
  check_model(mesh, model);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text = mica_fuzz::as_text(data, size);
  const auto mass_kind = size % 2 == 0 ? mica::MassKind::Consistent : mica::MassKind::Lumped;
  mica_fuzz::run_guarded([&] { load(text, mass_kind); }, [](const mica::Error&) {});
  return 0;
}
