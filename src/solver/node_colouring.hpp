// SPDX-License-Identifier: Apache-2.0
// Node colouring for the colour-ordered (multicolour) block Gauss-Seidel sweep. The nodes are cut
// into blocks of consecutive indices, and two blocks share a colour only when A has no block
// (i, j) between a node of one and a node of the other: the blocks of a colour update
// independently (in parallel), each in node order, and the whole is still an exact Gauss-Seidel
// sweep, in the order colour by colour, block by block, node by node. Blocks of one node give
// the plain greedy colouring of the pattern's graph.
#pragma once
#include "core/colouring.hpp"
#include "fem/block_matrix.hpp"

namespace mica {

// Greedy first-fit colouring of the blocks of `block_size` consecutive nodes, in block order.
Colouring colour_nodes(const BlockPattern& p, int32_t block_size = 1);

// Every node in exactly one block, every block once, and no two nodes coupled by a stored block
// of A in different blocks of one colour.
bool is_valid_node_colouring(const BlockPattern& p, const Colouring& c);

}  // namespace mica
