// SPDX-License-Identifier: Apache-2.0
#include "solver/lagged_factor.hpp"

#include <algorithm>
#include <type_traits>

namespace mica {

LaggedFactor::LaggedFactor() : active_(std::make_unique<Slot>()), pending_(std::make_unique<Slot>()) {}

LaggedFactor::~LaggedFactor() {
  stop_preparing_.store(true, std::memory_order_relaxed);
  worker_.wait();
}

void LaggedFactor::copy_system(Slot& slot, const BlockPattern& pattern, const BlockValues& A,
                               const std::vector<TriangleStiffness>* extra) {
  slot.A = A;  // the same size: no allocation after the first
  if (!extra) return;
  for (const TriangleStiffness& e : *extra)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) slot.A[size_t(pattern.find(e.nodes[r], e.nodes[c]))] -= e.K.block<3, 3>(3 * r, 3 * c);
}

void LaggedFactor::require_halves(const Slot& slot) {
  if (!slot.direct.by_hand())
    fail(Errc::Unsupported, "this CHOLMOD made a factor other than a supernodal LL^T of int indices, which the "
                            "factored sweep needs");
}

void LaggedFactor::factor(Slot& slot, const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                          const std::vector<Mat3>* node_rotation, const std::vector<TriangleStiffness>* extra) {
  if (!slot.direct.analyzed()) slot.direct.analyze(pattern, &projection);
  copy_system(slot, pattern, A, extra);  // what it is made from, kept for a saved state
  slot.direct.factorize(ProjectedSystem{pattern, slot.A, projection});
  require_halves(slot);
  slot.projection = projection;
  if (node_rotation) slot.rotation = *node_rotation;
  else slot.rotation.clear();
  slot.born = step_;
  ++factorizations_;
}

LaggedFactor::Slot& LaggedFactor::writable(std::unique_ptr<Slot>& slot) {
  const bool saved = slot.get() == saved_.active || (slot.get() == saved_.pending && saved_.in_flight);
  if (!open_ || !saved) return *slot;
  std::unique_ptr<Slot>& keep = kept_[0] ? kept_[1] : kept_[0];
  keep = std::move(slot);
  slot = spare_ ? std::move(spare_) : std::make_unique<Slot>();
  return *slot;
}

void LaggedFactor::clear_columns() {
  if (open_ && !columns_cleared_) {
    columns_kept_.swap(columns_);
    columns_cleared_ = true;
  }
  columns_id_ = ++last_columns_id_;  // never given before: every cached column is stale
}

void LaggedFactor::refactor_now(const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                                const std::vector<Mat3>* node_rotation, const std::vector<TriangleStiffness>* extra) {
  clear_columns();
  try {
    factor(writable(active_), pattern, A, projection, node_rotation, extra);
  } catch (...) {
    key_ = Key{};  // the factor in use is gone: the next update factors again
    throw;
  }
}

void LaggedFactor::adopt() {
  stop_preparing_.store(true, std::memory_order_relaxed);
  worker_.wait();
  in_flight_ = false;
  if (worker_.error()) return;  // the copied system did not factor (not positive definite): keep the one in use
  // Refactored since it was launched, or a factor the halves cannot use (see factor()).
  if (pending_->born < active_->born || !pending_->direct.by_hand()) return;
  // The next launch asks the worker for these too (which columns it makes does not change
  // results, so a rollback leaves this list as it is).
  recent_nodes_.clear();
  for (const auto& [node, c] : columns_)
    if (c.made_for == columns_id_) recent_nodes_.push_back(node);
  std::swap(active_, pending_);
  clear_columns();
  // The worker's half columns, copied (the slot keeps its own for a rollback): the same bits as
  // prepare_columns() makes, in buffers of the same sizes (no allocation once both maps hold the node).
  for (size_t k = 0; k < active_->prepared_count; ++k) {
    const auto [at, added] = columns_.try_emplace(active_->prepare[k]);
    if (added && open_) columns_added_.push_back(active_->prepare[k]);
    at->second.h = active_->prepared[k];
    at->second.made_for = columns_id_;
  }
  columns_from_worker_ += int64_t(active_->prepared_count);
}

