#include "fem/element_colouring.hpp"

namespace mica {

Colouring colour_elements(const std::vector<Tet>& tets, int32_t node_count) {
  // The elements around each node (CSR).
  std::vector<int32_t> first(size_t(node_count) + 1, 0), around(4 * tets.size());
  for (const Tet& t : tets)
    for (int32_t n : t) ++first[size_t(n) + 1];
  for (int32_t i = 0; i < node_count; ++i) first[i + 1] += first[i];
  std::vector<int32_t> next(first.begin(), first.end() - 1);
  for (int32_t e = 0; e < int32_t(tets.size()); ++e)
    for (int32_t n : tets[e]) around[next[n]++] = e;

  std::vector<int32_t> colour(tets.size(), -1), taken;  // taken[c] == e: a neighbour of e has colour c
  for (int32_t e = 0; e < int32_t(tets.size()); ++e) {
    for (int32_t n : tets[e])
      for (int32_t k = first[n]; k < first[n + 1]; ++k) {
        const int32_t c = colour[around[k]];
        if (c < 0) continue;
        if (size_t(c) >= taken.size()) taken.resize(size_t(c) + 1, -1);
        taken[c] = e;
      }
    int32_t c = 0;
    while (size_t(c) < taken.size() && taken[c] == e) ++c;
    colour[e] = c;
  }
  return group_by_colour(colour);
}

bool is_valid_element_colouring(const std::vector<Tet>& tets, int32_t node_count, const Colouring& c) {
  if (c.order.size() != tets.size() || c.start.empty() || c.start.front() != 0 ||
      c.start.back() != int32_t(c.order.size()))
    return false;
  std::vector<int32_t> seen(tets.size(), 0), owner(size_t(node_count), -1);
  for (int32_t k = 0; k < c.colours(); ++k) {
    if (c.start[k] > c.start[k + 1]) return false;
    for (int32_t n = c.start[k]; n < c.start[k + 1]; ++n) {
      const int32_t e = c.order[n];
      if (e < 0 || e >= int32_t(tets.size()) || seen[e]++) return false;
      for (int32_t node : tets[e]) {
        if (owner[node] == k) return false;  // a node in two elements of colour k
        owner[node] = k;
      }
    }
  }
  return true;
}

}  // namespace mica
