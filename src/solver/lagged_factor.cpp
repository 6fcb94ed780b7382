// SPDX-License-Identifier: Apache-2.0
#include "solver/lagged_factor.hpp"

#include <algorithm>
#include <optional>
#include <type_traits>

namespace mica {

LaggedFactor::LaggedFactor() : active_(std::make_unique<Slot>()), pending_(std::make_unique<Slot>()) {}

namespace {

void keep_rotations(std::vector<Mat3>& kept, const std::vector<Mat3>* rotation) {
  if (rotation) kept = *rotation;  // the same size: no allocation after the first
  else kept.clear();
}

}  // namespace

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

void LaggedFactor::renew(Slot& slot) const {
  if (slot.generation == generation_) return;
  slot.direct.forget_pattern();
  slot.generation = generation_;
}

void LaggedFactor::factor(Slot& slot, const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                          const std::vector<Mat3>* node_rotation, const std::vector<Mat3>* element_rotation,
                          const std::vector<TriangleStiffness>* extra) {
  ++waits_;
  renew(slot);
  slot.keep_double(bridgeable_);
  if (!slot.direct.analyzed()) slot.direct.analyze(pattern, &projection);
  copy_system(slot, pattern, A, extra);  // what it is made from, kept for a saved state
  slot.direct.factorize(ProjectedSystem{pattern, slot.A, projection});
  require_halves(slot);
  slot.pattern = pattern;
  slot.projection = projection;
  keep_rotations(slot.rotation, node_rotation);
  keep_rotations(slot.element_rotation, element_rotation);
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
                                const std::vector<Mat3>* node_rotation, const std::vector<Mat3>* element_rotation,
                                const std::vector<TriangleStiffness>* extra) {
  clear_columns();
  try {
    factor(writable(active_), pattern, A, projection, node_rotation, element_rotation, extra);
  } catch (...) {
    key_ = Key{};  // the factor in use is gone: the next update factors again
    throw;
  }
  end_bridge();  // the current system's factor: a bridge's job is dropped at adoption
}

void LaggedFactor::adopt(const FemModel& fem) {
  stop_preparing_.store(true, std::memory_order_relaxed);
  if (worker_.busy()) ++waits_;
  worker_.wait();
  in_flight_ = false;
  if (worker_.error()) return;  // the copied system did not factor (not positive definite): keep the one in use
  // Refactored since it was launched, or a factor the halves cannot use (see factor()).
  if (pending_->born < active_->born || !pending_->direct.by_hand()) return;
  // Of a topology the body has changed since (remap()): it bridges to the nodes now, through the
  // changes made since its launch; one that cannot is dropped.
  const bool stale = pending_->generation != generation_;
  std::optional<Bridge> bridge;
  if (stale) {
    bridge = make_bridge(*pending_, fem, job_node_, job_tet_);
    if (!pending_->direct.bridge(bridge->factor_node, bridge->copy, bridge->B, bridge->C)) return;
    bridge->drop_blocks();
  }
  // The next launch asks the worker for these too (which columns it makes does not change
  // results, so a rollback leaves this list as it is).
  recent_nodes_.clear();
  for (const auto& [node, c] : columns_)
    if (c.made_for == columns_id_) recent_nodes_.push_back(node);
  keep_bridge();
  if (bridge) bridge_ = std::move(*bridge);
  else bridge_.on = false;
  std::swap(active_, pending_);
  clear_columns();
  if (stale) return;  // the worker's columns are of its own numbering, without the bridge
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
  if (!slot.direct.analyzed()) slot.direct.analyze(slot.pattern, &slot.projection);  // a new topology's
  slot.direct.factorize(ProjectedSystem{slot.pattern, slot.A, slot.projection});
  const SupernodalSolve* halves = slot.direct.by_hand();
  if (!halves) return;  // adopt() drops such a factor
  for (size_t k = 0; k < slot.prepare.size() && !f.stop_preparing_.load(std::memory_order_relaxed); ++k) {
    halves->half_columns(3 * slot.prepare[k], slot.prepared[k]);
    slot.prepared_count = k + 1;
  }
}

void LaggedFactor::launch() {
  job_slot_ = pending_.get();  // pending_ itself may be moved (a rollback) while the job runs
  job_node_.clear();  // of the topology now: no change since
  job_tet_.clear();
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
                          const std::vector<Mat3>* node_rotation, const std::vector<Mat3>* element_rotation,
                          int32_t interval, const std::vector<TriangleStiffness>* extra) {
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
    factor(writable(active_), fem.pattern, A, projection, node_rotation, element_rotation, extra);
    key_ = key;
    launched_at_ = step_;  // the next refresh starts from a later step
    end_bridge();
    clear_columns();
    return;
  }
  // A bridge's own factor is made on the worker whatever the refresh interval (and one still in
  // flight when the bridge ended, refactored in a step, is adopted on its schedule: dropped).
  const bool bridge_job = bridge_.on || (in_flight_ && interval <= 0);
  const int64_t due = bridge_job ? std::max<int64_t>(interval, kBridgeSteps) : interval;
  if (due <= 0) return;
  if (in_flight_ && step_ - launched_at_ >= due) adopt(fem);
  if (!in_flight_ && !launch_staged_ && step_ > launched_at_ && (interval > 0 || bridge_.on)) {
    // The copies the worker factors: *pending_ is free, or holds the factor replaced just now
    // (in a step that may be undone, that one moves aside: writable). The worker analyses a
    // pattern the slot has not seen (the first refresh's, a new topology's).
    Slot& slot = writable(pending_);
    renew(slot);
    slot.keep_double(bridgeable_);
    // A refresh's slot is analysed here, once, as the first factor was; a new topology's on the
    // worker, with AMD alone (a cut body's pattern asks for it). Nested dissection on the worker
    // did not always find the same ordering (tests/capi/test_world_state.c failed one run in
    // three or four with another test running beside it), and results must not depend on timing.
    if (!slot.direct.analyzed() && fem.pattern.fill_ordering != FillOrdering::Amd)
      slot.direct.analyze(fem.pattern, &projection);
    copy_system(slot, fem.pattern, A, extra);
    slot.pattern = fem.pattern;  // the worker's (the body's changes with its topology)
    slot.projection = projection;
    keep_rotations(slot.element_rotation, element_rotation);
    if (open_) {
      if (node_rotation) staged_rotation_ = *node_rotation;
      else staged_rotation_.clear();
      staged_born_ = step_;
      launch_staged_ = true;
    } else {
      if (node_rotation) slot.rotation = *node_rotation;
      else slot.rotation.clear();
      slot.born = step_;
      launch();
    }
    ++factorizations_;
    launched_at_ = step_;
  }
}

