// SPDX-License-Identifier: Apache-2.0
#include "embedding/embedding.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "embedding/surface_projection.hpp"
#include "embedding/place_vertices.hpp"
#include "embedding/tet_locator.hpp"
#include "embedding/vertex_normals.hpp"
#include "world/topology_change.hpp"

namespace mica {

namespace {

// A vertex on a tet's face (or the body's surface) has weights of -1e-16 or so from round-off: it
// counts as inside.
constexpr double kInsideTolerance = 1e-9;

void check_input(const double* xyz, int32_t vertex_count, const int32_t* triangles, int32_t triangle_count,
                 double radius) {
  if (!std::isfinite(radius) || radius < 0)
    fail(Errc::InvalidArgument, "radius is " + number_text(radius) + " m, must be finite and >= 0");
  for (int32_t i = 0; i < vertex_count; ++i)
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(xyz[3 * size_t(i) + size_t(a)]))
        fail(Errc::InvalidArgument, "vertex " + std::to_string(i) + " is not finite (" + "xyz"[a] + " = " +
                                        number_text(xyz[3 * size_t(i) + size_t(a)]) + ")");
  for (int32_t t = 0; t < triangle_count; ++t)
    for (int k = 0; k < 3; ++k) {
      const int32_t v = triangles[3 * size_t(t) + size_t(k)];
      if (v < 0 || v >= vertex_count)
        fail(Errc::OutOfRange, "triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                                   ", outside 0.." + std::to_string(vertex_count - 1));
    }
}

// Binds points of the rest frame to a mesh: the grid over its tets, and the surface's tree made
// for the first point outside.
class Binder {
 public:
  Binder(const Vec3List& rest, const std::vector<Tet>& tets, const std::vector<Tri>& surface, double radius)
      : rest_(rest), tets_(tets), surface_(surface), radius_(radius), locator_(rest, tets) {}

  // The tet of p (-1: unbound), its weights and its kind.
  int32_t bind(const Vec3& p, Weights& w, VertexKind& kind) {
    kind = VertexKind::Inside;
    int32_t e = locator_.locate(p, kInsideTolerance, w);
    if (e >= 0) return e;
    if (!projection_) projection_ = std::make_unique<SurfaceProjection>(rest_, tets_, surface_);
    double distance;
    e = projection_->nearest_tet(p, radius_, distance);
    kind = e < 0 ? VertexKind::Unbound : VertexKind::Projected;
    if (e >= 0) w = locator_.weights(e, p);
    return e;
  }

