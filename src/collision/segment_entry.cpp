// SPDX-License-Identifier: Apache-2.0
#include "collision/segment_entry.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace mica {

namespace {

// In the tool frame: the path q0 + t e, t in [0, 1]. Each returns the entry time and the outward
// normal there, or false.

// The first t in [0, 1] where |q0 + t e - centre| = r, for a path starting outside that sphere.
bool sphere_entry(const Vec3& q0, const Vec3& e, const Vec3& centre, double r, double& t, Vec3& normal) {
  const Vec3 d = q0 - centre;
  const double a = e.squaredNorm(), b = d.dot(e), c = d.squaredNorm() - r * r;
  const double disc = b * b - a * c;
  if (!(a > 0) || disc < 0 || b >= 0) return false;  // no motion, a miss, or moving away
  const double s = (-b - std::sqrt(disc)) / a;
  if (!(s >= 0 && s <= 1)) return false;
  t = s;
  normal = (d + s * e) / r;
  return true;
}

bool capsule_entry(const Vec3& q0, const Vec3& e, double r, double half_length, double& t, Vec3& normal) {
  // The capsule is the union of the two end spheres and the cylinder between them: the entry is
  // the earliest entry into any of them (a path through a flat end of the cylinder meets that
  // end's sphere first, since the end disc lies inside it).
  bool found = false;
  double s;
  Vec3 n;
  for (double z : {-half_length, half_length})
    if (sphere_entry(q0, e, Vec3(0, 0, z), r, s, n) && (!found || s < t)) {
      found = true;
      t = s;
      normal = n;
    }
  // The infinite cylinder x^2 + y^2 = r^2, entered where |z| <= half_length.
  const double a = e.x() * e.x() + e.y() * e.y(), b = q0.x() * e.x() + q0.y() * e.y();
  const double c = q0.x() * q0.x() + q0.y() * q0.y() - r * r;
  const double disc = b * b - a * c;
  if (a > 0 && disc >= 0 && b < 0 && c > 0) {
    s = (-b - std::sqrt(disc)) / a;
    const Vec3 q = q0 + s * e;
    if (s >= 0 && s <= 1 && std::fabs(q.z()) <= half_length && (!found || s < t)) {
      found = true;
      t = s;
      normal = Vec3(q.x(), q.y(), 0) / r;
    }
  }
  return found;
}

// A convex polytope given as half-spaces n_k . q <= offset_k (Cyrus-Beck clipping): the path
// enters at the latest of its entries into the half-spaces it crosses inwards, if that comes
// before the earliest exit.
template <class Planes>
bool polytope_entry(const Vec3& q0, const Vec3& e, const Planes& planes, double& t, Vec3& normal) {
  double enter = 0, leave = 1;
  bool crossed = false;
  bool ok = true;
  planes([&](const Vec3& n, double offset) {
    if (!ok) return;
    const double height = n.dot(q0) - offset, rate = n.dot(e);
    if (rate == 0) {
      if (height > 0) ok = false;  // parallel to the plane and outside it
      return;
    }
    const double s = -height / rate;
    if (rate < 0) {  // inwards
      if (height > 0 && (!crossed || s > enter)) {
        crossed = true;
        enter = s;
        normal = n;
      }
    } else if (height > 0) {
      ok = false;  // outside this plane and moving away from it
    } else {
      leave = std::min(leave, s);
    }
  });
  if (!ok || !crossed || enter > leave || enter > 1) return false;
  t = enter;
  return true;
}

}  // namespace

bool segment_entry(const Tool& tool, const Vec3& y0, const Vec3& y1, SegmentEntry& entry) {
  const Eigen::Quaterniond to_tool = tool.orientation.conjugate();
  const Vec3 q0 = to_tool * (y0 - tool.position), e = to_tool * (y1 - y0);
  double t = 0;
  Vec3 normal = Vec3::UnitZ();
  bool found = false;
  switch (tool.shape) {
    case ToolShape::Sphere: found = sphere_entry(q0, e, Vec3::Zero(), tool.radius, t, normal); break;
    case ToolShape::Capsule: found = capsule_entry(q0, e, tool.radius, tool.half_length, t, normal); break;
    case ToolShape::Box:
      found = polytope_entry(q0, e,
                             [&](auto&& plane) {
                               for (int k = 0; k < 3; ++k)
                                 for (double sign : {1.0, -1.0}) plane(sign * Vec3::Unit(k), tool.half_extents[k]);
                             },
                             t, normal);
      break;
    case ToolShape::ConvexHull:
      if (!tool.hull) fail(Errc::WrongState, "the convex hull tool was not prepared (prepare_tool_shape)");
      found = polytope_entry(q0, e,
                             [&](auto&& plane) {
                               for (const HullFace& f : tool.hull->faces) plane(f.normal, f.offset);
                             },
                             t, normal);
      break;
    case ToolShape::Plane: return false;
  }
  if (!found) return false;
  entry = {t, y0 + t * (y1 - y0), tool.orientation * normal};
  return true;
}

}  // namespace mica