void LaggedFactor::factor_pending(void* self) {
  const LaggedFactor& f = *static_cast<const LaggedFactor*>(self);
  Slot& slot = *f.job_slot_;  // the stepping thread leaves it alone until adopt()
  slot.direct.factorize(ProjectedSystem{*f.job_pattern_, slot.A, slot.projection});
  const SupernodalSolve* halves = slot.direct.by_hand();
  if (!halves) return;  // adopt() drops such a factor
  for (size_t k = 0; k < slot.prepare.size() && !f.stop_preparing_.load(std::memory_order_relaxed); ++k) {
    halves->half_columns(3 * slot.prepare[k], slot.prepared[k]);
    slot.prepared_count = k + 1;
  }
}

void LaggedFactor::launch(const BlockPattern& pattern) {
  job_slot_ = pending_.get();  // pending_ itself may be moved (a rollback) while the job runs
  job_pattern_ = &pattern;      // fixed for the body's life, which outlives the job
  // The nodes whose half columns the factor in use has, and those the one it replaced had (a
  // launch right after an adoption comes before the step's contact nodes are made again): the
  // worker makes them for its factor.
  std::vector<int32_t>& nodes = job_slot_->prepare;
  nodes.clear();
  if (background_columns_) {
    for (const auto& [node, c] : columns_)
      if (c.made_for == columns_id_) nodes.push_back(node);
    for (int32_t node : recent_nodes_) {
      const auto at = columns_.find(node);
      if (at == columns_.end() || at->second.made_for != columns_id_) nodes.push_back(node);
    }
  }
  std::sort(nodes.begin(), nodes.end());  // the same order whatever the map's history
  if (job_slot_->prepared.size() < nodes.size()) job_slot_->prepared.resize(nodes.size());
  job_slot_->prepared_count = 0;
  stop_preparing_.store(false, std::memory_order_relaxed);
  in_flight_ = true;
  worker_.start(&LaggedFactor::factor_pending, this);
}

void LaggedFactor::update(const FemModel& fem, const Key& key, const BlockValues& A, const Projection& projection,
                          const std::vector<Mat3>* node_rotation, int32_t interval,
                          const std::vector<TriangleStiffness>* extra) {
  ++step_;
  node_count_ = fem.node_count();
  if (!(key == key_) || !active_->direct.analyzed()) {
    // A new step size, damping or constraint set: what is in flight is for another system.
    if (in_flight_) {
      stop_preparing_.store(true, std::memory_order_relaxed);
      worker_.wait();
      in_flight_ = false;
    }
    launch_staged_ = false;
    // throws on failure: the key stays, the next step retries
    factor(writable(active_), fem.pattern, A, projection, node_rotation, extra);
    key_ = key;
    launched_at_ = step_;  // the next refresh starts from a later step
    clear_columns();
    return;
  }
  if (interval <= 0) return;
  if (in_flight_ && step_ - launched_at_ >= interval) adopt();
  if (!in_flight_ && !launch_staged_ && step_ > launched_at_) {
    // The copies the worker factors: *pending_ is free, or holds the factor replaced just now
    // (in a step that may be undone, that one moves aside: writable).
    Slot& slot = writable(pending_);
    if (!slot.direct.analyzed()) slot.direct.analyze(fem.pattern, &projection);
    copy_system(slot, fem.pattern, A, extra);
    slot.projection = projection;
    if (open_) {
      if (node_rotation) staged_rotation_ = *node_rotation;
      else staged_rotation_.clear();
      staged_born_ = step_;
      staged_pattern_ = &fem.pattern;
      launch_staged_ = true;
    } else {
      if (node_rotation) slot.rotation = *node_rotation;
      else slot.rotation.clear();
      slot.born = step_;
      launch(fem.pattern);
    }
    ++factorizations_;
    launched_at_ = step_;
  }
}

