// SPDX-License-Identifier: Apache-2.0
// Bodies: creation from arrays, files and the box generator; read-back; loads; selection;
// tissue regions (materials per tet) and the mesh and its fields (tets, masses, strain, stress).
#include "capi_internal.hpp"
#include "fem/element_fields.hpp"
#include "mesh/mesh_io.hpp"

using namespace mica_capi;

namespace {

mica_body_def body_defaults() {
  mica_body_def d{};
  d.struct_size = sizeof d;
  d.model = MICA_MODEL_COROTATIONAL;
  d.mass = MICA_MASS_CONSISTENT;
  d.youngs_modulus = 1e4;
  d.poisson_ratio = 0.3;
  d.density = 1000;
  d.cutting_resistance = mica::kDefaultCuttingResistance;
  return d;
}

struct BodyInput {
  mica::BodySettings settings;
  mica::Vec3 translation, velocity;
  double cutting_resistance;  // N/m, every tet
};

BodyInput translate(const mica_body_def* def) {
  const mica_body_def d = read_def(def, body_defaults(), "def");
  if (d.model != MICA_MODEL_COROTATIONAL && d.model != MICA_MODEL_LINEAR && d.model != MICA_MODEL_NEO_HOOKEAN)
    refuse(MICA_ERR_INVALID_ARGUMENT, "def->model is " + std::to_string(d.model) +
                                          ", not a MICA_MODEL_* value (COROTATIONAL 0, LINEAR 1, NEO_HOOKEAN 2)");
  if (d.mass != MICA_MASS_CONSISTENT && d.mass != MICA_MASS_LUMPED)
    refuse(MICA_ERR_INVALID_ARGUMENT, "def->mass is " + std::to_string(d.mass) + ", not a MICA_MASS_* value");
  if (d.is_static != 0 && d.is_static != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "def->is_static must be 0 or 1");
  BodyInput in;
  in.settings.material = {d.youngs_modulus, d.poisson_ratio, d.density};
  in.settings.rayleigh_alpha = d.rayleigh_alpha;
  in.settings.rayleigh_beta = d.rayleigh_beta;
  in.settings.mass = d.mass == MICA_MASS_LUMPED ? mica::MassKind::Lumped : mica::MassKind::Consistent;
  in.settings.model = d.model == MICA_MODEL_COROTATIONAL ? mica::ElasticModel::Corotational
                     : d.model == MICA_MODEL_LINEAR    ? mica::ElasticModel::Linear
                                                       : mica::ElasticModel::NeoHookean;
  in.settings.is_static = d.is_static == 1;
  in.translation = vec3(d.translation, "def->translation");
  in.velocity = vec3(d.velocity, "def->velocity");
  if (!(d.cutting_resistance >= 0) || !std::isfinite(d.cutting_resistance))
    refuse(MICA_ERR_INVALID_ARGUMENT, "def->cutting_resistance is " + mica::number_text(d.cutting_resistance) +
                                          " N/m, must be finite and >= 0");
  in.cutting_resistance = d.cutting_resistance;
  return in;
}

// Adds the body; a body created deep inside another is made, and reported with
// MICA_WARN_BODIES_OVERLAP and the message (the core logged it).
mica_status create(mica_world* world, const mica_body_def* def, const mica::TetMesh& mesh, const char* function,
                   mica_body_id* out) {
  const BodyInput in = translate(def);
  *out = world->world.add_body(mesh, in.settings, in.translation, in.velocity);
  if (in.cutting_resistance != mica::kDefaultCuttingResistance)
    world->world.set_cutting_resistance(*out, std::vector<double>(mesh.tets.size(), in.cutting_resistance));
  const std::vector<mica::BodyOverlap>& overlaps = world->world.overlaps_at_creation();
  if (overlaps.empty()) return MICA_OK;
  try {
    std::string message = std::string(function) + ": " + world->world.overlap_message(*out, overlaps.front());
    if (overlaps.size() > 1) message += " (and " + std::to_string(overlaps.size() - 1) + " more bodies, in the log)";
    world->last_error = std::move(message);
  } catch (...) {
    // Out of memory for the message: the status still says it.
  }
  return MICA_WARN_BODIES_OVERLAP;
}

void check_count(int32_t count, int32_t min, const char* name) {
  if (count < min) refuse(MICA_ERR_INVALID_ARGUMENT, std::string(name) + " is " + std::to_string(count) + ", must be >= " + std::to_string(min));
}

// Node indices from the caller, unchecked: the core checks them against the body.
std::vector<int32_t> node_list(const int32_t* nodes, int32_t count) { return {nodes, nodes + count}; }

template <class Select>
mica_status select_nodes(const mica::Body& b, int32_t use_rest, int32_t* out, int32_t capacity, int32_t* out_count,
                         Select&& inside) {
  if (use_rest != 0 && use_rest != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "use_rest must be 0 or 1");
  const mica::Vec3List& p = use_rest ? b.fem.rest : b.x;
  std::vector<int32_t> found;
  for (size_t i = 0; i < p.size(); ++i)
    if (inside(p[i])) found.push_back(int32_t(i));
  return copy_out(found.data(), int32_t(found.size()), 1, out, capacity, out_count);
}

// 3 * node_count values of a body as node vectors; the count is checked before anything is read
// (the core checks that every value is finite).
mica::Vec3List node_values(const mica::Body& b, const double* xyz, int32_t node_count) {
  require(xyz, "xyz");
  if (node_count != b.fem.node_count())
    refuse(MICA_ERR_INVALID_ARGUMENT, "node_count is " + std::to_string(node_count) + ", " + b.name + " has " +
                                          std::to_string(b.fem.node_count()) + " nodes");
  mica::Vec3List values(static_cast<size_t>(node_count));
  for (size_t i = 0; i < values.size(); ++i) values[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  return values;
}

}  // namespace

extern "C" {

MICA_API mica_status mica_body_def_init(mica_body_def* def, uint32_t struct_size) {
  return init_def(def, struct_size, body_defaults(), "mica_body_def_init");
}

MICA_API mica_status mica_body_create(mica_world* world, const mica_body_def* def, const double* nodes,
                                      int32_t node_count, const int32_t* tets, int32_t tet_count,
                                      mica_body_id* out_body) {
  return guarded(world, "mica_body_create", [&] {
    require(world, "world");
    require(out_body, "out_body");
    require(nodes, "nodes");
    require(tets, "tets");
    check_count(node_count, 4, "node_count");
    check_count(tet_count, 1, "tet_count");
    if (node_count > INT32_MAX / 3) refuse(MICA_ERR_INVALID_ARGUMENT, "node_count is too large");
    mica::TetMesh mesh;
    mesh.nodes.resize(size_t(node_count));
    for (int32_t i = 0; i < node_count; ++i) mesh.nodes[i] = {nodes[3 * i], nodes[3 * i + 1], nodes[3 * i + 2]};
    mesh.tets.resize(size_t(tet_count));
    for (int32_t e = 0; e < tet_count; ++e)
      for (int a = 0; a < 4; ++a) mesh.tets[e][a] = tets[4 * int64_t(e) + a];
    return create(world, def, mesh, "mica_body_create", out_body);
  });
}

MICA_API mica_status mica_body_create_from_file(mica_world* world, const mica_body_def* def, const char* path,
                                                mica_body_id* out_body) {
  return guarded(world, "mica_body_create_from_file", [&] {
    require(world, "world");
    require(out_body, "out_body");
    require(path, "path");
    return create(world, def, mica::load_mesh(path), "mica_body_create_from_file", out_body);
  });
}

MICA_API mica_status mica_body_create_box(mica_world* world, const mica_body_def* def, const double lo[3],
                                          const double hi[3], const int32_t cells[3], int32_t tets_per_cell,
                                          mica_body_id* out_body) {
  return guarded(world, "mica_body_create_box", [&] {
    require(world, "world");
    require(out_body, "out_body");
    require(cells, "cells");
    const mica::TetMesh mesh =
        mica::make_box_grid(vec3(lo, "lo"), vec3(hi, "hi"), {cells[0], cells[1], cells[2]}, tets_per_cell);
    return create(world, def, mesh, "mica_body_create_box", out_body);
  });
}

MICA_API mica_status mica_body_destroy(mica_world* world, mica_body_id body) {
  return guarded(world, "mica_body_destroy", [&] {
    require(world, "world");
    world->world.remove_body(body);
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_get_counts(const mica_world* world, mica_body_id body, int32_t* node_count,
                                          int32_t* tet_count, int32_t* triangle_count) {
  return guarded(world, "mica_body_get_counts", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    if (node_count) *node_count = b.fem.node_count();
    if (tet_count) *tet_count = int32_t(b.tets.size());
    if (triangle_count) *triangle_count = int32_t(b.surface.size());
    return MICA_OK;
  });
}

#define MICA_NODE_GETTER(function, field)                                                                 \
  MICA_API mica_status function(const mica_world* world, mica_body_id body, double* out, int32_t capacity, \
                                int32_t* out_count) {                                                     \
    return guarded(world, #function, [&] {                                                                \
      require(world, "world");                                                                            \
      const mica::Body& b = world->world.body(body);                                                      \
      return copy_out(b.field[0].data(), b.fem.node_count(), 3, out, capacity, out_count);               \
    });                                                                                                   \
  }
MICA_NODE_GETTER(mica_body_get_positions, x)
MICA_NODE_GETTER(mica_body_get_velocities, v)
MICA_NODE_GETTER(mica_body_get_rest_positions, fem.rest)
#undef MICA_NODE_GETTER

MICA_API mica_status mica_body_get_surface(const mica_world* world, mica_body_id body, int32_t* out, int32_t capacity,
                                           int32_t* out_count) {
  return guarded(world, "mica_body_get_surface", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    return copy_out(b.surface.empty() ? nullptr : b.surface[0].data(), int32_t(b.surface.size()), 3, out, capacity,
                    out_count);
  });
}

MICA_API mica_status mica_body_positions_view(const mica_world* world, mica_body_id body, const double** out,
                                              int32_t* out_node_count) {
  return guarded(world, "mica_body_positions_view", [&] {
    require(world, "world");
    require(out, "out");
    const mica::Body& b = world->world.body(body);
    *out = b.x[0].data();
    if (out_node_count) *out_node_count = b.fem.node_count();
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_set_node_forces(mica_world* world, mica_body_id body, const int32_t* nodes,
                                               const double* forces, int32_t count) {
  return guarded(world, "mica_body_set_node_forces", [&] {
    require(world, "world");
    check_count(count, 0, "count");
    if (count > 0) {
      require(nodes, "nodes");
      require(forces, "forces");
    }
    mica::Vec3List f(static_cast<size_t>(count));
    for (int32_t k = 0; k < count; ++k) f[k] = {forces[3 * k], forces[3 * k + 1], forces[3 * k + 2]};
    world->world.set_node_forces(body, count ? node_list(nodes, count) : std::vector<int32_t>{}, f);
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_select_nodes_in_box(const mica_world* world, mica_body_id body, const double lo[3],
                                                   const double hi[3], int32_t use_rest, int32_t* out,
                                                   int32_t capacity, int32_t* out_count) {
  return guarded(world, "mica_body_select_nodes_in_box", [&] {
    require(world, "world");
    const mica::Vec3 l = vec3(lo, "lo"), h = vec3(hi, "hi");
    if (!l.allFinite() || !h.allFinite()) refuse(MICA_ERR_INVALID_ARGUMENT, "the box corners must be finite");
    return select_nodes(world->world.body(body), use_rest, out, capacity, out_count, [&](const mica::Vec3& p) {
      return (p.array() >= l.array()).all() && (p.array() <= h.array()).all();
    });
  });
}

MICA_API mica_status mica_body_select_nodes_by_plane(const mica_world* world, mica_body_id body,
                                                     const double point[3], const double normal[3],
                                                     double tolerance, int32_t use_rest, int32_t* out,
                                                     int32_t capacity, int32_t* out_count) {
  return guarded(world, "mica_body_select_nodes_by_plane", [&] {
    require(world, "world");
    const mica::Vec3 o = vec3(point, "point"), n = vec3(normal, "normal");
    if (!o.allFinite() || !(n.norm() > 0) || !std::isfinite(n.norm()) || !std::isfinite(tolerance))
      refuse(MICA_ERR_INVALID_ARGUMENT, "the plane needs a finite point, a finite non-zero normal and a finite tolerance");
    const mica::Vec3 u = n.normalized();
    return select_nodes(world->world.body(body), use_rest, out, capacity, out_count,
                        [&](const mica::Vec3& p) { return (p - o).dot(u) <= tolerance; });
  });
}

MICA_API mica_status mica_body_get_energy(const mica_world* world, mica_body_id body, double* kinetic,
                                          double* elastic, double* potential) {
  return guarded(world, "mica_body_get_energy", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    if (kinetic) *kinetic = mica::kinetic_energy(b.fem, b.v);
    if (elastic) *elastic = mica::elastic_energy(b.fem, b.x, b.settings.model);
    if (potential) {
      double u = 0;
      for (size_t i = 0; i < b.x.size(); ++i) u -= b.fem.node_mass[i] * world->world.settings().gravity.dot(b.x[i]);
      *potential = u;
    }
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_set_positions(mica_world* world, mica_body_id body, const double* xyz,
                                             int32_t node_count) {
  return guarded(world, "mica_body_set_positions", [&] {
    require(world, "world");
    world->world.set_positions(body, node_values(world->world.body(body), xyz, node_count));
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_set_velocities(mica_world* world, mica_body_id body, const double* xyz,
                                              int32_t node_count) {
  return guarded(world, "mica_body_set_velocities", [&] {
    require(world, "world");
    world->world.set_velocities(body, node_values(world->world.body(body), xyz, node_count));
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_get_tets(const mica_world* world, mica_body_id body, int32_t* out, int32_t capacity,
                                        int32_t* out_count) {
  return guarded(world, "mica_body_get_tets", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    return copy_out(b.tets[0].data(), int32_t(b.tets.size()), 4, out, capacity, out_count);
  });
}

MICA_API mica_status mica_body_get_tet_regions(const mica_world* world, mica_body_id body, int32_t* out,
                                               int32_t capacity, int32_t* out_count) {
  return guarded(world, "mica_body_get_tet_regions", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    return copy_out(b.regions.data(), int32_t(b.regions.size()), 1, out, capacity, out_count);
  });
}

MICA_API mica_status mica_body_set_materials(mica_world* world, mica_body_id body, const double* youngs_modulus,
                                             const double* poisson_ratio, const double* density, int32_t tet_count) {
  return guarded(world, "mica_body_set_materials", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    const int32_t tets = int32_t(b.tets.size());
    if (tet_count != tets)
      refuse(MICA_ERR_INVALID_ARGUMENT, "tet_count is " + std::to_string(tet_count) + ", the body has " +
                                            std::to_string(tets) + " tets (one material per tet)");
    std::vector<mica::Material> materials = b.fem.materials;  // a NULL array keeps that property
    for (int32_t e = 0; e < tets; ++e) {
      if (youngs_modulus) materials[e].youngs_modulus = youngs_modulus[e];
      if (poisson_ratio) materials[e].poisson_ratio = poisson_ratio[e];
      if (density) materials[e].density = density[e];
    }
    world->world.set_body_materials(body, materials);
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_remove_tets(mica_world* world, mica_body_id body, const int32_t* tets, int32_t count,
                                          double* out_removed_mass) {
  return guarded(world, "mica_body_remove_tets", [&] {
    require(world, "world");
    check_count(count, 0, "count");
    if (count > 0) require(tets, "tets");
    world->world.body(body);  // throws for a stale id
    // The body's render meshes follow the change (follow_topology, capi/embedding.cpp).
    world->topology_warning.clear();
    const double removed = world->world.remove_tets(body, count ? node_list(tets, count) : std::vector<int32_t>{});
    if (out_removed_mass) *out_removed_mass = removed;
    return topology_warning(world, "mica_body_remove_tets");
  });
}

MICA_API mica_status mica_body_cut(mica_world* world, mica_body_id body, const double* triangles,
                                   int32_t triangle_count, int32_t* out_faces_cut, int32_t* out_nodes_added) {
  return guarded(world, "mica_body_cut", [&] {
    require(world, "world");
    check_count(triangle_count, 0, "triangle_count");
    if (triangle_count > 0) require(triangles, "triangles");
    world->world.body(body);  // throws for a stale id
    // The body's render meshes follow the change (follow_topology, capi/embedding.cpp).
    world->topology_warning.clear();
    mica::Vec3List corners(size_t(triangle_count) * 3);
    for (size_t k = 0; k < corners.size(); ++k) corners[k] = mica::Vec3(triangles[3 * k], triangles[3 * k + 1], triangles[3 * k + 2]);
    const mica::World::CutResult r = world->world.cut(body, corners);
    if (out_faces_cut) *out_faces_cut = r.faces;
    if (out_nodes_added) *out_nodes_added = r.nodes_added;
    return topology_warning(world, "mica_body_cut");
  });
}

MICA_API mica_status mica_body_set_cutting_resistance(mica_world* world, mica_body_id body, const double* per_tet,
                                                      int32_t tet_count) {
  return guarded(world, "mica_body_set_cutting_resistance", [&] {
    require(world, "world");
    require(per_tet, "per_tet");
    check_count(tet_count, 0, "tet_count");
    world->world.set_cutting_resistance(body, std::vector<double>(per_tet, per_tet + tet_count));
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_get_topology_version(const mica_world* world, mica_body_id body, uint64_t* out) {
  return guarded(world, "mica_body_get_topology_version", [&] {
    require(world, "world");
    require(out, "out");
    *out = world->world.body(body).topology_version;
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_get_node_masses(const mica_world* world, mica_body_id body, double* out,
                                               int32_t capacity, int32_t* out_count) {
  return guarded(world, "mica_body_get_node_masses", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    return copy_out(b.fem.node_mass.data(), b.fem.node_count(), 1, out, capacity, out_count);
  });
}

MICA_API mica_status mica_body_get_strains(const mica_world* world, mica_body_id body, double* out, int32_t capacity,
                                           int32_t* out_count) {
  return guarded(world, "mica_body_get_strains", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    const int32_t tets = int32_t(b.tets.size());
    if (!out || capacity < tets) return copy_out<double>(nullptr, tets, 6, out, capacity, out_count);
    std::vector<mica::Mat3> strain;
    mica::element_strains(b.fem, b.x, b.settings.model, strain);
    std::vector<double> voigt(size_t(6) * size_t(tets));
    for (int32_t e = 0; e < tets; ++e) {  // xx yy zz yz xz xy, tensor (not engineering) shears
      const mica::Mat3& s = strain[e];
      const double v[6] = {s(0, 0), s(1, 1), s(2, 2), s(1, 2), s(0, 2), s(0, 1)};
      std::copy(v, v + 6, voigt.begin() + 6 * int64_t(e));
    }
    return copy_out(voigt.data(), tets, 6, out, capacity, out_count);
  });
}

MICA_API mica_status mica_body_get_von_mises(const mica_world* world, mica_body_id body, double* out,
                                             int32_t capacity, int32_t* out_count) {
  return guarded(world, "mica_body_get_von_mises", [&] {
    require(world, "world");
    const mica::Body& b = world->world.body(body);
    const int32_t tets = int32_t(b.tets.size());
    if (!out || capacity < tets) return copy_out<double>(nullptr, tets, 1, out, capacity, out_count);
    std::vector<double> stress;
    mica::element_von_mises(b.fem, b.x, b.settings.model, stress);
    return copy_out(stress.data(), tets, 1, out, capacity, out_count);
  });
}

}  // extern "C"
