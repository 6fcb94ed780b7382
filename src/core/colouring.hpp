// A colouring of items (nodes, elements) into independent sets, for parallel loops: the items
// of one colour may be processed at once, the colours one after the other.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

namespace mica {

struct Colouring {
  std::vector<int32_t> order;  // every item once, grouped by colour, ascending within a colour
  std::vector<int32_t> start;  // colours() + 1 offsets into order

  int32_t colours() const { return start.empty() ? 0 : int32_t(start.size()) - 1; }
  int32_t size(int32_t colour) const { return start[colour + 1] - start[colour]; }
  bool empty() const { return order.empty(); }
};

// Groups items by their colour (0..) into a Colouring, keeping items ascending within a colour.
inline Colouring group_by_colour(const std::vector<int32_t>& colour_of) {
  int32_t colours = 0;
  for (int32_t c : colour_of) colours = c + 1 > colours ? c + 1 : colours;
  Colouring out;
  out.start.assign(size_t(colours) + 1, 0);
  for (int32_t c : colour_of) ++out.start[size_t(c) + 1];
  for (int32_t c = 0; c < colours; ++c) out.start[c + 1] += out.start[c];
  out.order.resize(colour_of.size());
  std::vector<int32_t> next(out.start.begin(), out.start.end() - 1);
  for (int32_t i = 0; i < int32_t(colour_of.size()); ++i) out.order[next[colour_of[i]]++] = i;
  return out;
}

}  // namespace mica
