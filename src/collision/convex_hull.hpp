// SPDX-License-Identifier: Apache-2.0
// The convex hull of a small point set as outward face planes and face polygons, built once per tool.
#pragma once
#include <array>
#include <memory>
#include <string>

#include "core/types.hpp"

namespace mica {

// Faces are found by brute force over point triples (O(n^4)): fine for this many points, refused beyond.
constexpr size_t kMaxHullPoints = 64;

struct HullFace {
  Vec3 normal;       // outward, unit
  double offset;     // normal . x = offset on the face plane
  Vec3List polygon;  // the face's corners, counter-clockwise seen from outside
  std::vector<int32_t> corners;  // the same corners as indices into HullData::vertices
};

struct HullData {
  std::vector<HullFace> faces;
  Vec3List vertices;  // the hull's corners (a subset of the input points)
  std::vector<std::array<int32_t, 2>> edges;  // corner pairs (smaller index first), each edge once
  Vec3List edge_directions;  // unit, one per set of parallel edges (for separating-axis tests)
  Vec3 centre;        // the mean of the corners: a point strictly inside
};

// Throws Error(InvalidArgument), naming `field`, unless there are 4..kMaxHullPoints finite points
// that are not (nearly) coplanar.
std::shared_ptr<const HullData> build_convex_hull(const Vec3List& points, const std::string& field);

}  // namespace mica
