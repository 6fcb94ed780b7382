#include "collision/contact.hpp"

namespace mica {

void collide_nodes(const Tool& tool, int32_t tool_index, uint64_t tool_key, int32_t body_index, uint64_t body_key,
                   const Vec3List& x, const std::vector<int32_t>& nodes, std::vector<Contact>& out) {
  for (int32_t node : nodes) {
    const SurfacePoint s = closest_surface_point(tool, x[node]);
    if (s.distance >= tool.margin) continue;
    Contact c;
    c.key = contact_key(tool_key, body_key, uint64_t(node));
    c.tool = tool_index;
    c.a = node_point(body_index, node);
    c.normal = s.normal;
    c.point = x[node];
    c.gap = s.distance;
    c.friction = tool.friction;
    out.push_back(c);
  }
}

}  // namespace mica
