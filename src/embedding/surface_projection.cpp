// SPDX-License-Identifier: Apache-2.0
#include "embedding/surface_projection.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "collision/closest_point.hpp"
#include "core/error.hpp"

namespace mica {

namespace {

// A face as its sorted node triple (the hash mixes the three; equality compares them all).
struct FaceKey {
  std::array<int32_t, 3> v;
  bool operator==(const FaceKey& o) const { return v == o.v; }
};
struct FaceHash {
  size_t operator()(const FaceKey& k) const {
    return std::hash<uint64_t>()((uint64_t(uint32_t(k.v[0])) << 42) ^ (uint64_t(uint32_t(k.v[1])) << 21) ^
                                 uint64_t(uint32_t(k.v[2])));
  }
};
FaceKey key_of(int32_t a, int32_t b, int32_t c) {
  std::array<int32_t, 3> v{a, b, c};
  std::sort(v.begin(), v.end());
  return {v};
}

}  // namespace

SurfaceProjection::SurfaceProjection(const Vec3List& rest, const std::vector<Tet>& tets,
                                     const std::vector<Tri>& surface)
    : rest_(rest), surface_(surface) {
  bvh_.build(rest, surface);
  std::unordered_map<FaceKey, int32_t, FaceHash> face_tet;
  face_tet.reserve(surface.size());
  for (const Tri& f : surface) face_tet.emplace(key_of(f[0], f[1], f[2]), -1);
  static constexpr int kFaces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  for (size_t e = 0; e < tets.size(); ++e)
    for (const auto& face : kFaces) {
      auto it = face_tet.find(key_of(tets[e][face[0]], tets[e][face[1]], tets[e][face[2]]));
      if (it != face_tet.end()) it->second = int32_t(e);
    }
  tet_of_.resize(surface.size());
  for (size_t t = 0; t < surface.size(); ++t) {
    tet_of_[t] = face_tet.at(key_of(surface[t][0], surface[t][1], surface[t][2]));
    if (tet_of_[t] < 0) fail(Errc::BadMesh, "surface triangle " + std::to_string(t) + " is a face of no tet");
  }
}

int32_t SurfaceProjection::nearest_tet(const Vec3& p, double radius, double& distance) const {
  // Most vertices lie close to the surface: a small search first, doubled until it finds a point or
  // reaches the radius (a point found within the search distance is the nearest of all).
  for (double reach = radius / 16;; reach = std::min(2 * reach, radius)) {
    distance = HUGE_VAL;
    int32_t nearest = -1;
    bvh_.query(Aabb{p, p}.inflated(reach), [&](int32_t t) {
      const Tri& f = surface_[size_t(t)];
      const double d = (p - closest_on_triangle(p, rest_[f[0]], rest_[f[1]], rest_[f[2]]).point).norm();
      if (d <= reach && d < distance) {
        distance = d;
        nearest = t;
      }
    });
    if (nearest >= 0) return tet_of_[size_t(nearest)];
    if (reach >= radius) return -1;
  }
}

}  // namespace mica
