// SPDX-License-Identifier: Apache-2.0
// What follows a change of a body's tets (World::adopt_topology), whoever made it:
//  - the model (FEM with each new tet's material, mass, surface, surface nodes, pseudo-normals,
//    colourings) is built from the new mesh;
//  - the state (x, v, v_previous) of each new node is its origin's (a cut node's copies start
//    where it was, at its velocity, and share its force); the end-of-step rotations are dropped;
//  - constraints: a held node's copies are all held (a handle's offset is copied with it), a node
//    that is gone leaves its group, a group left with no node is destroyed;
//  - the solver's caches of the body, the warm starts of its contacts and the last step's
//    contacts readout (whose indices name the old nodes) are dropped.
// Everything new is built first; the swap that follows cannot throw, so a failed change changes
// nothing.
#include "world/world.hpp"

namespace mica {

namespace {

// A constraint group's nodes (and handle offsets) in the new numbering.
struct RenumberedLpc {
  Id id;
  std::vector<int32_t> nodes;
  Vec3List offsets;
};

}  // namespace

void World::adopt_topology(Id id, NewTopology& t) {
  Body& b = body(id);
  const std::vector<int32_t>& origin = t.change.node_origin;
  // Each old node's copies, in the new numbering (none: the node is gone).
  std::vector<int32_t> copy_start(b.x.size() + 1, 0), copies(origin.size());
  for (int32_t o : origin) ++copy_start[size_t(o) + 1];
  for (size_t i = 1; i < copy_start.size(); ++i) copy_start[i] += copy_start[i - 1];
  {
    std::vector<int32_t> fill(copy_start.begin(), copy_start.end() - 1);
    for (size_t i = 0; i < origin.size(); ++i) copies[size_t(fill[size_t(origin[i])]++)] = int32_t(i);
  }

  // Constraints on the body, renumbered; the groups left empty are destroyed, unless driven.
  std::vector<RenumberedLpc> kept;
  std::vector<Id> emptied;
  lpcs_.for_each([&](Id lpc, const Lpc& c) {
    if (c.body != id) return;
    RenumberedLpc r{lpc, {}, {}};
    for (size_t j = 0; j < c.nodes.size(); ++j) {
      const size_t o = size_t(c.nodes[j]);
      for (int32_t k = copy_start[o]; k < copy_start[o + 1]; ++k) {
        r.nodes.push_back(copies[size_t(k)]);
        if (c.handle) r.offsets.push_back(c.handle->offsets[j]);
      }
    }
    if (r.nodes.empty())
      emptied.push_back(lpc);
    else
      kept.push_back(std::move(r));
  });
  for (Id lpc : emptied)
    devices_.for_each([&](Id, const DeviceLink& link) {
      if (link.settings().lpc == lpc)
        fail(Errc::WrongState, "the change would leave a grasp a device drives without nodes: destroy the device first");
    });

  // The new body: its model from the new mesh, the state carried over, fresh scratch.
  auto fresh = std::make_unique<Body>(t.mesh, t.materials, b.settings, b.name, b.key);
  // Its factor is made in the background within a few steps (LaggedFactor::kBridgeSteps), and
  // without a factor to bridge (the exact solver, a body not stepped yet) by its next step: AMD
  // alone, no 20 ms of nested dissection.
  fresh->fem.pattern.fill_ordering = FillOrdering::Amd;
  colour_for_threads(*fresh);
  for (size_t i = 0; i < origin.size(); ++i) {
    const size_t o = size_t(origin[i]);
    fresh->x[i] = b.x[o];
    fresh->v[i] = b.v[o];
    fresh->v_previous[i] = b.v_previous[o];
    fresh->node_forces[i] = b.node_forces[o] / double(copy_start[o + 1] - copy_start[o]);  // the copies share it
    fresh->has_node_forces = fresh->has_node_forces || !fresh->node_forces[i].isZero(0);
  }
  for (size_t e = 0; e < t.change.tet_origin.size(); ++e)
    fresh->cutting_resistance[e] = b.cutting_resistance[size_t(t.change.tet_origin[e])];
  fresh->bvh.build(fresh->x, fresh->surface);
  fresh->lpc_version = b.lpc_version + 1;
  fresh->topology_version = b.topology_version + 1;
  fresh->matrix_version = b.matrix_version + 1;
  t.change.body = id;
  t.change.topology_version = fresh->topology_version;
  const std::vector<uint64_t> stale = contact_row_keys(id);
  lpcs_.reserve_free();  // so that erase below allocates nothing

  // Nothing below throws.
  // Its factors go on as a bridge to the new nodes (one in the making on the old pattern is waited for).
  solver_->remap(b.key, BodyRemap{b.fem, fresh->fem, origin, t.change.tet_origin, fresh->lpc_version,
                                 !b.settings.neo_hookean()});
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
  if (topology_listener_) topology_listener_(t.change, body(id));
}

}  // namespace mica