void LaggedFactor::begin() {
  saved_.key = key_;
  saved_.step = step_;
  saved_.launched_at = launched_at_;
  saved_.factorizations = factorizations_;
  saved_.active = active_.get();
  saved_.pending = pending_.get();
  saved_.in_flight = in_flight_;
  saved_.columns_id = columns_id_;
  columns_cleared_ = false;
  columns_added_.clear();
  open_ = true;
}

void LaggedFactor::commit() {
  if (!open_) return;
  open_ = false;
  for (std::unique_ptr<Slot>& k : kept_) {
    if (k && !spare_) spare_ = std::move(k);
    k.reset();
  }
  columns_added_.clear();
  saved_.in_flight = false;
  saved_.active = saved_.pending = nullptr;
  if (launch_staged_) {
    launch_staged_ = false;
    pending_->rotation.swap(staged_rotation_);
    pending_->born = staged_born_;
    launch(*staged_pattern_);
  }
}

void LaggedFactor::rollback() {
  if (!open_) return;
  open_ = false;
  launch_staged_ = false;  // no job was launched since begin(): the only one is the saved one
  std::unique_ptr<Slot>* all[] = {&active_, &pending_, &kept_[0], &kept_[1], &spare_};
  std::unique_ptr<Slot> active, pending, spare;
  for (std::unique_ptr<Slot>* s : all) {
    if (!*s) continue;
    if (s->get() == saved_.active) active = std::move(*s);
    else if (s->get() == saved_.pending) pending = std::move(*s);
    else if (!spare) spare = std::move(*s);
    else s->reset();
  }
  for (std::unique_ptr<Slot>* s : all) s->reset();
  active_ = std::move(active);
  pending_ = std::move(pending);
  spare_ = std::move(spare);
  in_flight_ = saved_.in_flight;  // its job is over or still running: no job started since begin()
  saved_.in_flight = false;
  saved_.active = saved_.pending = nullptr;
  key_ = saved_.key;
  step_ = saved_.step;
  launched_at_ = saved_.launched_at;
  factorizations_ = saved_.factorizations;
  if (columns_cleared_) {
    columns_.swap(columns_kept_);
  } else {
    for (int32_t node : columns_added_) columns_.erase(node);
  }
  columns_id_ = saved_.columns_id;
  columns_added_.clear();
  columns_cleared_ = false;
}

void LaggedFactor::save_slot(const Slot& slot, ByteWriter& out) {
  out.put_vector(slot.A);
  out.put_vector(slot.projection.S);
  out.put_vector(slot.projection.z);
  out.put_vector(slot.projection.nodes);
  out.put_vector(slot.projection.is_constrained);
  out.put_vector(slot.rotation);
  out.put(slot.born);
}

void LaggedFactor::load_slot(Slot& slot, ByteReader& in, const BlockPattern& pattern) {
  const size_t n = pattern.row_start.size() - 1;
  in.get_vector(slot.A, "a factor's matrix");
  in.get_vector(slot.projection.S, "a factor's projection");
  in.get_vector(slot.projection.z, "a factor's projection");
  in.get_vector(slot.projection.nodes, "a factor's projection");
  in.get_vector(slot.projection.is_constrained, "a factor's projection");
  in.get_vector(slot.rotation, "a factor's rotations");
  slot.born = in.get<int64_t>("a factor's step");
  slot.prepare.clear();  // its half columns are made again as needed
  slot.prepared_count = 0;
  bool fits = slot.A.size() == size_t(pattern.block_count()) && slot.projection.S.size() == n &&
              slot.projection.z.size() == n && slot.projection.is_constrained.size() == n &&
              (slot.rotation.empty() || slot.rotation.size() == n);
  for (int32_t node : slot.projection.nodes) fits = fits && node >= 0 && size_t(node) < n;
  if (!fits) fail(Errc::Parse, "a saved factor does not fit its body's matrix pattern: corrupt state");
  slot.direct.analyze(pattern, &slot.projection);
  slot.direct.factorize(ProjectedSystem{pattern, slot.A, slot.projection});
  require_halves(slot);
}