namespace {

// out[i] = map[in[i]], or in[i] where map is empty (the identity).
std::vector<int32_t> compose(const std::vector<int32_t>& map, const std::vector<int32_t>& in) {
  std::vector<int32_t> out(in);
  if (!map.empty())
    for (int32_t& i : out) i = map[size_t(i)];
  return out;
}

}  // namespace

bool LaggedFactor::remap(const BodyRemap& change) {
  const SupernodalSolve* halves = active_->direct.by_hand();
  if (!change.elements_linear || !halves || !halves->double_kept() || (!bridge_.on && active_->generation != generation_))
    return false;
  // Everything new first (this may throw), then what cannot. The bridge maps the nodes and tets
  // now to the factor's, through every change since it was made.
  const std::vector<int32_t> no_change;
  Bridge bridge = make_bridge(*active_, change.after, compose(bridge_.on ? bridge_.factor_node : no_change, change.node_origin),
                              compose(bridge_.on ? bridge_.factor_tet : no_change, change.tet_origin));
  std::vector<int32_t> job_node, job_tet;  // a factor in flight's maps, as the bridge's
  if (in_flight_) {
    job_node = compose(job_node_, change.node_origin);
    job_tet = compose(job_tet_, change.tet_origin);
  }
  if (!active_->direct.bridge(bridge.factor_node, bridge.copy, bridge.B, bridge.C)) return false;
  bridge.drop_blocks();
  bridge_ = std::move(bridge);
  job_node_.swap(job_node);
  job_tet_.swap(job_tet);
  key_.constraint_version = change.constraint_version;
  node_count_ = int32_t(bridge_.factor_node.size());
  ++generation_;  // every slot's analysis is of an older topology
  // The cached half columns are of the old numbering.
  columns_.clear();
  columns_kept_.clear();
  recent_nodes_.clear();
  columns_id_ = ++last_columns_id_;
  return true;
}

