// SPDX-License-Identifier: Apache-2.0
// A host's fine mesh embedded in a body's tets: each vertex bound once, at the body's rest shape,
// to a tet and four barycentric weights, then placed from the tet's current nodes after each step
// (SOFA's barycentric mapping, iMSTK's PointToTetMap). The triangles give area-weighted normals.
// After a change of the body's tets (resection, incision) only the vertices whose tet went are
// bound again (follow).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "embedding/normals_plan.hpp"
#include "embedding/place_vertices.hpp"

namespace mica {

struct TopologyChange;

// How a vertex was bound (the values of MICA_EMBED_*).
enum class VertexKind : int32_t {
  Inside = 0,     // in a tet (or on its boundary): its weights are in [0, 1]
  Projected = 1,  // outside the body, its nearest surface point within the radius: it follows the tet
                  // under that point, its weights extrapolated (some negative), so it keeps its offset
  Unbound = 2     // outside the body and farther than the radius: update() leaves it as it is
};

class Embedding {
 public:
  // Binds `vertex_count` vertices (3 doubles each, m, in the body's rest frame) to the tets of a
  // body (its rest positions, tets and surface); vertices outside it within `radius` (m) of its
  // surface are projected, the others unbound. `triangles` (3 vertex indices each, may be null
  // when triangle_count is 0) are copied for the normals, summed in blocks of `block_size`
  // (normals_plan.hpp). Throws Error(InvalidArgument) for a vertex that is not finite (naming it)
  // or a radius not finite or negative, Error(OutOfRange) for a triangle naming a vertex outside
  // 0..vertex_count-1 (naming the triangle).
  Embedding(uint64_t body, const Vec3List& rest, const std::vector<Tet>& tets, const std::vector<Tri>& surface,
            const double* xyz, int32_t vertex_count, const int32_t* triangles, int32_t triangle_count,
            double radius, int32_t block_size = 2048);

  uint64_t body() const { return body_; }
  int32_t node_count() const { return node_count_; }  // the body's, at binding or at the last follow
  uint64_t topology_version() const { return topology_version_; }  // the body's that the bindings are of
  void set_topology_version(uint64_t version) { topology_version_ = version; }
  double radius() const { return radius_; }
  int32_t vertex_count() const { return int32_t(kinds_.size()); }
  int32_t triangle_count() const { return plan_.triangles; }
  const std::vector<int32_t>& kinds() const { return kinds_; }  // VertexKind values, per vertex
  int32_t count(VertexKind kind) const { return counts_[size_t(kind)]; }
  int32_t tet(int32_t vertex) const { return tet_[size_t(vertex)]; }  // -1: unbound

  // Writes each bound vertex's position, interpolated from the body's current node positions x and
  // tets, into out_xyz (3 per vertex); an unbound vertex's entries are left as they are. With
  // out_normals, also the area-weighted normals of the triangles at those positions (3 per vertex;
  // a vertex in no triangle, or whose triangles have no area, gets 0, 0, 0). out_normals must not
  // overlap out_xyz. Allocates nothing; uses the embedding's scratch (one thread at a time). Throws
  // Error(WrongState) if x or tets are not of the body's sizes at binding or the last follow().
  void update(const Vec3List& x, const std::vector<Tet>& tets, double* out_xyz, double* out_normals) const;

  // What follow() did to the vertices whose tet the change removed.
  struct FollowReport {
    int32_t followed = 0;   // bound to a tet that stays: same weights, the tet's new nodes
    int32_t inside = 0;     // their tet removed, found inside another
    int32_t projected = 0;  // their tet removed, projected onto the new surface within the radius
    int32_t unbound = 0;    // their tet removed, nothing within the radius: unbound from now on
  };

  // Follows a change of the body's tets to its new mesh (rest positions, tets, surface): a vertex
  // bound to a tet that stays (change.tet_origin names it) keeps its kind and weights and takes the
  // tet's new nodes (a cut keeps every tet: the vertex follows the node copies its tet now holds);
  // a vertex whose tet is gone is bound again from its rest position as at creation (inside
  // another tet, projected within the radius, or unbound). Unbound vertices stay unbound (the new
  // surface is no nearer to them). Throws Error(InvalidArgument) for a change whose sizes or
  // origins do not fit the embedding or the new mesh; a failed follow changes nothing.
  FollowReport follow(const TopologyChange& change, const Vec3List& rest, const std::vector<Tet>& tets,
                      const std::vector<Tri>& surface);

  // Every vertex unbound, for a body of `node_count` nodes and `tet_count` tets at `topology_version` (after a change
  // that could not be followed: the update then leaves the host's positions as they are).
  // Allocates nothing, never throws.
  void unbind_all(int32_t node_count, int32_t tet_count, uint64_t topology_version) noexcept;

 private:

  uint64_t body_;
  int32_t node_count_;
  int32_t tet_count_;              // the body's, at binding or at the last follow
  uint64_t topology_version_ = 0;  // set by the owner (the C layer) from the body's
  double radius_;
  std::vector<VertexBinding> bindings_;  // in the plan's order (plan_.order[j]'s in j)
  std::vector<int32_t> tet_;       // per vertex: its tet (-1: unbound), for follow()
  std::vector<double> rest_xyz_;   // the vertices as given, for binding again in follow()
  std::vector<int32_t> kinds_;
  std::array<int32_t, 3> counts_{};
  NormalsPlan plan_;  // the triangles, in the order update() sums them
  mutable std::vector<NormalSlot> scratch_;  // update()'s (one thread uses a world at a time)
};

}  // namespace mica