// A saved state holds the key's bytes: h, alpha, beta and the constraint version.
static_assert(sizeof(LaggedFactor::Key) == 4 * 8 && std::is_trivially_copyable_v<LaggedFactor::Key>);

void LaggedFactor::save(ByteWriter& out) const {
  out.put(key_);
  out.put(step_);
  out.put(launched_at_);
  out.put(factorizations_);
  out.put(node_count_);
  const bool active = active_->direct.analyzed();
  const bool in_flight = in_flight_;
  out.put(uint8_t(active));
  out.put(uint8_t(in_flight));
  if (active) save_slot(*active_, out);
  if (in_flight) save_slot(*pending_, out);
  out.put(uint64_t(0));  // no cached columns (a state of 0.6's first builds kept them)
}

void LaggedFactor::load(ByteReader& in, const BlockPattern& pattern) {
  const int64_t n = int64_t(pattern.row_start.size()) - 1;
  key_ = in.get<Key>("a factor's key");
  step_ = in.get<int64_t>("a factor's schedule");
  launched_at_ = in.get<int64_t>("a factor's schedule");
  factorizations_ = in.get<int64_t>("a factor's count");
  node_count_ = in.get<int32_t>("a factor's node count");
  const bool active = in.get<uint8_t>("a factor's flags") != 0;
  const bool in_flight = in.get<uint8_t>("a factor's flags") != 0;
  if ((active || node_count_ != 0) && node_count_ != n)
    fail(Errc::Parse, "a saved factor is of " + std::to_string(node_count_) + " nodes, its body has " +
                          std::to_string(n) + ": corrupt state");
  if (active) load_slot(*active_, in, pattern);
  if (in_flight) {
    load_slot(*pending_, in, pattern);
    in_flight_ = true;  // factored now (the worker has no job): adopted on the schedule it was launched with
  }
  // Cached columns in a state of 0.6's first builds (dense, 3n x 3 each): read past, made again.
  const uint64_t count = in.get<uint64_t>("the cached columns");
  if (count > uint64_t(std::max<int64_t>(n, 0))) fail(Errc::Parse, "more cached columns than nodes: corrupt state");
  std::vector<double> skipped;
  for (uint64_t k = 0; k < count; ++k) {
    const int32_t node = in.get<int32_t>("a cached column");
    const int64_t rows = in.get<int64_t>("a cached column");
    if (node < 0 || node >= n || rows != 3 * n)
      fail(Errc::Parse, "a cached column does not fit its body: corrupt state");
    skipped.resize(size_t(rows) * 3);
    in.get_bytes(skipped.data(), skipped.size() * sizeof(double), "a cached column");
  }
}

void LaggedFactor::prepare_columns(const std::vector<int32_t>& nodes) {
  for (int32_t node : nodes) {
    const auto [at, added] = columns_.try_emplace(node);
    CachedColumns& c = at->second;
    if (c.made_for == columns_id_) continue;
    if (added && open_) columns_added_.push_back(node);
    active_->direct.by_hand()->half_columns(3 * node, c.h);
    c.made_for = columns_id_;
  }
}

void WarpedFactorPreconditioner::bind(LaggedFactor* factor, const std::vector<Mat3>* node_rotation) {
  factor_ = factor;
  turn_.clear();
  if (!node_rotation) return;
  turn_.resize(node_rotation->size());
  for (size_t i = 0; i < turn_.size(); ++i) turn_[i] = factor->turn(node_rotation, int32_t(i));
}

void WarpedFactorPreconditioner::apply(const Vec3List& r, Vec3List& z) {
  forward(r);
  backward(z);
}

void WarpedFactorPreconditioner::forward(const Vec3List& r) {
  size_ = r.size();
  factor_->halves().forward(flat(r).data(), true, turn_.empty() ? nullptr : turn_.data());
}

void WarpedFactorPreconditioner::backward(Vec3List& z) {
  z.resize(size_);
  factor_->halves().backward(flat(z).data(), turn_.empty() ? nullptr : turn_.data());
}

}  // namespace mica
