#include "collision/tool.hpp"

namespace mica {

SurfacePoint closest_surface_point(const Tool& tool, const Vec3& p) {
  switch (tool.shape) {
    case ToolShape::Sphere: {
      const Vec3 d = p - tool.position;
      const double r = d.norm();
      // At the very centre any direction is as good: push along +z.
      const Vec3 n = r > 1e-15 ? Vec3(d / r) : Vec3::UnitZ();
      return {r - tool.radius, n};
    }
    case ToolShape::Plane: {
      const Vec3 n = tool.orientation * tool.plane_normal;
      return {n.dot(p - tool.position), n};
    }
  }
  return {HUGE_VAL, Vec3::UnitZ()};
}

}  // namespace mica
