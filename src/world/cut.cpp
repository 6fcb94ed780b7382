// SPDX-License-Identifier: Apache-2.0
// Incision: a body separates along a cut surface by duplicating nodes along element faces
// (Nienhuys and van der Stappen 2001, without their snapping: docs/cutting.md says why).
//  1. A face shared by two tets is crossed when the segment between the two tets' centroids (where
//     the body is now) crosses a cut triangle: the crossed faces approximate the cut surface
//     within an element and always separate the tets on its two sides.
//  2. A piece the crossed faces would free with fewer than kSmallestPiece tets stays joined
//     (rejoin_slivers).
//  3. Around each node of a crossed face, its tets are joined through the faces they share that
//     hold the node and are not crossed; each group beyond the first gets a copy of the node (a
//     node at the edge of the cut, whose tets stay joined around it, is not copied: the cut stops
//     there, as a crack does).
// No tet is added, removed or changed in shape, so the mass and every element's quality stay.
// The copies take their node's place in the tets of their group and are numbered after the
// body's nodes in order; World::adopt_topology makes the rest follow.
#include <algorithm>
#include <iterator>
#include <numeric>

#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

// Whether the segment p-q crosses the triangle abc (Moller and Trumbore's test; a segment in the
// triangle's plane does not cross it).
bool segment_crosses(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a;
  const Vec3 pv = d.cross(e2);
  const double det = e1.dot(pv);
  if (std::abs(det) <= 1e-14 * d.norm() * e1.norm() * e2.norm()) return false;
  const double inv = 1 / det;
  const Vec3 s = p - a;
  const double u = s.dot(pv) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3 qv = s.cross(e1);
  const double v = d.dot(qv) * inv;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(qv) * inv;
  return t >= 0 && t <= 1;
}

// The tets of node i (ascending).
struct NodeTets {
  const int32_t* begin;
  const int32_t* end;
};
NodeTets tets_of(const FemModel& fem, int32_t i) {
  return {fem.node_elements.data() + fem.node_element_start[size_t(i)],
          fem.node_elements.data() + fem.node_element_start[size_t(i) + 1]};
}

// The tet other than e that holds face f (the three nodes of e but its f-th), or -1.
int32_t neighbour(const Body& b, int32_t e, int f) {
  int32_t n[3], k = 0;
  for (int j = 0; j < 4; ++j)
    if (j != f) n[k++] = b.tets[size_t(e)][size_t(j)];
  const NodeTets t0 = tets_of(b.fem, n[0]);
  for (const int32_t* o = t0.begin; o != t0.end; ++o) {
    if (*o == e) continue;
    const Tet& t = b.tets[size_t(*o)];
    if (std::count(t.begin(), t.end(), n[1]) && std::count(t.begin(), t.end(), n[2])) return *o;
  }
  return -1;
}

Vec3 centroid(const Body& b, int32_t e) {
  const Tet& t = b.tets[size_t(e)];
  return 0.25 * (b.x[size_t(t[0])] + b.x[size_t(t[1])] + b.x[size_t(t[2])] + b.x[size_t(t[3])]);
}

// Whether tets e and o share a face that holds node i.
bool share_face_with(const Tet& e, const Tet& o, int32_t i) {
  if (!std::count(o.begin(), o.end(), i)) return false;
  int shared = 0;
  for (int32_t n : e) shared += int(std::count(o.begin(), o.end(), n));
  return shared == 3;
}

using FacePair = std::pair<int32_t, int32_t>;  // the two tets of a face, lower first

