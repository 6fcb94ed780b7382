#include "collision/contact.hpp"

#include <algorithm>

#include "collision/closest_point.hpp"
#include "collision/tool_sweep.hpp"
#include "collision/triangle_contact.hpp"

namespace mica {

namespace {

// Feature numbers in contact keys: nodes as they are, triangles above 2^40, edges (node pairs) with bit 63.
constexpr uint64_t kTriangleFeature = uint64_t(1) << 40;
constexpr uint64_t kEdgeFeature = uint64_t(1) << 63;
// A triangle point this close to an edge is left to the node contacts.
constexpr double kInteriorWeight = 1e-3;

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

Vec3 tool_point_velocity(const Tool& tool, const Vec3& p) {
  return tool.velocity + tool.angular_velocity.cross(p - tool.position);
}

}  // namespace

void collide_tool(const Tool& tool, int32_t tool_index, uint64_t tool_key, const SurfaceView& body, double h,
                  std::vector<Contact>& out) {
  // The tool's own travel: its translation plus its turn at the far end of its bounds.
  const Aabb bounds = tool_bounds(tool, 0);
  const double lever = tool.shape == ToolShape::Plane ? 0 : 0.5 * bounds.size().norm();
  const double margin = tool.margin + body.travel + h * (tool.velocity.norm() + tool.angular_velocity.norm() * lever);
  const Aabb reach = tool_bounds(tool, margin);
  // A plane has no far side to push a body through.
  const ToolSweep sweep(tool);
  const bool swept = sweep.moved() && tool.shape != ToolShape::Plane;
  const Vec3List& x = *body.x;
  // The nodes the tool went past (their start side and the nearest-point normal disagree), in
  // ascending order as body.nodes; kept between calls so that a step allocates nothing here.
  thread_local std::vector<int32_t> passed_nodes;
  passed_nodes.clear();
  for (int32_t node : *body.nodes) {
    if (!reach.contains(x[node])) continue;
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
    out.push_back(Contact{contact_key(tool_key, body.key, uint64_t(node)), tool_index, node_point(body.index, node),
                          BodyPoint{}, side.normal, x[node], side.gap, tool.friction,
                          tool_point_velocity(tool, x[node])});
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
      const Vec3 point = (1 - wj) * x[i] + wj * x[j];
      out.push_back(Contact{contact_key(tool_key, body.key, kEdgeFeature | uint64_t(j) << 32 | uint64_t(i)),
                            tool_index, edge_point(body.index, i, j, 1 - wj, wj), BodyPoint{}, side.normal, point,
                            side.gap, tool.friction, tool_point_velocity(tool, point)});
    }
    TriangleHit hit;
    if (!collide_triangle(tool, x[t[0]], x[t[1]], x[t[2]], margin, hit)) return;
    bool swept_through = false;  // the tool met the triangle in the step, or now lies across it
    if (swept && hit.normal.dot(hit.point - sweep.start_relative(hit.point)) > 0) {
      // As for the nodes; a triangle whose start side is undecided is left to its nodes.
      TriangleHit side;
      double t_touch = 0;
      if (triangle_start_side(tool, sweep, x[t[0]], x[t[1]], x[t[2]], side, t_touch)) {
        swept_through = t_touch > 0 || side.normal.dot(hit.normal) < 0;
        hit = side;
      } else if (hit.gap < 0) {
        return;
      }
      if (hit.gap >= margin) return;
    }
    int corner = 0;  // of the smallest weight
    hit.weights.minCoeff(&corner);
    if (hit.weights[corner] > kInteriorWeight) {
      out.push_back(Contact{contact_key(tool_key, body.key, kTriangleFeature + uint64_t(tri)), tool_index,
                            triangle_point(body.index, t, hit.weights), BodyPoint{}, hit.normal, hit.point, hit.gap,
                            tool.friction, tool_point_velocity(tool, hit.point)});
      return;
    }
    // On an edge the tool swept into (or now lies across): the edge's nodes may lie on either side
    // of the tool's path, and the edge between them must not end across it (otherwise, as at
    // rest, an edge is left to its nodes). The two nodes share the contact, made once: by the
    // triangle that has the edge as (i, j) with i < j (each edge of a closed surface appears once
    // each way round).
    const int32_t i = t[(corner + 1) % 3], j = t[(corner + 2) % 3];
    const double wi = hit.weights[(corner + 1) % 3], wj = hit.weights[(corner + 2) % 3];
    if (!swept_through || i > j || std::min(wi, wj) <= kInteriorWeight) return;
    out.push_back(Contact{contact_key(tool_key, body.key, kEdgeFeature | uint64_t(i) << 32 | uint64_t(j)), tool_index,
                          edge_point(body.index, i, j, wi, wj), BodyPoint{}, hit.normal, hit.point, hit.gap,
                          tool.friction, tool_point_velocity(tool, hit.point)});  // key (i, j), i < j: the
                                                                                   // edge's other contact has (j, i)
  });
}

void collide_bodies(const SurfaceView& a, const SurfaceView& b, double margin_at_rest, double friction,
                    std::vector<Contact>& out) {
  const Vec3List& xa = *a.x;
  const Vec3List& xb = *b.x;
  const double margin = margin_at_rest + a.travel + b.travel;
  const double reach = std::max(margin, b.depth);
  for (int32_t node : *a.nodes) {
    const Vec3& p = xa[node];
    // The nearest triangle of b within reach, and which side of it p is on.
    double best = HUGE_VAL;
    int32_t best_tri = -1;
    TrianglePoint best_point{};
    b.bvh->query(Aabb{p, p}.inflated(reach), [&](int32_t tri) {
      const Tri& t = (*b.triangles)[tri];
      const TrianglePoint q = closest_on_triangle(p, xb[t[0]], xb[t[1]], xb[t[2]]);
      const double d = (p - q.point).norm();
      if (d < best) {
        best = d;
        best_tri = tri;
        best_point = q;
      }
    });
    if (best_tri < 0 || best > reach) continue;
    const Tri& t = (*b.triangles)[best_tri];
    const Vec3 face = (xb[t[1]] - xb[t[0]]).cross(xb[t[2]] - xb[t[0]]).normalized();  // outward
    // The side: from the pseudo-normal of the face, edge or vertex the nearest point lies on.
    const Vec3 outward = b.normals->at(best_tri, t, best_point.weights, face);
    const Vec3 d = p - best_point.point;
    const bool inside = d.dot(outward) < 0;
    const double gap = inside ? -best : best;
    if (gap >= margin) continue;
    // The normal separates a's node from b: along d outside, against it inside.
    Vec3 normal = best > 1e-12 ? Vec3((inside ? -d : d) / best) : outward.normalized();
    if (!normal.allFinite()) normal = face;  // a node on a collapsed feature: the face has to do
    Contact c{contact_key(a.key, b.key, uint64_t(node)), -1, node_point(a.index, node), BodyPoint{}, normal, p, gap,
              friction, Vec3::Zero()};
    if (b.index >= 0) c.b = triangle_point(b.index, t, best_point.weights);  // a static b is an obstacle
    out.push_back(c);
  }
}

}  // namespace mica
