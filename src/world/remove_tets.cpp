// SPDX-License-Identifier: Apache-2.0
// Resection: a body loses some of its tets. Everything that depends on the topology follows in
// the same call:
//  - the model (FEM with the kept tets' materials, mass, surface, surface nodes, pseudo-normals,
//    colourings) is built again from the kept tets, in their order; nodes left without a tet go
//    and the others are renumbered in their order;
//  - the state (x, v, v_previous, node forces) is carried over to the new numbering; the
//    end-of-step rotations are dropped;
//  - constraints: removed nodes leave their group, kept ones are renumbered (a handle's offsets
//    follow their nodes), a group left with no node is destroyed;
//  - the solver's caches of the body, the warm starts of its contacts and the last step's
//    contacts readout (whose indices name the old nodes) are dropped.
// Everything new is built first; the swap that follows cannot throw, so a failed call changes
// nothing.
#include <algorithm>

#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

// What the kept tets make of a body: the new mesh, and each old node's new index (-1: removed).
struct KeptMesh {
  TetMesh mesh;
  std::vector<Material> materials;
  std::vector<int32_t> new_index;
  std::vector<int32_t> old_index;  // per new node
  std::vector<int32_t> old_tet;    // per new tet
  double removed_mass = 0;         // kg
};

void check_removal(const Body& b, const std::vector<int32_t>& tets) {
  const int32_t count = int32_t(b.tets.size());
  std::vector<int32_t> position(size_t(count), -1);
  for (size_t k = 0; k < tets.size(); ++k) {
    const int32_t e = tets[k];
    if (e < 0 || e >= count)
      fail(Errc::OutOfRange, b.name + ": tet index " + std::to_string(e) + " at position " + std::to_string(k) +
                                 " is outside 0.." + std::to_string(count - 1));
    if (position[size_t(e)] >= 0)
      fail(Errc::InvalidArgument, b.name + ": tet " + std::to_string(e) + " is listed twice (positions " +
                                      std::to_string(position[size_t(e)]) + " and " + std::to_string(k) + ")");
    position[size_t(e)] = int32_t(k);
  }
  if (tets.size() == size_t(count))
    fail(Errc::InvalidArgument, "removing every tet would leave " + b.name + " without tets: destroy the body instead");
}

KeptMesh kept_mesh(const Body& b, const std::vector<int32_t>& tets) {
  KeptMesh k;
  std::vector<uint8_t> removed(b.tets.size(), 0);
  for (int32_t e : tets) removed[size_t(e)] = 1;
  // The removed mass: rho V of each removed tet (the lumped and consistent masses both sum to it).
  for (int32_t e : tets) k.removed_mass += b.fem.materials[size_t(e)].density * b.fem.elements[size_t(e)].volume;
  std::vector<uint8_t> used(size_t(b.fem.node_count()), 0);
  for (size_t e = 0; e < b.tets.size(); ++e)
    if (!removed[e])
      for (int32_t i : b.tets[e]) used[size_t(i)] = 1;
  k.new_index.assign(used.size(), -1);
  for (size_t i = 0; i < used.size(); ++i)
    if (used[i]) {
      k.new_index[i] = int32_t(k.old_index.size());
      k.old_index.push_back(int32_t(i));
      k.mesh.nodes.push_back(b.fem.rest[i]);
    }
  for (size_t e = 0; e < b.tets.size(); ++e) {
    if (removed[e]) continue;
    Tet t = b.tets[e];
    for (int32_t& i : t) i = k.new_index[size_t(i)];
    k.mesh.tets.push_back(t);
    k.mesh.regions.push_back(b.regions[e]);
    k.materials.push_back(b.fem.materials[e]);
    k.old_tet.push_back(int32_t(e));
  }
  return k;
}

// A constraint group's nodes (and handle offsets) in the new numbering.
struct RenumberedLpc {
  Id id;
  std::vector<int32_t> nodes;
  Vec3List offsets;
};

}  // namespace

double World::remove_tets(Id id, const std::vector<int32_t>& tets) {
  Body& b = body(id);
  check_removal(b, tets);
  if (tets.empty()) return 0;
  KeptMesh k = kept_mesh(b, tets);

  // Constraints on the body, renumbered; the groups left empty are destroyed, unless driven.
  std::vector<RenumberedLpc> kept;
  std::vector<Id> emptied;
  lpcs_.for_each([&](Id lpc, const Lpc& c) {
    if (c.body != id) return;
    RenumberedLpc r{lpc, {}, {}};
    for (size_t j = 0; j < c.nodes.size(); ++j) {
      const int32_t i = k.new_index[size_t(c.nodes[j])];
      if (i < 0) continue;
      r.nodes.push_back(i);
      if (c.handle) r.offsets.push_back(c.handle->offsets[j]);
    }
    if (r.nodes.empty())
      emptied.push_back(lpc);
    else
      kept.push_back(std::move(r));
  });
  for (Id lpc : emptied)
    devices_.for_each([&](Id, const DeviceLink& link) {
      if (link.settings().lpc == lpc)
        fail(Errc::WrongState, "the removal would leave a grasp a device drives without nodes: destroy the device first");
    });

  // The new body: its model from the kept tets, the state carried over, fresh scratch.
  auto fresh = std::make_unique<Body>(k.mesh, b.settings, b.name, b.key);
  fresh->fem = build_fem_model(k.mesh, k.materials, b.settings.mass, b.name);  // the per-tet materials
  colour_for_threads(*fresh);
  for (size_t i = 0; i < k.old_index.size(); ++i) {
    const size_t o = size_t(k.old_index[i]);
    fresh->x[i] = b.x[o];
    fresh->v[i] = b.v[o];
    fresh->v_previous[i] = b.v_previous[o];
    fresh->node_forces[i] = b.node_forces[o];
    fresh->has_node_forces = fresh->has_node_forces || !fresh->node_forces[i].isZero(0);
  }
  fresh->bvh.build(fresh->x, fresh->surface);
  fresh->lpc_version = b.lpc_version + 1;
  fresh->topology_version = b.topology_version + 1;
  fresh->matrix_version = b.matrix_version + 1;
  TopologyChange change;
  change.body = id;
  change.topology_version = fresh->topology_version;
  change.node_origin = std::move(k.old_index);
  change.tet_origin = std::move(k.old_tet);
  const std::vector<uint64_t> stale = contact_row_keys(id);
  lpcs_.reserve_free();  // so that erase below allocates nothing

  // Nothing below throws.
  solver_->forget(b.key);  // its factors (one may be in the making on the body's pattern) first
  for (uint64_t key : stale) warm_start_.erase(key);
  for (RenumberedLpc& r : kept) {
    Lpc& c = lpcs_.get(r.id, "constraint");
    c.nodes.swap(r.nodes);
    if (c.handle) c.handle->offsets.swap(r.offsets);
  }
  for (Id lpc : emptied) lpcs_.erase(lpc);
  bodies_.replace(id, std::move(fresh));  // the old body goes here
  // The readout's node and row indices are of the old numbering.
  last_.contacts.clear();
  last_.rows.clear();
  last_.lambda.clear();
  last_.curvature_impulse.clear();
  last_.debt = 0;
  if (topology_listener_) topology_listener_(change, body(id));
  if (recorder_) recorder_->write(RecordKind::RemoveTets, id, tets);
  return k.removed_mass;
}

}  // namespace mica
