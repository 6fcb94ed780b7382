#include "solver/lagged_factor.hpp"

#include <algorithm>

namespace mica {

LaggedFactor::LaggedFactor() : active_(std::make_unique<Slot>()), pending_(std::make_unique<Slot>()) {}

LaggedFactor::~LaggedFactor() {
  if (job_.valid()) job_.wait();
}

void LaggedFactor::factor(Slot& slot, const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                          const std::vector<Mat3>* node_rotation) {
  if (!slot.direct.analyzed()) slot.direct.analyze(pattern);
  slot.direct.factorize(ProjectedSystem{pattern, A, projection});
  if (node_rotation) slot.rotation = *node_rotation;
  else slot.rotation.clear();
  slot.born = step_;
  ++factorizations_;
}

void LaggedFactor::refactor_now(const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                                const std::vector<Mat3>* node_rotation) {
  columns_.clear();
  try {
    factor(*active_, pattern, A, projection, node_rotation);
  } catch (...) {
    key_ = Key{};  // the factor in use is gone: the next update factors again
    throw;
  }
}

void LaggedFactor::adopt() {
  try {
    job_.get();
  } catch (...) {
    return;  // the copied system did not factor (not positive definite): keep the one in use
  }
  if (pending_->born < active_->born) return;  // refactored since it was launched
  std::swap(active_, pending_);
  columns_.clear();
}

void LaggedFactor::update(const FemModel& fem, const Key& key, const BlockValues& A, const Projection& projection,
                          const std::vector<Mat3>* node_rotation, int32_t interval) {
  ++step_;
  node_count_ = fem.node_count();
  if (!(key == key_) || !active_->direct.analyzed()) {
    // A new step size, damping or constraint set: what is in flight is for another system.
    if (job_.valid()) {
      job_.wait();
      job_ = {};
    }
    factor(*active_, fem.pattern, A, projection, node_rotation);  // throws on failure: the key stays, the next step retries
    key_ = key;
    launched_at_ = step_;  // the next refresh starts from a later step
    columns_.clear();
    return;
  }
  if (interval <= 0) return;
  if (job_.valid() && step_ - launched_at_ >= interval) adopt();
  if (!job_.valid() && step_ > launched_at_) {
    Slot& slot = *pending_;
    if (!slot.direct.analyzed()) slot.direct.analyze(fem.pattern);
    slot.A = A;
    slot.projection = projection;
    if (node_rotation) slot.rotation = *node_rotation;
    else slot.rotation.clear();
    slot.born = step_;
    const BlockPattern* pattern = &fem.pattern;  // fixed for the body's life, which outlives the job
    job_ = std::async(std::launch::async, [&slot, pattern] {
      slot.direct.factorize(ProjectedSystem{*pattern, slot.A, slot.projection});
    });
    ++factorizations_;
    launched_at_ = step_;
  }
}

void LaggedFactor::solve(const Vec3List& in, Vec3List& out) const {
  active_->direct.solve_raw(flat(in), x_);
  out.resize(in.size());
  flat(out) = x_.col(0);
}

void LaggedFactor::prepare_columns(const std::vector<int32_t>& nodes) {
  missing_.clear();
  for (int32_t node : nodes)
    if (!columns_.count(node) && std::find(missing_.begin(), missing_.end(), node) == missing_.end())
      missing_.push_back(node);
  if (missing_.empty()) return;
  const Eigen::Index k = Eigen::Index(missing_.size());
  units_.setZero(3 * node_count_, 3 * k);
  for (Eigen::Index q = 0; q < k; ++q) units_.block<3, 3>(3 * missing_[q], 3 * q).setIdentity();
  active_->direct.solve_raw(units_, batch_);
  for (Eigen::Index q = 0; q < k; ++q) columns_[missing_[q]] = batch_.middleCols<3>(3 * q);
}

void WarpedFactorPreconditioner::bind(LaggedFactor* factor, const std::vector<Mat3>* node_rotation) {
  factor_ = factor;
  turn_.clear();
  if (!node_rotation) return;
  turn_.resize(node_rotation->size());
  for (size_t i = 0; i < turn_.size(); ++i) turn_[i] = factor->turn(node_rotation, int32_t(i));
}

void WarpedFactorPreconditioner::apply(const Vec3List& r, Vec3List& z) {
  if (turn_.empty()) {
    factor_->solve(r, z);
    return;
  }
  const size_t n = r.size();
  rotated_.resize(n);
  for (size_t i = 0; i < n; ++i) rotated_[i] = turn_[i].transpose() * r[i];
  factor_->solve(rotated_, z);
  for (size_t i = 0; i < n; ++i) z[i] = turn_[i] * z[i];
}

}  // namespace mica