LaggedFactor::Bridge LaggedFactor::make_bridge(const Slot& slot, const FemModel& fem, std::vector<int32_t> factor_node,
                                               std::vector<int32_t> factor_tet) const {
  Bridge b;
  b.on = true;
  b.factor_node = std::move(factor_node);
  b.factor_tet = std::move(factor_tet);
  const size_t factor_nodes = size_t(slot.pattern.rows);
  const std::vector<Mat3>& R = slot.element_rotation;
  bool fits = b.factor_node.size() == size_t(fem.node_count()) && b.factor_tet.size() == fem.elements.size();
  for (int32_t f : b.factor_node) fits = fits && f >= 0 && size_t(f) < factor_nodes;
  for (int32_t e : b.factor_tet) fits = fits && e >= 0 && (R.empty() || size_t(e) < R.size());
  if (!fits) fail(Errc::Internal, "a bridge's maps do not fit its factor");
  // Each factor node's first node is its group's; every other node of the group is a copy of it.
  std::vector<int32_t> first(factor_nodes, -1);
  for (size_t i = 0; i < b.factor_node.size(); ++i) {
    int32_t& f = first[size_t(b.factor_node[i])];
    if (f < 0) f = int32_t(i);
    else b.copy.emplace_back(int32_t(i), f);
  }
  if (!slot.rotation.empty()) {  // the factor's node rotations, per node now: a copy's is its node's
    b.rotation.resize(b.factor_node.size());
    for (size_t i = 0; i < b.rotation.size(); ++i) b.rotation[i] = slot.rotation[size_t(b.factor_node[i])];
  }
  bridge_blocks(slot, fem, b);
  return b;
}

void LaggedFactor::bridge_blocks(const Slot& slot, const FemModel& fem, Bridge& bridge) const {
  // The cut mesh's system as of the factor, A~ = S (M (1 + h alpha) + (h^2 + h beta) K(R_f)) S + D:
  // each element's blocks as the step assembles them (World::assemble_elements), at the
  // rotations the factor's system was assembled with, projected as the factor was; D, the
  // projection's I - S, shared among a group's nodes, sums to the factor's (so T A~ T^T = K_f).
  const std::vector<Mat3>& R = slot.element_rotation;
  const Projection& S = slot.projection;
  const double h = key_.system.h, mass_scale = 1 + h * key_.system.alpha, k_scale = h * h + h * key_.system.beta;
  const std::vector<int32_t>& f = bridge.factor_node;
  std::vector<int32_t> group_size(size_t(slot.pattern.rows), 0);
  for (int32_t g : f) ++group_size[size_t(g)];
  // A~ d_k per node (3 x 3 blocks: column k's three), gathered over the nodes it touches.
  std::vector<Mat3> column(f.size(), Mat3::Zero());
  std::vector<int32_t> touched;
  std::vector<uint8_t> is_touched(f.size(), 0);
  const auto add = [&](int32_t node, const Mat3& block) {
    if (!is_touched[size_t(node)]) {
      is_touched[size_t(node)] = 1;
      touched.push_back(node);
    }
    column[size_t(node)] += block;
  };
  // A~'s column blocks (each node of its tets, node), times `weight`.
  Mat3 K[16];
  const auto add_node_column = [&](int32_t node, double weight) {
    const Mat3& S_node = S.projector(f[size_t(node)]);
    for (int32_t at = fem.node_element_start[size_t(node)]; at < fem.node_element_start[size_t(node) + 1]; ++at) {
      const int32_t e = fem.node_elements[size_t(at)];
      const TetElement& el = fem.elements[size_t(e)];
      const Mat3 Re = R.empty() ? Mat3::Identity() : R[size_t(bridge.factor_tet[size_t(e)])];
      rotated_stiffness(el, fem.lame[size_t(e)], Re, k_scale, K);
      const double rv = fem.materials[size_t(e)].density * el.volume;
      int b = 0;
      while (el.nodes[size_t(b)] != node) ++b;
      for (int a = 0; a < 4; ++a) {
        const double mass = fem.mass_kind == MassKind::Lumped ? (a == b ? rv / 4 : 0.0) : (a == b ? rv / 10 : rv / 20);
        const int32_t i = el.nodes[size_t(a)];
        const Mat3 block = K[4 * a + b] + (mass_scale * mass) * Mat3::Identity();
        add(i, weight * (S.projector(f[size_t(i)]) * block * S_node));
      }
    }
    add(node, (weight / group_size[size_t(f[size_t(node)])]) * (Mat3::Identity() - S_node));
  };
  const std::vector<std::pair<int32_t, int32_t>>& copy = bridge.copy;
  const Eigen::Index m = 3 * Eigen::Index(copy.size());
  bridge.B.setZero(3 * Eigen::Index(slot.pattern.rows), m);
  bridge.C.setZero(m, m);
  for (size_t k = 0; k < copy.size(); ++k) {
    const auto [c, p] = copy[k];
    add_node_column(p, M_SQRT1_2);
    add_node_column(c, -M_SQRT1_2);
    const Eigen::Index col = 3 * Eigen::Index(k);
    for (int32_t i : touched)  // B = T A~ V: the rows summed onto their factor nodes
      bridge.B.block<3, 3>(3 * Eigen::Index(f[size_t(i)]), col) += column[size_t(i)];
    for (size_t l = 0; l < copy.size(); ++l) {  // C = V^T A~ V
      const auto [cl, pl] = copy[l];
      bridge.C.block<3, 3>(3 * Eigen::Index(l), col) = M_SQRT1_2 * (column[size_t(pl)] - column[size_t(cl)]);
    }
    for (int32_t i : touched) {
      column[size_t(i)].setZero();
      is_touched[size_t(i)] = 0;
    }
    touched.clear();
  }
}

