// SPDX-License-Identifier: Apache-2.0
// Where a straight path first enters a tool's solid shape: a ray cast against the tool at its pose.
#pragma once
#include "collision/tool.hpp"

namespace mica {

struct SegmentEntry {
  double t;     // in [0, 1]: the entry is y0 + t (y1 - y0)
  Vec3 point;   // m, world: the entry, on the tool's surface
  Vec3 normal;  // unit, world: the tool's outward normal there (for a path that meets an edge or a
                // corner, the normal of the face it crosses last, whose plane it enters through)
};

// The first point of the segment y0 -> y1 (world) inside the tool or on its surface, for a path
// that starts outside (closest_surface_point(tool, y0).distance > 0). False when the segment
// misses the tool, and always for a Plane (it has no far side to pass through to). Exact for
// every shape: sphere and capsule by quadratics, box and convex hull by clipping against their
// face planes.
bool segment_entry(const Tool& tool, const Vec3& y0, const Vec3& y1, SegmentEntry& entry);

}  // namespace mica
