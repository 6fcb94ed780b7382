// SPDX-License-Identifier: Apache-2.0
// A change of a body's tets (resection, remove_tets.cpp; incision, cut.cpp): the new mesh and
// where each of its nodes and tets came from. World::adopt_topology makes everything that depends
// on the topology follow (topology_change.cpp); a listener (the C layer's embedded render meshes)
// hears of each change once it is made.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "core/types.hpp"
#include "fem/material.hpp"
#include "mesh/tet_mesh.hpp"

namespace mica {

struct Body;

// What a change made of a body, for those who keep its node or tet indices.
struct TopologyChange {
  uint64_t body = 0;                 // its id
  uint64_t topology_version = 0;     // the body's, after the change
  std::vector<int32_t> node_origin;  // per new node: the old node it continues (a cut node's copies share it)
  std::vector<int32_t> tet_origin;   // per new tet: the old tet (same rest shape, nodes renumbered)
};

using TopologyListener = std::function<void(const TopologyChange&, const Body& changed)>;

// A body's new topology, built before anything is changed: the mesh (rest positions of its
// nodes, its tets and regions), each tet's material, and the origins.
struct NewTopology {
  TetMesh mesh;
  std::vector<Material> materials;   // per new tet
  TopologyChange change;             // node_origin and tet_origin filled
};

}  // namespace mica
