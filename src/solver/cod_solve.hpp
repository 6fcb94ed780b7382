// SPDX-License-Identifier: Apache-2.0
// x = the minimum-norm least-squares solution of a square system from its complete orthogonal
// decomposition: what Eigen's CompleteOrthogonalDecomposition::solve computes, step for step (to
// round-off: its Q^* is applied as dot products here), but into workspaces the caller keeps (Eigen's solve makes a copy of the right-hand side and, in
// place, a mask for the permutation: heap allocations on every call). The solver loop's.
#pragma once
#include <Eigen/QR>

namespace mica {

// work and y: at least rhs.size() entries each (their contents are overwritten).
inline void cod_solve(const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>& cod,
                      const Eigen::Ref<const Eigen::VectorXd>& rhs, Eigen::Ref<Eigen::VectorXd> x,
                      Eigen::Ref<Eigen::VectorXd> work, Eigen::Ref<Eigen::VectorXd> y) {
  const Eigen::Index n = cod.cols(), rank = cod.rank();
  if (rank == 0) {
    x.setZero();
    return;
  }
  // c = Q^* rhs = H_{rank-1} .. H_0 rhs, reflector by reflector on a plain vector (Eigen's
  // Householder sequence treats it as a matrix, and its product there allocates).
  Eigen::Map<Eigen::VectorXd> c(work.data(), n), z(y.data(), n);
  c = rhs;
  for (Eigen::Index k = 0; k < rank; ++k) {
    double scratch;
    c.tail(n - k).applyHouseholderOnTheLeft(cod.matrixQTZ().col(k).tail(n - k - 1), cod.hCoeffs()(k), &scratch);
  }
  // T z = c(0:rank)
  z.head(rank) = c.head(rank);
  cod.matrixT().topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solveInPlace(z.head(rank));
  if (rank < n) {  // Z^* [z; 0] (Eigen's applyZAdjointOnTheLeftInPlace)
    z.tail(n - rank).setZero();
    for (Eigen::Index k = 0; k < rank; ++k) {
      if (k != rank - 1) std::swap(z(k), z(rank - 1));
      double scratch;  // the Householder update's workspace: one entry per column, here one
      z.segment(rank - 1, n - rank + 1)
          .applyHouseholderOnTheLeft(cod.matrixQTZ().row(k).tail(n - rank).adjoint(), cod.zCoeffs()(k), &scratch);
      if (k != rank - 1) std::swap(z(k), z(rank - 1));
    }
  }
  x.noalias() = cod.colsPermutation() * z;  // undo the column permutation
}

}  // namespace mica
