#include "collision/contact.hpp"

namespace mica {

void collide_nodes(const Tool& tool, int32_t tool_index, uint64_t tool_key, int32_t body_index, uint64_t body_key,
                   const Vec3List& x, const std::vector<int32_t>& nodes, std::vector<Contact>& out) {
  for (int32_t node : nodes) {
    const SurfacePoint s = closest_surface_point(tool, x[node]);
    if (s.distance >= tool.margin) continue;
    // The key mixes the tool, the body and the node so it survives reordering of either list.
    const uint64_t key = (tool_key * 0x9E3779B97F4A7C15ull) ^ (body_key * 0xC2B2AE3D27D4EB4Full) ^ uint64_t(node);
    out.push_back(Contact{key, tool_index, body_index, node, s.normal, x[node], s.distance});
  }
}

}  // namespace mica
