// SPDX-License-Identifier: Apache-2.0
// A symmetric-pattern sparse matrix of 3x3 blocks (block CSR): one block row per node.
// The pattern is built once from the mesh; values are refilled every step without allocation.
#pragma once
#include <vector>

#include "core/types.hpp"

namespace mica {

// How a sparse factor of a pattern orders its unknowns to limit fill (DirectSolver::analyze).
enum class FillOrdering : uint8_t {
  LeastFill,  // AMD or nested dissection (CHOLMOD's NESDIS over METIS), whichever fills less
  Amd         // AMD alone: for a pattern that must be factored within a step (a body just cut)
};

struct BlockPattern {
  int32_t rows = 0;
  std::vector<int32_t> row_start;  // rows + 1 offsets into col
  std::vector<int32_t> col;        // block column of each stored block, sorted per row
  std::vector<int32_t> diag;       // index of block (i, i) per row
  FillOrdering fill_ordering = FillOrdering::LeastFill;

  size_t block_count() const { return col.size(); }
  // Index of block (i, j) or -1 when it is not stored.
  int32_t find(int32_t i, int32_t j) const;
};

using BlockValues = std::vector<Mat3>;

// Nodes i, j are coupled when some tet holds both.
BlockPattern build_block_pattern(int32_t node_count, const std::vector<Tet>& tets);

// For each tet, the 16 block indices of (a, b), row-major: assembly is a plain scatter.
std::vector<std::array<int32_t, 16>> element_block_slots(const BlockPattern& p, const std::vector<Tet>& tets);

// y = A x
void block_multiply(const BlockPattern& p, const BlockValues& A, const Vec3List& x, Vec3List& y);
// y = A x and, per row, bound_i = (sum_j |A_ij|_F^2)(sum_j |x_j|^2), which bounds (sum_j |A_ij| |x_j|)^2
// by Cauchy-Schwarz: what the round-off in y_i is relative to (momentum_residual). One pass.
void block_multiply_bound(const BlockPattern& p, const BlockValues& A, const Vec3List& x, Vec3List& y,
                          std::vector<double>& bound);

}  // namespace mica
