// SPDX-License-Identifier: Apache-2.0
// Bodies created overlapping. Body contacts look for penetrations of about one surface edge, so a
// pair placed deeper into each other tangles: its contacts push some nodes one way and miss the
// deeper ones, every step, and the exact solvers' dense contact matrix grows with them (seconds
// and gigabytes a step). Such a pair is found when the later body is created, reported, and its
// contacts are skipped until the two bodies' bounds part.
#include <algorithm>
#include <cstdio>

#include "collision/nearest_surface_point.hpp"
#include "collision/overlap.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

// A body's surface where it is now (a dynamic body's tree was last refitted by a step's collide).
SurfaceView current_surface(Body& b, Id id) {
  if (b.is_dynamic()) b.bvh.refit(b.x);
  return SurfaceView{-1, id, &b.x, &b.surface, &b.surface_node_list, &b.bvh, &b.pseudo_normals, b.surface_edge, 0};
}

std::string metres(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g m", value);
  return text;
}

}  // namespace

std::vector<BodyOverlap> World::find_overlaps(Body& created) {
  std::vector<BodyOverlap> found;
  if (!settings_.body_contact || created.bvh.empty()) return found;
  const SurfaceView a = current_surface(created, 0);
  bodies_.for_each([&](Id id, Body& other) {
    if (other.bvh.empty() || (!created.is_dynamic() && !other.is_dynamic())) return;  // two static bodies never touch
    const SurfaceView b = current_surface(other, id);
    if (!a.bvh->bounds().inflated(settings_.body_margin).overlaps(b.bvh->bounds())) return;
    // Contacts see a node of one body at most the other's surface edge (or the margin) deep.
    const double reach_in_b = std::max(settings_.body_margin, b.depth), reach_in_a = std::max(settings_.body_margin, a.depth);
    const Penetration ab = deepest_penetration(a, b), ba = deepest_penetration(b, a);
    if (ab.depth <= reach_in_b && ba.depth <= reach_in_a) return;
    const bool ours = ab.depth >= ba.depth;
    found.push_back(BodyOverlap{id, ours ? ab.depth : ba.depth, ours ? ab.node : ba.node, ours, ours ? reach_in_b : reach_in_a});
  });
  return found;
}

std::string World::overlap_message(Id created, const BodyOverlap& o) const {
  const std::string& a = body(created).name;  // "body 0x...": its id
  const std::string& b = body(o.other).name;
  const std::string& owner = body(o.node_of_created ? created : o.other).name;
  const std::string& host = body(o.node_of_created ? o.other : created).name;
  return a + " was created overlapping " + b + " by " + metres(o.depth) + " (node " + std::to_string(o.node) + " of " +
         owner + " is that deep inside " + host + "; body contacts look " + metres(o.reach) +
         " deep), so the two would tangle: they do not collide with each other until their bounding boxes part. "
         "Create them apart (mica_body_def.translation) for contact between them.";
}

void World::warn_if_inside_a_body(Id tool_id) const {
  const Tool& t = tool(tool_id);
  if (!settings_.log || t.shape == ToolShape::Plane) return;  // a plane's origin is any point of it
  bodies_.for_each([&](Id id, const Body& b) {
    if (b.bvh.empty() || !b.bvh.bounds().contains(t.position)) return;
    const SurfaceView view{-1, id, &b.x, &b.surface, &b.surface_node_list, &b.bvh, &b.pseudo_normals, b.surface_edge, 0};
    const Aabb& box = b.bvh.bounds();
    const NearestSurfacePoint near = nearest_surface_point(view, t.position, (box.hi - box.lo).norm());
    if (near.tri < 0 || (t.position - near.point.point).dot(near.outward) >= 0) return;
    settings_.log(LogLevel::Warning,
                  "tool (id " + SlotMap<Tool, IdKind::Tool>::hex(tool_id) + ") was created with its origin " +
                      metres(near.distance) + " inside " + b.name + ": mica_tool_set_pose sweeps a tool from its last pose, so its first move would drag the "
                      "tissue on its way. Create it at its start pose (mica_tool_def.position), or move it there "
                      "with mica_tool_teleport.");
  });
}

bool World::contacts_skipped(Id a, Id b) const {
  for (const auto& [p, q] : overlapping_)
    if ((p == a && q == b) || (p == b && q == a)) return true;
  return false;
}

void World::forget_parted_overlaps() {
  overlapping_.erase(std::remove_if(overlapping_.begin(), overlapping_.end(),
                                    [&](const std::pair<Id, Id>& pair) {
                                      const Body* a = bodies_.find(pair.first);
                                      const Body* b = bodies_.find(pair.second);
                                      return !a || !b ||
                                             !a->bvh.bounds().inflated(settings_.body_margin).overlaps(b->bvh.bounds());
                                    }),
                     overlapping_.end());
}

}  // namespace mica
