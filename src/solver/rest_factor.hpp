// A sparse Cholesky factor of a body's velocity system at rest, K = S A0 S + I - S with
// A0 = (1 + h alpha) M + (h^2 + h beta) K0 (K0: the stiffness of the rest shape). Factored once
// per time step, damping and constraint set; the co-rotated system of any later step differs
// from it by the element rotations, which the warped preconditioner R K^-1 R^T undoes node by
// node (Mueller and Gross 2004 call the idea stiffness warping; Saupin, Duriez and Cotin 2008
// use it for contact compliance).
#pragma once
#include <Eigen/Dense>
#include <unordered_map>

#include "fem/fem_model.hpp"
#include "solver/direct_solver.hpp"
#include "solver/pcg.hpp"

namespace mica {

class RestFactor {
 public:
  struct Key {
    double h = 0, alpha = 0, beta = 0;
    uint64_t lpc_version = ~uint64_t(0);
    bool operator==(const Key& o) const {
      return h == o.h && alpha == o.alpha && beta == o.beta && lpc_version == o.lpc_version;
    }
  };
  // Refactors when the key changed (the projection's S must be that of the key's constraint
  // set: only its z may change between updates). Returns true if it refactored.
  bool update(const FemModel& fem, const Key& key, const Projection& projection);
  // out = K^-1 in (rest frame, no rotation).
  void solve(const Vec3List& in, Vec3List& out) const;
  // The three columns of K^-1 belonging to `node` (3n x 3), kept until the next refactor: the
  // response of every node to a unit force on `node`.
  const Eigen::MatrixXd& columns(int32_t node);
  int64_t factorizations() const { return direct_.factorizations(); }
  int32_t node_count() const { return pattern_rows_; }

 private:
  Key key_;
  BlockValues A0_;
  Vec3List scratch_;
  DirectSolver direct_;
  int32_t pattern_rows_ = 0;
  std::unordered_map<int32_t, Eigen::MatrixXd> columns_;
};

// The warped preconditioner z = R K^-1 R^T r with one rotation per node (identity if none).
class WarpedRestPreconditioner : public Preconditioner {
 public:
  void bind(RestFactor* factor, const std::vector<Mat3>* node_rotation) {
    factor_ = factor;
    rotation_ = node_rotation;
  }
  void apply(const Vec3List& r, Vec3List& z) override;

 private:
  RestFactor* factor_ = nullptr;
  const std::vector<Mat3>* rotation_ = nullptr;
  Vec3List rotated_;
};

// Per node, the rotation nearest the sum of its elements' rotations (identity for a node in no
// element).
void compute_node_rotations(const FemModel& fem, const std::vector<Mat3>& element_rotation,
                            std::vector<Mat3>& node_rotation);

}  // namespace mica
