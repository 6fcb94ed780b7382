// SPDX-License-Identifier: Apache-2.0
#include "collision/contact.hpp"

#include <algorithm>

#include "collision/closest_point.hpp"
#include "collision/core_features.hpp"
#include "collision/nearest_surface_point.hpp"
#include "collision/tool_sweep.hpp"

namespace mica {

namespace {

// Feature numbers in contact keys: nodes as they are, triangles above 2^40, edges (node pairs,
// smaller first) with bit 63, the swept edges of a fast tool with bit 62.
constexpr uint64_t kTriangleFeature = uint64_t(1) << 40;
constexpr uint64_t kEdgeFeature = uint64_t(1) << 63;
constexpr uint64_t kSweptEdgeFeature = uint64_t(1) << 62;
// A pair of a body feature and of a feature of the tool's core: corners count from 0, edges from
// kCoreEdgeFeatures; a node against the tool's surface (its nearest point) is a pair of its own.
constexpr uint64_t kCoreEdgeFeatures = 1 << 16;
constexpr uint64_t kToolSurface = 1 << 17;
constexpr uint64_t kCoreFaceFeatures = 1 << 18;

uint64_t pair_id(uint64_t body_feature, uint64_t core_feature) {
  return body_feature ^ (core_feature * 0x9E3779B97F4A7C15ull);  // 0 for a sphere: the body feature alone
}
// A barycentric weight at or below this puts a triangle's point on the edge (or corner) opposite.
// The closest-point queries give exact zeros there; this only absorbs their rounding.
constexpr double kOnFeature = 1e-12;

BodyPoint triangle_point(int32_t body, const Tri& t, const Vec3& w) {
  BodyPoint p;
  p.body = body;
  p.count = 3;
  for (int k = 0; k < 3; ++k) {
    p.nodes[k] = t[k];
    p.weights[k] = w[k];
  }
  return p;
}

// The point of edge (i, j) with weights wi, wj (of a triangle: renormalised over the edge).
BodyPoint edge_point(int32_t body, int32_t i, int32_t j, double wi, double wj) {
  BodyPoint p;
  p.body = body;
  p.count = 2;
  p.nodes[0] = i;
  p.nodes[1] = j;
  p.weights[0] = wi / (wi + wj);
  p.weights[1] = wj / (wi + wj);
  return p;
}

// The feature of triangle t (of surface triangle index tri) that the point with weights w lies
// on: a corner (a node), an edge (its two nodes) or the face; its key feature and body point.
struct Feature {
  uint64_t id;
  BodyPoint point;
};

Feature feature_of(int32_t body, int32_t tri, const Tri& t, const Vec3& w) {
  int on[3], count = 0;  // corners with a weight
  for (int k = 0; k < 3; ++k)
    if (w[k] > kOnFeature) on[count++] = k;
  if (count == 1) return {uint64_t(t[on[0]]), node_point(body, t[on[0]])};
  if (count == 2) {
    const int32_t i = std::min(t[on[0]], t[on[1]]), j = std::max(t[on[0]], t[on[1]]);
    const double wi = t[on[0]] == i ? w[on[0]] : w[on[1]];
    return {kEdgeFeature | uint64_t(j) << 32 | uint64_t(i), edge_point(body, i, j, wi, 1 - wi)};
  }
  return {kTriangleFeature + uint64_t(tri), triangle_point(body, t, w)};
}

// Contacts from first on that share a key (a node, an edge or a face reached from several
// triangles, or from the node loop and a triangle) are merged into the deepest; order is kept.
void merge_duplicate_features(std::vector<Contact>& out, size_t first) {
  thread_local std::vector<std::pair<uint64_t, size_t>> order;  // kept: a step allocates nothing here
  thread_local std::vector<char> drop;
  order.clear();
  for (size_t k = first; k < out.size(); ++k) order.push_back({out[k].key, k});
  std::sort(order.begin(), order.end());
  drop.assign(out.size() - first, 0);
  for (size_t a = 0, b = 0; a < order.size(); a = b) {
    size_t deepest = order[a].second;
    for (b = a; b < order.size() && order[b].first == order[a].first; ++b)
      if (out[order[b].second].gap < out[deepest].gap) deepest = order[b].second;
    for (size_t k = a; k < b; ++k) drop[order[k].second - first] = order[k].second != deepest;
  }
  size_t kept = first;
  for (size_t k = first; k < out.size(); ++k)
    if (!drop[k - first]) out[kept++] = out[k];
  out.resize(kept);
}

Vec3 tool_point_velocity(const Tool& tool, const Vec3& p) {
  return tool.velocity + tool.angular_velocity.cross(p - tool.position);
}

// Whether point p lies behind the body's surface with the surface point `distance` from it as
// its nearest: on the inner side of the pseudo-normal there, and no surface point nearer.
bool behind_surface_at(const SurfaceView& body, const Vec3& p, double distance) {
  const NearestSurfacePoint n = nearest_surface_point(body, p, distance * (1 + 1e-6) + 1e-12);  // within round-off
  return n.tri >= 0 && n.distance >= distance * (1 - 1e-6) - 1e-12 && (p - n.point.point).dot(n.outward) < 0;
}

}  // namespace

void collide_tool(const Tool& tool, int32_t tool_index, uint64_t tool_key, const SurfaceView& body, double h,
                  std::vector<Contact>& out) {
  // The tool's own travel: its translation plus its turn at the far end of its bounds.
  const Aabb bounds = tool_bounds(tool, 0);
  const double lever = tool.shape == ToolShape::Plane ? 0 : 0.5 * bounds.size().norm();
  const double tool_margin = tool.margin + h * (tool.velocity.norm() + tool.angular_velocity.norm() * lever);
  const Aabb reach = tool_bounds(tool, tool_margin + body.travel);
  // Each node's and triangle's own travel (h times its speed), not the body's fastest: a piece cut
  // free and falling far away must not widen the margin of every node near the tool.
  auto travel = [&](int32_t node) { return body.v ? h * (*body.v)[size_t(node)].norm() : body.travel; };
  // A plane has no far side to push a body through.
  const ToolSweep sweep(tool);
  const bool swept = sweep.moved() && tool.shape != ToolShape::Plane;
  const Vec3List& x = *body.x;
  const size_t first = out.size();
  thread_local ToolCore core;  // kept: a step allocates nothing here
  tool_core(tool, core);
  // A contact of the body point p; pair is the feature pair's id (the contact's key).
  auto emit = [&](uint64_t pair, const BodyPoint& p, const Vec3& normal, const Vec3& point, double gap) -> Contact& {
    out.push_back(Contact{contact_key(tool_key, body.key, pair), p, BodyPoint{}, normal, point, gap, tool.friction,
                          tool_point_velocity(tool, point)});
    out.back().tool = tool_index;
    out.back().other = tool_key;
    return out.back();
  };
  // The nodes the tool went past (their start side and the nearest-point normal disagree), in
  // ascending order as body.nodes; kept between calls so that a step allocates nothing here.
  thread_local std::vector<int32_t> passed_nodes;
  passed_nodes.clear();
  for (int32_t node : *body.nodes) {
    if (!reach.contains(x[node])) continue;
    const double margin = tool_margin + travel(node);
    const SurfacePoint s = closest_surface_point(tool, x[node]);
    if (s.distance >= margin) continue;
    SideContact side{s.normal, s.distance};
    // The nearest-point normal pushes the node on along its path relative to the tool: the tool
    // passed it, and that would push it out of the tool's far side. Keep it on its start side.
    if (swept && s.normal.dot(x[node] - sweep.start_relative(x[node])) > 0) {
      const bool met = node_start_side(tool, sweep, x[node], side);
      if (!met && s.distance < 0) continue;
      if (met && side.normal.dot(s.normal) < 0) passed_nodes.push_back(node);
      if (side.gap >= margin) continue;
    }
    const bool kept = !(side.normal == s.normal && side.gap == s.distance);  // on its start side
    // A box's or hull's core meets a node with its faces and edges; its corners, as a sphere's or
    // a capsule's core, meet the node's triangles below (a node that is no triangle's closest
    // point lies behind their contacts). Only a node kept on its start side needs its own.
    if (!kept && core.polytope) {
      FeatureHit hit;
      int32_t face = -1, edge = -1;
      if (!node_core(core, x[node], hit, face, edge) || !(hit.gap < margin)) continue;
      const uint64_t feature = face >= 0 ? kCoreFaceFeatures + uint64_t(face) : kCoreEdgeFeatures + uint64_t(edge);
      emit(pair_id(uint64_t(node), feature), node_point(body.index, node), hit.normal, x[node], hit.gap);
      continue;
    }
    if (!kept && tool.shape != ToolShape::Plane) continue;
    emit(pair_id(uint64_t(node), kToolSurface), node_point(body.index, node), side.normal, x[node], side.gap);
  }
  if (tool.shape == ToolShape::Plane) return;  // a plane's deepest point on a triangle is a node
  auto passed = [&](int32_t n) { return std::binary_search(passed_nodes.begin(), passed_nodes.end(), n); };
  // Whether the node's path misses the tool altogether.
  auto misses = [&](int32_t n) {
    SideContact side;
    return !node_start_side(tool, sweep, x[n], side);
  };
  body.bvh->query(reach, [&](int32_t tri) {
    const Tri& t = (*body.triangles)[tri];
    const double margin = tool_margin + std::max({travel(t[0]), travel(t[1]), travel(t[2])});
    // Edges from a node the tool went past to one beside its path (each edge once: from the
    // triangle that has it as (i, j), i < j).
    for (int k = 0; !passed_nodes.empty() && k < 3; ++k) {
      int32_t i = t[k], j = t[(k + 1) % 3];
      if (i > j) continue;
      if (!(passed(i) && misses(j))) {
        if (!(passed(j) && misses(i))) continue;
        std::swap(i, j);
      }
      double wj = 0;
      SideContact side;
      if (!edge_start_side(tool, sweep, x[i], x[j], wj, side) || side.gap >= margin) continue;
      emit(kSweptEdgeFeature | uint64_t(j) << 32 | uint64_t(i), edge_point(body.index, i, j, 1 - wj, wj), side.normal,
           (1 - wj) * x[i] + wj * x[j], side.gap);
    }
    const Vec3 corner[3] = {x[t[0]], x[t[1]], x[t[2]]};
    const Vec3 face = (corner[1] - corner[0]).cross(corner[2] - corner[0]).normalized();
    int side_known = 0;  // the triangle's side at the step's start: 0 not looked for, 1 found, -1 undecided
    TriangleHit side;
    // A feature pair's hit (weights over the triangle's corners) as a contact of body point p.
    auto add = [&](FeatureHit hit, uint64_t pair, const BodyPoint& p, int32_t core_corner, int32_t core_edge) {
      if (!(hit.gap < margin)) return;
      if (swept && hit.normal.dot(hit.point - sweep.start_relative(hit.point)) > 0) {
        // As for the nodes: keep the body point on the side of the tool it was on at the start.
        if (side_known == 0) {
          double t_touch = 0;
          side_known = triangle_start_side(tool, sweep, corner[0], corner[1], corner[2], side, t_touch) ? 1 : -1;
        }
        if (side_known < 0 && hit.gap < 0) return;  // undecided: left to the nodes
        if (side_known > 0) {
          hit.normal = side.normal;
          hit.gap = side.gap + side.normal.dot(hit.point - side.point);
        }
        if (!(hit.gap < margin)) return;
      }
      Contact& c = emit(pair, p, hit.normal, hit.point, hit.gap);
      c.triangle = tri;
      c.core_corner = core_corner;
      c.core_edge = core_edge;
    };
    // A rounded core: its corners against the triangle, its edge against the triangle's edges.
    // Orienting a hit by the surface may only lower its gap: a pair farther than margin plus the
    // rounding is out of reach either way.
    const double out_of_reach = margin + core.radius;
    auto oriented = [&](FeatureHit hit) {
      const FeatureHit as_found = hit;
      orient_by_surface(body.normals->at(tri, hit.weights, face, *body.x, *body.triangles), core.radius, body.depth, hit);
      // Inside, a core point is as deep as its nearest surface point says, not as this pair's: a
      // box's core edge just through the surface once got its pair with a triangle edge 1.5 mm
      // away, 1.8 mm "deep" sideways, and threw the body. Other pairs stay one-sided.
      const double distance = as_found.gap + core.radius;
      if (hit.normal.dot(as_found.normal) < 0 &&
          !behind_surface_at(body, as_found.point - distance * as_found.normal, distance))
        return as_found;
      return hit;
    };
    for (int32_t k = 0; k < int32_t(core.corners.size()); ++k) {
      FeatureHit hit;
      if (!corner_triangle(core.corners[k], core.radius, corner[0], corner[1], corner[2], hit) ||
          !(hit.gap < out_of_reach))
        continue;
      const Feature f = feature_of(body.index, tri, t, hit.weights);
      add(oriented(hit), pair_id(f.id, k), f.point, k, -1);
    }
    for (int32_t k = 0; k < int32_t(core.edges.size()); ++k)
      for (int e = 0; e < 3; ++e) {
        const int32_t i = std::min(t[e], t[(e + 1) % 3]), j = std::max(t[e], t[(e + 1) % 3]);
        FeatureHit hit;
        if (!edge_edge(core.corners[core.edges[k][0]], core.corners[core.edges[k][1]], core.radius, x[i], x[j], hit) ||
            !(hit.gap < out_of_reach))
          continue;
        const BodyPoint p = edge_point(body.index, i, j, hit.weights[0], hit.weights[1]);
        for (int c = 0; c < 3; ++c) hit.weights[c] = t[c] == i ? p.weights[0] : t[c] == j ? p.weights[1] : 0.0;
        add(oriented(hit), pair_id(kEdgeFeature | uint64_t(j) << 32 | uint64_t(i), kCoreEdgeFeatures + k), p, -1, k);
      }
  });
  merge_duplicate_features(out, first);
}

void collide_bodies(const SurfaceView& a, const SurfaceView& b, double margin_at_rest, double friction,
                    std::vector<Contact>& out) {
  const Vec3List& xa = *a.x;
  const double margin = margin_at_rest + a.travel + b.travel;
  const double reach = std::max(margin, b.depth);
  for (int32_t node : *a.nodes) {
    const Vec3& p = xa[node];
    // The nearest triangle of b within reach, and which side of it p is on.
    const NearestSurfacePoint n = nearest_surface_point(b, p, reach);
    if (n.tri < 0 || n.distance > reach) continue;
    const Vec3 d = p - n.point.point;
    const bool inside = d.dot(n.outward) < 0;
    const double gap = inside ? -n.distance : n.distance;
    if (gap >= margin) continue;
    // The normal separates a's node from b: along d outside, against it inside.
    Vec3 normal = n.distance > 1e-12 ? Vec3((inside ? -d : d) / n.distance) : n.outward.normalized();
    if (!normal.allFinite()) normal = n.face;  // a node on a collapsed feature: the face has to do
    Contact c{contact_key(a.key, b.key, uint64_t(node)), node_point(a.index, node), BodyPoint{}, normal, p, gap,
              friction, Vec3::Zero()};
    if (b.index >= 0) c.b = triangle_point(b.index, (*b.triangles)[n.tri], n.point.weights);  // a static b is an obstacle
    c.other = b.key;
    out.push_back(c);
  }
}

}  // namespace mica
