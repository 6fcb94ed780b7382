// SPDX-License-Identifier: Apache-2.0
// Axis-aligned bounding boxes in world coordinates (closed: touching boxes overlap).
#pragma once
#include <cmath>

#include "core/types.hpp"

namespace mica {

struct Aabb {
  // Default-constructed boxes are empty: adding any point makes them that point.
  Vec3 lo = Vec3::Constant(HUGE_VAL);
  Vec3 hi = Vec3::Constant(-HUGE_VAL);

  static Aabb of(const Vec3& a, const Vec3& b, const Vec3& c) {
    Aabb box;
    box.add(a);
    box.add(b);
    box.add(c);
    return box;
  }

  bool empty() const { return !(lo.array() <= hi.array()).all(); }
  void add(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void add(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  Aabb inflated(double margin) const {
    const Vec3 m = Vec3::Constant(margin);
    return {lo - m, hi + m};
  }
  bool overlaps(const Aabb& b) const { return (lo.array() <= b.hi.array()).all() && (b.lo.array() <= hi.array()).all(); }
  bool contains(const Vec3& p) const { return (lo.array() <= p.array()).all() && (p.array() <= hi.array()).all(); }
  Vec3 centre() const { return 0.5 * (lo + hi); }
  Vec3 size() const { return hi - lo; }
};

}  // namespace mica