 private:
  const Vec3List& rest_;
  const std::vector<Tet>& tets_;
  const std::vector<Tri>& surface_;
  double radius_;
  TetLocator locator_;
  std::unique_ptr<SurfaceProjection> projection_;
};

bool holds_last_node(const Tet& t, int32_t node_count) {
  return std::find(t.begin(), t.end(), node_count - 1) != t.end();
}

// Vertex `vertex` bound to tet e (-1: unbound) of `tets`, over nodes 0..node_count-1.
VertexBinding binding(int32_t vertex, int32_t e, const Weights& w, const std::vector<Tet>& tets, int32_t node_count) {
  if (e < 0) return {{0, 0, 0}, -1, vertex, 0};
  return {{w[1], w[2], w[3]}, e, vertex, holds_last_node(tets[size_t(e)], node_count)};
}

// Asks the cache for `bytes` from `from` on.
void prefetch(const void* from, size_t bytes) {
  for (size_t at = 0; at < bytes; at += 64) __builtin_prefetch(static_cast<const char*>(from) + at, 0, 3);
}

}  // namespace

Embedding::Embedding(uint64_t body, const Vec3List& rest, const std::vector<Tet>& tets,
                     const std::vector<Tri>& surface, const double* xyz, int32_t vertex_count,
                     const int32_t* triangles, int32_t triangle_count, double radius, int32_t block_size)
    : body_(body), node_count_(int32_t(rest.size())), tet_count_(int32_t(tets.size())), radius_(radius) {
  check_input(xyz, vertex_count, triangles, triangle_count, radius);
  plan_ = plan_normals(triangles, triangle_count, vertex_count, block_size);
  scratch_.resize(size_t(plan_.slots));
  Binder binder(rest, tets, surface, radius);
  bindings_.resize(size_t(vertex_count));
  tet_.resize(size_t(vertex_count));
  kinds_.resize(size_t(vertex_count));
  rest_xyz_.assign(xyz, xyz + 3 * size_t(vertex_count));
  for (size_t j = 0; j < plan_.order.size(); ++j) {
    const size_t i = size_t(plan_.order[j]);
    const Vec3 p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    Weights w;
    VertexKind kind;
    const int32_t e = binder.bind(p, w, kind);
    bindings_[j] = binding(int32_t(i), e, w, tets, node_count_);
    tet_[i] = e;
    kinds_[i] = int32_t(kind);
    ++counts_[size_t(kind)];
  }
}

void Embedding::update(const Vec3List& x, const std::vector<Tet>& tets, double* out_xyz, double* out_normals) const {
  if (int32_t(x.size()) != node_count_ || int32_t(tets.size()) != tet_count_)
    fail(Errc::WrongState, "the body has " + std::to_string(x.size()) + " nodes and " + std::to_string(tets.size()) +
                               " tets, " + std::to_string(node_count_) + " and " + std::to_string(tet_count_) +
                               " when the embedding was made or last followed it");
  const NormalsPlan& p = plan_;
  const VertexBinding* b = bindings_.data();
  if (!out_normals) return place_vertices(b, vertex_count(), tets, x, out_xyz);
  // The vertices in no triangle, then block by block (normals_plan.hpp): place what a block uses
  // first, into the scratch too; sum the block's triangles there; write the normals it uses last.
  place_vertices(b, p.first_start[0], tets, x, out_xyz);
  for (int32_t j = 0; j < p.first_start[0]; ++j) std::fill_n(out_normals + 3 * size_t(b[j].vertex), 3, 0.0);
  NormalSlot* scratch = scratch_.data();
  for (int32_t k = 0; k < p.blocks(); ++k) {
    const int32_t first = p.first_start[size_t(k)], next = p.first_start[size_t(k) + 1];
    place_vertices(b + first, next - first, tets, x, out_xyz, p.slot.data() + first, scratch);
    // The sums in parts, each followed by a part of the next block's bindings asked for: reading
    // them, which bounds the placing, overlaps the sums' arithmetic.
    const int32_t begin = p.pair_start[size_t(k)], end = p.pair_start[size_t(k) + 1];
    const size_t bytes = sizeof(VertexBinding) * size_t(k + 1 < p.blocks() ? p.first_start[size_t(k) + 2] - next : 0);
    constexpr int32_t kParts = 16;
    for (int32_t part = 0; part < kParts; ++part) {
      const int32_t q0 = begin + (end - begin) * part / kParts, q1 = begin + (end - begin) * (part + 1) / kParts;
      add_pair_normals(scratch, p.pairs.data() + 4 * size_t(q0), q1 - q0);
      if (bytes > 0) prefetch(reinterpret_cast<const char*>(b + next) + bytes * size_t(part) / kParts, bytes / kParts);
    }
    const int32_t single = p.single_start[size_t(k)];
    add_triangle_normals(scratch, p.singles.data() + 3 * size_t(single), p.single_start[size_t(k) + 1] - single);
    const int32_t last = p.last_start[size_t(k)];
    finish_normals(scratch, p.last.data() + last, p.last_slot.data() + last, p.last_start[size_t(k) + 1] - last,
                   out_normals);
  }
}

Embedding::FollowReport Embedding::follow(const TopologyChange& change, const Vec3List& rest,
                                          const std::vector<Tet>& tets, const std::vector<Tri>& surface) {
  if (change.node_origin.size() != rest.size() || change.tet_origin.size() != tets.size())
    fail(Errc::InvalidArgument, "the change names " + std::to_string(change.node_origin.size()) + " nodes and " +
                                    std::to_string(change.tet_origin.size()) + " tets, the new mesh has " +
                                    std::to_string(rest.size()) + " and " + std::to_string(tets.size()));
  if (count(VertexKind::Unbound) == vertex_count()) {  // nothing to follow (or unbound by a failed follow)
    node_count_ = int32_t(rest.size());
    tet_count_ = int32_t(tets.size());
    topology_version_ = change.topology_version;
    return {};
  }
  // Each old tet's new index, -1 if it went.
  std::vector<int32_t> now(size_t(tet_count_), -1);
  for (size_t e = 0; e < change.tet_origin.size(); ++e) {
    const int32_t old = change.tet_origin[e];
    if (old < 0 || old >= tet_count_)
      fail(Errc::InvalidArgument, "new tet " + std::to_string(e) + " comes from tet " + std::to_string(old) +
                                      ", outside the embedding's 0.." + std::to_string(tet_count_ - 1));
    if (now[size_t(old)] < 0) now[size_t(old)] = int32_t(e);
  }
  FollowReport report;
  std::vector<VertexBinding> bindings = bindings_;
  std::vector<int32_t> tet = tet_, kinds = kinds_;
  std::array<int32_t, 3> counts = counts_;
  std::unique_ptr<Binder> binder;  // made for the first vertex whose tet went
  for (size_t j = 0; j < bindings.size(); ++j) {
    const size_t i = size_t(bindings[j].vertex);
    if (tet[i] < 0) continue;  // unbound stays unbound
    const int32_t e = now[size_t(tet[i])];
    if (e >= 0) {  // the tet stays: same weights (same rest shape, corners in the same order), new nodes
      bindings[j].tet = e;
      bindings[j].has_last_node = holds_last_node(tets[size_t(e)], int32_t(rest.size()));
      tet[i] = e;
      ++report.followed;
      continue;
    }
    if (!binder) binder = std::make_unique<Binder>(rest, tets, surface, radius_);
    Weights w;
    VertexKind kind;
    const int32_t found = binder->bind(Vec3(rest_xyz_[3 * i], rest_xyz_[3 * i + 1], rest_xyz_[3 * i + 2]), w, kind);
    bindings[j] = binding(int32_t(i), found, w, tets, int32_t(rest.size()));
    tet[i] = found;
    --counts[size_t(kinds[i])];
    kinds[i] = int32_t(kind);
    ++counts[size_t(kind)];
    ++(kind == VertexKind::Inside ? report.inside : kind == VertexKind::Projected ? report.projected : report.unbound);
  }
  // Nothing below throws.
  bindings_.swap(bindings);
  tet_.swap(tet);
  kinds_.swap(kinds);
  counts_ = counts;
  node_count_ = int32_t(rest.size());
  tet_count_ = int32_t(tets.size());
  topology_version_ = change.topology_version;
  return report;
}

void Embedding::unbind_all(int32_t node_count, int32_t tet_count, uint64_t topology_version) noexcept {
  for (VertexBinding& b : bindings_) b = {{0, 0, 0}, -1, b.vertex, 0};
  for (int32_t& e : tet_) e = -1;
  for (int32_t& k : kinds_) k = int32_t(VertexKind::Unbound);
  counts_ = {0, 0, int32_t(kinds_.size())};
  node_count_ = node_count;
  tet_count_ = tet_count;
  topology_version_ = topology_version;
}

}  // namespace mica
