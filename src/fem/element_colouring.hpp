// SPDX-License-Identifier: Apache-2.0
// Element colouring for parallel assembly: the tets are cut into blocks of consecutive indices,
// and two blocks that hold tets sharing a node never share a colour, so the blocks of one colour
// scatter into disjoint blocks of A and disjoint forces. Blocks of one tet give the plain
// greedy colouring of the elements.
#pragma once
#include "core/colouring.hpp"
#include "core/types.hpp"

namespace mica {

// Greedy first-fit colouring of the blocks of `block_size` consecutive tets, in block order.
Colouring colour_elements(const std::vector<Tet>& tets, int32_t node_count, int32_t block_size = 1);

// Every tet in exactly one block, every block once, and no node in tets of two different blocks
// of one colour.
bool is_valid_element_colouring(const std::vector<Tet>& tets, int32_t node_count, const Colouring& c);

}  // namespace mica