// Step 1: the crossed faces, sorted.
std::vector<FacePair> crossed_faces(const Body& b, const Vec3List& corners) {
  std::vector<FacePair> crossed;
  for (size_t c = 0; c < corners.size(); c += 3) {
    const Vec3 &p = corners[c], &q = corners[c + 1], &r = corners[c + 2];
    const Vec3 lo = p.cwiseMin(q).cwiseMin(r), hi = p.cwiseMax(q).cwiseMax(r);
    for (int32_t e = 0; e < int32_t(b.tets.size()); ++e) {
      // A tet whose nodes' box misses the triangle's has no centroid segment crossing it (a
      // segment between two neighbours' centroids lies within their joint box).
      Vec3 tlo = b.x[size_t(b.tets[size_t(e)][0])], thi = tlo;
      for (int32_t n : b.tets[size_t(e)]) tlo = tlo.cwiseMin(b.x[size_t(n)]), thi = thi.cwiseMax(b.x[size_t(n)]);
      if ((tlo.array() > hi.array()).any() || (thi.array() < lo.array()).any()) continue;
      for (int f = 0; f < 4; ++f) {
        const int32_t o = neighbour(b, e, f);
        if (o < 0) continue;
        if (segment_crosses(centroid(b, e), centroid(b, o), p, q, r)) crossed.emplace_back(std::min(e, o), std::max(e, o));
      }
    }
  }
  std::sort(crossed.begin(), crossed.end());
  crossed.erase(std::unique(crossed.begin(), crossed.end()), crossed.end());
  return crossed;
}

int32_t root(std::vector<int32_t>& parent, int32_t k) {
  while (parent[size_t(k)] != k) k = parent[size_t(k)] = parent[size_t(parent[size_t(k)])];
  return k;
}

// Fewer tets than this a cut does not free (rejoin_slivers).
constexpr int32_t kSmallestPiece = 12;

// The tets of e's piece, joined by the faces that `joined` says are, if it has fewer than
// kSmallestPiece; empty if it has more.
template <class Joined>
std::vector<int32_t> small_piece(const Body& b, int32_t e, const Joined& joined) {
  std::vector<int32_t> piece{e};
  for (size_t k = 0; k < piece.size(); ++k)
    for (int f = 0; f < 4; ++f) {
      const int32_t o = neighbour(b, piece[k], f);
      if (o < 0 || !joined(piece[k], o) || std::count(piece.begin(), piece.end(), o)) continue;
      piece.push_back(o);
      if (int32_t(piece.size()) >= kSmallestPiece) return {};
    }
  return piece;
}

// Step 2: a piece the crossed faces would free with fewer than kSmallestPiece tets is joined again
// across one of its crossed faces (the first to a piece that is not small, else the first), until
// it is not small or has no crossed face left (it was as small before: a removal's leftover). Pieces
// are joined by faces: one that hangs on by an edge or a node comes free when step 3 splits it.
// Along element faces, a blade that passes close to a face, or a sliver that lies across its path,
// frees one tet or a few that no real blade would (an 8 mm deep incision through the nidus freed
// 56 such pieces of 1 to 6 tets, and the blade then knocked them away; with 8 as the bound, some
// runs of it still freed a piece of 10 tets, which the blade knocked 27 cm away).
void rejoin_slivers(const Body& b, std::vector<FacePair>& crossed) {
  std::vector<FacePair> rejoined;  // sorted
  const auto joined = [&](int32_t e, int32_t o) {
    const FacePair f(std::min(e, o), std::max(e, o));
    return !std::binary_search(crossed.begin(), crossed.end(), f) ||
           std::binary_search(rejoined.begin(), rejoined.end(), f);
  };
  for (const FacePair& face : crossed)
    for (int32_t side : {face.first, face.second})
      for (std::vector<int32_t> piece = small_piece(b, side, joined); !piece.empty();
           piece = small_piece(b, side, joined)) {
        FacePair pick(-1, -1), first(-1, -1);
        for (int32_t e : piece)
          for (int f = 0; f < 4; ++f) {
            const int32_t o = neighbour(b, e, f);
            if (o < 0 || joined(e, o)) continue;
            const FacePair across(std::min(e, o), std::max(e, o));
            if (first.first < 0 || across < first) first = across;
            if (small_piece(b, o, joined).empty() && (pick.first < 0 || across < pick)) pick = across;
          }
        if (first.first < 0) break;  // no crossed face left: a piece that was as small before the cut
        if (pick.first < 0) pick = first;
        rejoined.insert(std::upper_bound(rejoined.begin(), rejoined.end(), pick), pick);
      }
  std::vector<FacePair> kept;
  std::set_difference(crossed.begin(), crossed.end(), rejoined.begin(), rejoined.end(), std::back_inserter(kept));
  crossed.swap(kept);
}

}  // namespace

