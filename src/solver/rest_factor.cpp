#include "solver/rest_factor.hpp"

#include "fem/rotation.hpp"

namespace mica {

bool RestFactor::update(const FemModel& fem, const Key& key, const Projection& projection) {
  if (key == key_ && direct_.analyzed()) return false;
  const int32_t n = fem.node_count();
  if (!direct_.analyzed()) direct_.analyze(fem.pattern);
  A0_.resize(fem.pattern.block_count());
  scratch_.resize(size_t(n));
  set_scaled_mass(fem, 1.0 + key.h * key.alpha, A0_);
  assemble_elastic(fem, fem.rest, nullptr, key.h * key.h + key.h * key.beta, &A0_, scratch_);
  direct_.factorize(ProjectedSystem{fem.pattern, A0_, projection});
  key_ = key;
  pattern_rows_ = n;
  columns_.clear();
  return true;
}

void RestFactor::solve(const Vec3List& in, Vec3List& out) const {
  Eigen::MatrixXd x;
  direct_.solve_raw(flat(in), x);
  out.resize(in.size());
  flat(out) = x.col(0);
}

const Eigen::MatrixXd& RestFactor::columns(int32_t node) {
  auto it = columns_.find(node);
  if (it != columns_.end()) return it->second;
  Eigen::MatrixXd unit = Eigen::MatrixXd::Zero(3 * pattern_rows_, 3);
  unit.block<3, 3>(3 * node, 0).setIdentity();
  Eigen::MatrixXd& X = columns_[node];
  direct_.solve_raw(unit, X);
  return X;
}

void WarpedRestPreconditioner::apply(const Vec3List& r, Vec3List& z) {
  if (!rotation_) {
    factor_->solve(r, z);
    return;
  }
  const std::vector<Mat3>& R = *rotation_;
  rotated_.resize(r.size());
  for (size_t i = 0; i < r.size(); ++i) rotated_[i] = R[i].transpose() * r[i];
  factor_->solve(rotated_, z);
  for (size_t i = 0; i < z.size(); ++i) z[i] = R[i] * z[i];
}

void compute_node_rotations(const FemModel& fem, const std::vector<Mat3>& element_rotation,
                            std::vector<Mat3>& node_rotation) {
  node_rotation.assign(size_t(fem.node_count()), Mat3::Zero());
  for (size_t e = 0; e < fem.elements.size(); ++e)
    for (int32_t a : fem.elements[e].nodes) node_rotation[size_t(a)] += element_rotation[e];
  for (Mat3& R : node_rotation) R = R.isZero(0) ? Mat3::Identity() : proper_rotation(R);
}

}  // namespace mica
