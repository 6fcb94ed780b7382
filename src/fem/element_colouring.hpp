// Element colouring for parallel assembly: two tets that share a node never share a colour,
// so the tets of one colour scatter into disjoint blocks of A and disjoint forces.
#pragma once
#include "core/colouring.hpp"
#include "core/types.hpp"

namespace mica {

// Greedy first-fit colouring in element order.
Colouring colour_elements(const std::vector<Tet>& tets, int32_t node_count);

// Every element exactly once, and no node in two elements of one colour.
bool is_valid_element_colouring(const std::vector<Tet>& tets, int32_t node_count, const Colouring& c);

}  // namespace mica
