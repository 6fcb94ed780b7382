// Contacts between a body's surface nodes and tools: one row of G each.
#pragma once
#include <vector>

#include "collision/tool.hpp"

namespace mica {

struct Contact {
  uint64_t key;      // persistent across steps while the same (tool, body, node) touch: warm starts
  int32_t tool;      // index in the step's tool list
  int32_t body;      // index in the step's dynamic-body list
  int32_t node;      // body node
  Vec3 normal;       // unit, from the tool into the body: the direction lambda pushes the body
  Vec3 point;        // m, the node's position when detected
  double gap;        // m, signed distance at the start of the step (negative: penetrating)
};

// Appends a contact for each listed node closer to the tool than its margin.
void collide_nodes(const Tool& tool, int32_t tool_index, uint64_t tool_key, int32_t body_index, uint64_t body_key,
                   const Vec3List& x, const std::vector<int32_t>& nodes, std::vector<Contact>& out);

}  // namespace mica
