// Node colouring for the colour-ordered (multicolour) block Gauss-Seidel sweep: nodes i != j
// share a colour only when A has no block (i, j), so a colour's nodes update independently
// (in parallel) and the sweep is still an exact Gauss-Seidel sweep, in colour order.
#pragma once
#include "core/colouring.hpp"
#include "fem/block_matrix.hpp"

namespace mica {

// Greedy first-fit colouring of the block pattern's graph in node order.
Colouring colour_nodes(const BlockPattern& p);

// Every node exactly once, and no two nodes coupled by a stored block in one colour.
bool is_valid_node_colouring(const BlockPattern& p, const Colouring& c);

}  // namespace mica
