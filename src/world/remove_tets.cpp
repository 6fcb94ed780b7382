// SPDX-License-Identifier: Apache-2.0
// Resection: a body loses some of its tets. The kept tets keep their order; nodes left without a
// tet go and the others are renumbered in their order. What depends on the topology follows in
// World::adopt_topology (topology_change.cpp); a refused call changes nothing.
#include <algorithm>

#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

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

// The kept tets' mesh, each new node's and tet's origin; the removed mass (kg).
NewTopology kept_mesh(const Body& b, const std::vector<int32_t>& tets, double& removed_mass) {
  NewTopology k;
  std::vector<uint8_t> removed(b.tets.size(), 0);
  for (int32_t e : tets) removed[size_t(e)] = 1;
  // The removed mass: rho V of each removed tet (the lumped and consistent masses both sum to it).
  removed_mass = 0;
  for (int32_t e : tets) removed_mass += b.fem.materials[size_t(e)].density * b.fem.elements[size_t(e)].volume;
  std::vector<uint8_t> used(size_t(b.fem.node_count()), 0);
  for (size_t e = 0; e < b.tets.size(); ++e)
    if (!removed[e])
      for (int32_t i : b.tets[e]) used[size_t(i)] = 1;
  std::vector<int32_t> new_index(used.size(), -1);
  for (size_t i = 0; i < used.size(); ++i)
    if (used[i]) {
      new_index[i] = int32_t(k.change.node_origin.size());
      k.change.node_origin.push_back(int32_t(i));
      k.mesh.nodes.push_back(b.fem.rest[i]);
    }
  for (size_t e = 0; e < b.tets.size(); ++e) {
    if (removed[e]) continue;
    Tet t = b.tets[e];
    for (int32_t& i : t) i = new_index[size_t(i)];
    k.mesh.tets.push_back(t);
    k.mesh.regions.push_back(b.regions[e]);
    k.materials.push_back(b.fem.materials[e]);
    k.change.tet_origin.push_back(int32_t(e));
  }
  return k;
}

}  // namespace

double World::remove_tets(Id id, const std::vector<int32_t>& tets) {
  const Body& b = body(id);
  check_removal(b, tets);
  if (tets.empty()) return 0;
  double removed_mass = 0;
  NewTopology k = kept_mesh(b, tets, removed_mass);
  adopt_topology(id, k);
  if (recorder_) recorder_->write(RecordKind::RemoveTets, id, tets);
  return removed_mass;
}

}  // namespace mica