void LaggedFactor::keep_bridge() {
  if (!open_ || bridge_kept_) return;
  kept_bridge_ = bridge_;
  bridge_kept_ = true;
}

void LaggedFactor::end_bridge() {
  if (!bridge_.on) return;
  keep_bridge();
  bridge_.on = false;
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
  saved_.waits = waits_;
  bridge_kept_ = false;
  columns_cleared_ = false;
  columns_added_.clear();
  open_ = true;
}

void LaggedFactor::commit() {
  bridge_kept_ = false;
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
    launch();
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
  waits_ = saved_.waits;
  if (bridge_kept_) bridge_ = std::move(kept_bridge_);  // the bridge of the factor put back
  bridge_kept_ = false;
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

void LaggedFactor::read_slot(Slot& slot, ByteReader& in) {
  in.get_vector(slot.A, "a factor's matrix");
  in.get_vector(slot.projection.S, "a factor's projection");
  in.get_vector(slot.projection.z, "a factor's projection");
  in.get_vector(slot.projection.nodes, "a factor's projection");
  in.get_vector(slot.projection.is_constrained, "a factor's projection");
  in.get_vector(slot.rotation, "a factor's rotations");
  slot.born = in.get<int64_t>("a factor's step");
  slot.prepare.clear();  // its half columns are made again as needed
  slot.prepared_count = 0;
}

void LaggedFactor::factor_read_slot(Slot& slot, const BlockPattern& pattern) {
  const size_t n = pattern.row_start.size() - 1;
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

namespace {

// A slot's pattern in a saved state, where it is not the body's (a bridged factor's, or one in
// flight since a topology change).
void put_pattern(const BlockPattern& p, ByteWriter& out) {
  out.put(p.rows);
  out.put_vector(p.row_start);
  out.put_vector(p.col);
  out.put_vector(p.diag);
  out.put(uint8_t(p.fill_ordering));
}

void get_pattern(BlockPattern& p, ByteReader& in) {
  p.rows = in.get<int32_t>("a factor's pattern");
  in.get_vector(p.row_start, "a factor's pattern");
  in.get_vector(p.col, "a factor's pattern");
  in.get_vector(p.diag, "a factor's pattern");
  const uint8_t ordering = in.get<uint8_t>("a factor's pattern");
  // Its structure, as the analysis reads it.
  bool fits = p.rows >= 0 && p.row_start.size() == size_t(p.rows) + 1 && p.diag.size() == size_t(p.rows) &&
              p.row_start.front() == 0 && size_t(p.row_start.back()) == p.col.size() &&
              ordering <= uint8_t(FillOrdering::Amd);
  for (size_t r = 0; fits && r < size_t(p.rows); ++r) fits = p.row_start[r] <= p.row_start[r + 1];  // all of it first
  for (size_t r = 0; fits && r < size_t(p.rows); ++r) {
    fits = p.row_start[r] <= p.row_start[r + 1] && p.diag[r] >= p.row_start[r] && p.diag[r] < p.row_start[r + 1] &&
           p.col[size_t(p.diag[r])] == int32_t(r);
    for (int32_t k = p.row_start[r]; fits && k < p.row_start[r + 1]; ++k)
      fits = p.col[size_t(k)] >= 0 && p.col[size_t(k)] < p.rows &&
             (k == p.row_start[r] || p.col[size_t(k)] > p.col[size_t(k) - 1]);
  }
  if (!fits) fail(Errc::Parse, "a saved factor's pattern is not one: corrupt state");
  p.fill_ordering = FillOrdering(ordering);
}

}  // namespace

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
  // Since 0.9 (a state without it has none of it): each slot's element rotations and, where
  // it is of an older topology than the body's, its pattern; the bridge's maps; the changes
  // since the launch of the factor in flight.
  for (const Slot* slot : {active ? active_.get() : nullptr, in_flight ? pending_.get() : nullptr}) {
    if (!slot) continue;
    out.put_vector(slot->element_rotation);
    out.put(uint8_t(slot->kept_double));
    const bool older = slot->generation != generation_;
    out.put(uint8_t(older));
    if (older) put_pattern(slot->pattern, out);
  }
  out.put(uint8_t(bridge_.on));
  if (bridge_.on) {
    out.put_vector(bridge_.factor_node);
    out.put_vector(bridge_.factor_tet);
  }
  if (in_flight) {
    out.put_vector(job_node_);
    out.put_vector(job_tet_);
  }
}

void LaggedFactor::load(ByteReader& in, const FemModel& fem) {
  const BlockPattern& pattern = fem.pattern;
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
  if (active) read_slot(*active_, in);
  if (in_flight) read_slot(*pending_, in);
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
  // Each slot's pattern (the body's, or its own where it is older), its element rotations.
  generation_ = 1;
  bridge_ = Bridge{};
  job_node_.clear();
  job_tet_.clear();
  const bool since_09 = in.remaining() > 0;
  for (Slot* slot : {active ? active_.get() : nullptr, in_flight ? pending_.get() : nullptr}) {
    if (!slot) continue;
    slot->generation = generation_;
    slot->pattern = pattern;
    slot->element_rotation.clear();
    if (!since_09) continue;
    in.get_vector(slot->element_rotation, "a factor's element rotations");
    for (const Mat3& R : slot->element_rotation)
      if (!R.allFinite()) fail(Errc::Parse, "a saved factor's element rotation is not finite: corrupt state");
    slot->keep_double(in.get<uint8_t>("a factor's double flag") != 0);
    if (in.get<uint8_t>("a factor's pattern flag") == 0) continue;
    slot->generation = 0;
    get_pattern(slot->pattern, in);
  }
  bridge_.on = since_09 && in.get<uint8_t>("a factor's bridge") != 0;
  std::vector<int32_t> factor_node, factor_tet;
  if (bridge_.on) {
    in.get_vector(factor_node, "a bridge's nodes");
    in.get_vector(factor_tet, "a bridge's tets");
  }
  if (since_09 && in_flight) {
    in.get_vector(job_node_, "a factor in flight's changes");
    in.get_vector(job_tet_, "a factor in flight's changes");
  }
  // Where the maps lead: a bridge from the factor in use only, the changes since a launch only
  // from a factor in flight of an older topology, each map into its slot's numbering.
  const auto fits = [&](const std::vector<int32_t>& map, size_t size, int64_t bound) {
    bool ok = map.size() == size;
    for (int32_t i : map) ok = ok && i >= 0 && i < bound;
    return ok;
  };
  const auto tet_bound = [](const Slot& slot) {
    return slot.element_rotation.empty() ? std::numeric_limits<int64_t>::max() : int64_t(slot.element_rotation.size());
  };
  bool ok = !bridge_.on || (active && active_->generation == 0 && fits(factor_node, size_t(n), active_->pattern.rows) &&
                            fits(factor_tet, fem.elements.size(), tet_bound(*active_)));
  if (bridge_.on == (active && active_->generation == 0)) {
    const bool changed = in_flight && pending_->generation == 0;
    ok = ok && (changed ? fits(job_node_, size_t(n), pending_->pattern.rows) &&
                              fits(job_tet_, fem.elements.size(), tet_bound(*pending_))
                        : job_node_.empty() && job_tet_.empty());
  } else {
    ok = false;
  }
  if (ok && bridge_.on) {  // a cut's copies start where their node was at rest: a group of others is no bridge's
    std::vector<int32_t> first(size_t(active_->pattern.rows), -1);
    for (size_t i = 0; ok && i < factor_node.size(); ++i) {
      int32_t& f = first[size_t(factor_node[i])];
      if (f < 0) f = int32_t(i);
      else ok = fem.rest[i] == fem.rest[size_t(f)];
    }
  }
  if (!ok) fail(Errc::Parse, "a saved factor's bridge does not fit its body: corrupt state");
  // The slots' factors, now that the pattern of each is known; the bridge made again (the same bits).
  if (active) factor_read_slot(*active_, active_->pattern);
  if (in_flight) {
    factor_read_slot(*pending_, pending_->pattern);
    in_flight_ = true;  // factored now (the worker has no job): adopted on the schedule it was launched with
  }
  if (bridge_.on) {
    bridge_ = make_bridge(*active_, fem, std::move(factor_node), std::move(factor_tet));
    if (!active_->direct.bridge(bridge_.factor_node, bridge_.copy, bridge_.B, bridge_.C))
      fail(Errc::Parse, "a saved factor's bridge needs its double factor: corrupt state");
    bridge_.drop_blocks();
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
