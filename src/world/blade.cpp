// SPDX-License-Identifier: Apache-2.0
// Blades: a capsule tool marked as a blade cuts the tissue it presses harder than the tissue
// resists. A blade's edge is its segment (local z) and its plane the local x-z plane, as a
// scalpel's. After a step, where the force a blade put on a body along its local x exceeds the
// body's cutting resistance (N per m of edge, per tet; Okamura, Simone and O'Leary 2004's cutting
// force per unit length) times the length of edge in the tissue, the body is cut in the blade's
// plane, along the part of the edge that touches it, from the edge to one surface edge ahead of
// it, or as far as it takes (up to three) to part a node (World::cut_body): the tissue resists,
// then gives. The decision reads only the step's results, so a replayed step cuts
// where the recorded one did.
#include <algorithm>
#include <cmath>
#include <limits>

#include "world/world.hpp"

namespace mica {

namespace {

// What a blade put on one body in the step.
struct BladePress {
  Vec3 force = Vec3::Zero();  // N, on the tissue
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;  // m, the contacts' extent along the edge
  double resistance = 0;      // N/m, the mean over the contacts of their nodes' tets' resistance
  int32_t contacts = 0;
};

double node_resistance(const Body& b, int32_t i) {
  const FemModel& fem = b.fem;
  double sum = 0;
  const int32_t first = fem.node_element_start[size_t(i)], last = fem.node_element_start[size_t(i) + 1];
  for (int32_t k = first; k < last; ++k) sum += b.cutting_resistance[size_t(fem.node_elements[size_t(k)])];
  return last > first ? sum / (last - first) : 0;
}

}  // namespace

void World::cut_with_blades(const StepContext& ctx) {
  struct Cut {
    Id body;
    Vec3 a0, a1, d;     // the edge's ends, the direction it cuts in
    double back, edge;  // m: the blade's radius, the body's surface edge
  };
  std::vector<Cut> cuts;
  const ContactRows& rows = last_.rows;
  for (size_t k = 0; k < ctx.tools.size(); ++k) {
    const Tool& t = *ctx.tools[k];
    if (!t.blade) continue;
    const Vec3 axis = t.orientation * Vec3::UnitZ(), blade = t.orientation * Vec3::UnitX();
    thread_local std::vector<BladePress> press;  // kept: a step that cuts nothing allocates nothing here
    press.assign(ctx.dynamic.size(), BladePress{});
    for (size_t r = 0; r < rows.size(); ++r) {
      const Contact& c = last_.contacts[size_t(rows.contact[r])];
      if (c.tool != int32_t(k) || rows.normal_of[r] >= 0 || !(last_.lambda[r] > 0)) continue;
      const Body& b = *ctx.dynamic[size_t(c.a.body)];
      BladePress& p = press[size_t(c.a.body)];
      p.force += rows.direction[r] * last_.lambda[r] / ctx.h;
      const double s = axis.dot(c.point - t.position);
      p.lo = std::min(p.lo, s), p.hi = std::max(p.hi, s);
      double resistance = 0;
      for (int32_t j = 0; j < c.a.count; ++j) resistance += c.a.weights[size_t(j)] * node_resistance(b, c.a.nodes[size_t(j)]);
      p.resistance += resistance;
      p.contacts += 1;
    }
    for (size_t i = 0; i < press.size(); ++i) {
      const BladePress& p = press[i];
      if (p.contacts == 0) continue;
      const Body& b = *ctx.dynamic[i];
      const double along = blade.dot(p.force);  // what presses the edge into the tissue, in the blade's plane
      // The edge in the tissue: the contacts' extent along it, at least one surface edge.
      const double edge = std::min(std::max(p.hi - p.lo, b.surface_edge), 2 * t.half_length);
      if (!(std::abs(along) > p.resistance / p.contacts * edge)) continue;
      // The part of the edge that touches the tissue, and a surface edge either side, cuts.
      const double from = std::max(p.lo - b.surface_edge, -t.half_length), to = std::min(p.hi + b.surface_edge, t.half_length);
      cuts.push_back({last_.bodies[i], t.position + axis * from, t.position + axis * to, along > 0 ? blade : Vec3(-blade),
                      t.radius, b.surface_edge});
    }
  }
  // The cut reaches one surface edge ahead of the edge, or, where the tissue is wedged open ahead
  // of the blade and the nearest faces are already cut, as far as it takes to part a node (up to
  // three surface edges): each cut parts something.
  for (const Cut& c : cuts) {
    try {
      for (double reach = 1; reach <= 3; reach += 0.5) {
        const Vec3 back = -c.d * c.back, ahead = c.d * (c.back + reach * c.edge);
        if (cut_body(c.body, {c.a0 + back, c.a1 + back, c.a1 + ahead, c.a0 + back, c.a1 + ahead, c.a0 + ahead}).nodes_added > 0)
          break;
      }
    } catch (const std::exception& e) {  // the step stands; the tissue stays whole this time
      if (settings_.log) settings_.log(LogLevel::Warning, std::string("a blade's cut was not made: ") + e.what());
    }
  }
}

}  // namespace mica