World::CutResult World::cut_body(Id id, const Vec3List& corners) {
  const Body& b = body(id);
  if (corners.size() % 3 != 0) fail(Errc::InvalidArgument, "a cut takes three corners per triangle");
  for (size_t k = 0; k < corners.size(); ++k)
    if (!corners[k].allFinite())
      fail(Errc::InvalidArgument, "cut triangle " + std::to_string(k / 3) + " has a corner that is not finite");
  CutResult result;
  std::vector<FacePair> crossed = crossed_faces(b, corners);
  rejoin_slivers(b, crossed);
  result.faces = int32_t(crossed.size());
  auto is_crossed = [&](int32_t e, int32_t o) {
    return std::binary_search(crossed.begin(), crossed.end(), FacePair(std::min(e, o), std::max(e, o)));
  };

  // Step 3: the nodes of the crossed faces, each split by the groups of its tets.
  std::vector<int32_t> nodes;
  for (const FacePair& f : crossed)
    for (int32_t n : b.tets[size_t(f.first)])
      if (std::count(b.tets[size_t(f.second)].begin(), b.tets[size_t(f.second)].end(), n)) nodes.push_back(n);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());

  NewTopology t;
  t.mesh.nodes = b.fem.rest;
  t.mesh.tets = b.tets;
  t.mesh.regions = b.regions;
  t.materials = b.fem.materials;
  t.change.node_origin.resize(b.x.size());
  std::iota(t.change.node_origin.begin(), t.change.node_origin.end(), 0);
  t.change.tet_origin.resize(b.tets.size());
  std::iota(t.change.tet_origin.begin(), t.change.tet_origin.end(), 0);
  std::vector<int32_t> parent, group_node;
  for (int32_t i : nodes) {
    const NodeTets around = tets_of(b.fem, i);
    const int32_t count = int32_t(around.end - around.begin);
    parent.resize(size_t(count));
    std::iota(parent.begin(), parent.end(), 0);
    for (int32_t j = 0; j < count; ++j)
      for (int32_t k = j + 1; k < count; ++k) {
        const int32_t e = around.begin[j], o = around.begin[k];
        if (share_face_with(b.tets[size_t(e)], b.tets[size_t(o)], i) && !is_crossed(e, o))
          parent[size_t(root(parent, j))] = root(parent, k);
      }
    // The group of the node's first tet keeps it; each other group, in the order of its first
    // tet, gets a copy.
    group_node.assign(size_t(count), -1);
    group_node[size_t(root(parent, 0))] = i;
    for (int32_t j = 0; j < count; ++j) {
      int32_t& node = group_node[size_t(root(parent, j))];
      if (node < 0) {
        node = int32_t(t.mesh.nodes.size());
        t.mesh.nodes.push_back(b.fem.rest[size_t(i)]);
        t.change.node_origin.push_back(i);
        ++result.nodes_added;
      }
      for (int32_t& n : t.mesh.tets[size_t(around.begin[j])])
        if (n == i) n = node;
    }
  }
  if (result.nodes_added == 0) return result;  // nothing parts: the body is left as it was
  adopt_topology(id, t);
  return result;
}

World::CutResult World::cut(Id id, const Vec3List& corners) {
  const CutResult result = cut_body(id, corners);
  if (recorder_ && result.nodes_added > 0) recorder_->write(RecordKind::Cut, id, corners);
  return result;
}

}  // namespace mica
