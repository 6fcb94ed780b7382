// SPDX-License-Identifier: Apache-2.0
// A sparse Cholesky factor of a recent state of a body's velocity system, K_f = S A_f S + I - S,
// kept with the node rotations R_f of the step it was built from. A later co-rotated system
// differs from it mostly by how far each node has turned since, which the warped preconditioner
// Q K_f^-1 Q^T, Q_i = R_i R_f,i^T, undoes node by node (stiffness warping: Mueller and Gross 2004;
// Saupin, Duriez and Cotin 2008 use it for contact compliance; Courtecuisse et al. 2010 refresh
// the factor asynchronously, as here).
//
// Refactored at once when the step, the damping or the constraint set changed; and, with a
// refresh interval L > 0, every L steps in the background: the system of step k is copied and
// factored on a worker thread while steps k .. k+L-1 run, and adopted at step k+L. Adoption is in
// lockstep (the step waits if the worker is late), so results never depend on timing. The worker
// is one thread per factor, "mica-factor", made at the first refresh and kept until the factor
// is destroyed: a refresh makes no thread and allocates nothing on the stepping thread. After
// factoring, the worker also makes the half columns of the nodes that had them at launch, or
// before the adoption just made (the contact nodes then, most of them still in contact at
// adoption), which the stepping thread would otherwise make again at adoption (4 ms of a 13 ms
// step on the nidus); adoption stops it after the column in hand and makes the rest itself (a
// column is the same bits whoever makes it), so a late worker costs the step no more than it
// did without this.
//
// After a change of the body's topology (a cut, a resection: remap()), the factor in use goes on
// as a bridge to the new nodes while the new system's factor, its analysis included, is made on
// the worker and adopted in lockstep kBridgeSteps steps later: no step factors because of a cut
// (Courtecuisse et al. 2014 precondition with the factor made before a cut in the same way).
#pragma once
#include <Eigen/Dense>
#include <atomic>
#include <memory>
#include <unordered_map>

#include "core/background_thread.hpp"
#include "core/byte_stream.hpp"
#include "fem/fem_model.hpp"
#include "solver/direct_solver.hpp"
#include "solver/pcg.hpp"
#include "solver/velocity_solver.hpp"

namespace mica {

class LaggedFactor {
 public:
  // What the factor in use was made for: the system's and the constraint set's
  // (SolverBody::system, constraint_version).
  struct Key {
    SystemKey system;
    uint64_t constraint_version = ~uint64_t(0);  // none yet: the first update factors
    bool operator==(const Key& o) const { return system == o.system && constraint_version == o.constraint_version; }
  };
  LaggedFactor();
  ~LaggedFactor();  // waits for a background factorization in flight
  LaggedFactor(const LaggedFactor&) = delete;
  LaggedFactor& operator=(const LaggedFactor&) = delete;

  // Once per step, with this step's system A (M + h C + h^2 K of the current rotations), its
  // projection and node rotations (null: a linear body, no warping). Factors A at once when the
  // key changed; otherwise adopts and launches background factorizations every `interval` steps
  // (0: never). What A holds of `extra` (the contacts' stiffness, which changes every step) is
  // left out of what is factored: the solver adds the current one back (factored_mica.hpp).
  // `element_rotation`: the element rotations A was assembled with (null: the linear model), kept
  // with the factor for a bridge after a topology change (remap()).
  void update(const FemModel& fem, const Key& key, const BlockValues& A, const Projection& projection,
              const std::vector<Mat3>* node_rotation, const std::vector<Mat3>* element_rotation, int32_t interval,
              const std::vector<TriangleStiffness>* extra = nullptr);
  // Factors the given system now, on the calling thread (the factored sweep's remedy when a solve
  // with the current factor drags on). A background factorization in flight goes on, and is
  // dropped at adoption as older than this one.
  void refactor_now(const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                    const std::vector<Mat3>* node_rotation, const std::vector<Mat3>* element_rotation,
                    const std::vector<TriangleStiffness>* extra = nullptr);
  // Computes the half columns (SupernodalSolve::HalfColumns) of all these nodes not yet cached.
  void prepare_columns(const std::vector<int32_t>& nodes);
  // A prepared node's half columns H = L^-1 P E (E its unit columns; K_f = P^T L L^T P), kept
  // until the factor changes: K_f^-1 E = P^T L^-T H, E^T K_f^-1 E' = H^T H'.
  const SupernodalSolve::HalfColumns& columns(int32_t node) const { return columns_.at(node).h; }
  // The factor in use's solve in halves (SupernodalSolve::forward .. backward).
  const SupernodalSolve& halves() const { return *active_->direct.by_hand(); }
  // Q_i = R_i R_f,i^T: how far node i turned since the factor's step (R_i: now).
  Mat3 turn(const std::vector<Mat3>* node_rotation, int32_t i) const {
    if (!node_rotation) return Mat3::Identity();
    const std::vector<Mat3>& R_f = bridge_.on ? bridge_.rotation : active_->rotation;
    return R_f.empty() ? (*node_rotation)[i] : Mat3((*node_rotation)[i] * R_f[i].transpose());
  }
  int64_t factorizations() const { return factorizations_; }
  // Factors the stepping thread waited for: made by update() or refactor_now(), or adopted from a
  // worker that was not done yet.
  int64_t waits() const { return waits_; }

  // After a change of the body's topology (a cut, a resection), between steps. The factor in use
  // becomes a bridge to the new system (SupernodalSolve::bridge): its nodes serve the nodes that
  // came from them, and each copy of a cut node moves against its node in a mode of its own,
  // coupled to the rest through B and C, the cut mesh's system as of the factor (its elements
  // at the factor's rotations, its mass and damping): so the bridge is as near the cut body's
  // system as the factor was to the uncut one. The next update() launches the new system's
  // factorization, analysis included, on the worker, adopted max(interval, kBridgeSteps)
  // updates later in lockstep (results do not depend on timing). A factor in flight is not
  // waited for: adopted on its schedule, it bridges the changes made since its launch (a blade
  // that cuts every step goes on with a factor a few steps old). A bridged factor bridges
  // further changes from its own topology. False when there is no factor to bridge (none yet, or
  // one of a model whose elements are not linear or co-rotational): the caller drops the cache
  // and the next step factors. Throws (std::bad_alloc) with nothing changed.
  bool remap(const BodyRemap& change);
  // Whether the factors made from now on keep what a bridge needs: the double factor, beside the
  // half copy the solves read (on the nidus about 8.6 MB more than the copy alone). Off by
  // default; the factored sweep turns it on for a body that may be cut (SolverBody::may_be_cut).
  void set_bridgeable(bool on) { bridgeable_ = on; }
  // kBridgeSteps steps give the worker the analysis and factorization of the nidus (about 35 ms
  // of CPU) while the stepping thread shares its core.
  static constexpr int32_t kBridgeSteps = 4;
  // The mark of the factor in use's half columns: another mark, other columns.
  uint64_t columns_id() const { return columns_id_; }
  // Whether a background refresh also makes half columns (on; a test turns it off to compare),
  // and how many adoptions have taken from it so far.
  void set_background_columns(bool on) { background_columns_ = on; }
  int64_t columns_from_worker() const { return columns_from_worker_; }
  // Blocks until the background refresh in flight, its columns included, is done (a test's
  // way to give the worker all the time it needs; adoption does not wait for the columns).
  void wait_for_worker() { worker_.wait(); }
  int32_t node_count() const { return node_count_; }

  // A step that may fail: begin() before its first update(), then commit() if the step is kept or
  // rollback() if it is undone, which puts back the factor in use, the one in flight, the refresh
  // schedule and the cached columns as they were at begin() (a failed step leaves no trace in
  // later steps). Meanwhile a factor replaced at once (new key, refactor_now) is kept aside, and a
  // background refresh is launched only at commit(); one slot so used stays as a spare (a third
  // factor's memory at most). Without begin() every call takes effect at once.
  void begin();
  void commit();
  void rollback();
  // What a later solve depends on (World::save_state), between steps only: the key and refresh
  // schedule, and the systems the factor in use and the one in flight were made from (each slot
  // keeps a copy); the half columns are made again as needed (each node's alone: the same
  // bits). load() into a fresh LaggedFactor reads it back and factors those systems again (the
  // same matrix factors to the same bits); it throws Error(Parse) on a state that does not fit
  // `pattern`.
  void save(ByteWriter& out) const;
  void load(ByteReader& in, const FemModel& fem);

 private:
  struct Slot {
    // The preconditioner's solves: half or single, and only the copy kept, unless the factor is
    // to serve a bridge (set_bridgeable), whose Schur complement is a small difference of large
    // terms that needs the double factor (remap()).
    Slot() { direct.set_copy(SupernodalSolve::Copy::Half, false); }
    void keep_double(bool on) { direct.set_copy(SupernodalSolve::Copy::Half, on); kept_double = on; }
    bool kept_double = false;
    DirectSolver direct;
    BlockValues A;            // the system factored (a copy: the worker factors it; a saved state keeps it)
    Projection projection;
    std::vector<Mat3> rotation;  // R_f per node (empty: identity)
    int64_t born = -1;           // the solve whose system it is
    // A background refresh's half columns: of these nodes (set at launch), the first
    // `prepared_count` made by the worker.
    std::vector<int32_t> prepare;
    std::vector<SupernodalSolve::HalfColumns> prepared;
    size_t prepared_count = 0;
    uint64_t generation = 0;  // the topology (LaggedFactor::generation_) its analysis is of
    std::vector<Mat3> element_rotation;  // what A was assembled with (empty: the linear model)
    BlockPattern pattern;                // A's (the worker reads it: the body's changes with its topology)
  };
  // The bridge after a topology change (remap()), until the new system's factor is adopted.
  struct Bridge {
    bool on = false;
    std::vector<int32_t> factor_node, factor_tet;   // per node and tet now: the factor's
    std::vector<std::pair<int32_t, int32_t>> copy;  // (copy, its group's first node)
    std::vector<Mat3> rotation;                     // per node now: the factor's node rotation (turn())
    Eigen::MatrixXd B, C;                           // SupernodalSolve::bridge's, until it has them
    void drop_blocks() {
      B.resize(0, 0);
      C.resize(0, 0);
    }
  };
  // The bridge from `slot`'s factor to the nodes and tets of `fem` (maps into the slot's own).
  Bridge make_bridge(const Slot& slot, const FemModel& fem, std::vector<int32_t> factor_node,
                     std::vector<int32_t> factor_tet) const;
  // Keeps the bridge for a rollback before a step first changes it; ends it.
  void keep_bridge();
  void end_bridge();
  // Readies `slot` to be analysed for the current topology (forgets an older one's analysis).
  void renew(Slot& slot) const;
  // B and C of the bridge (SupernodalSolve::bridge), from the slot's system.
  void bridge_blocks(const Slot& slot, const FemModel& fem, Bridge& bridge) const;
  static void read_slot(Slot& slot, ByteReader& in);
  // Checks a slot read against the pattern it factors, then analyses and factors it.
  static void factor_read_slot(Slot& slot, const BlockPattern& pattern);
  void factor(Slot& slot, const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
              const std::vector<Mat3>* node_rotation, const std::vector<Mat3>* element_rotation,
              const std::vector<TriangleStiffness>* extra);
  // Throws Error(Unsupported) unless the slot's factor can be solved in halves (halves()).
  static void require_halves(const Slot& slot);
  // slot.A = A - extra.
  static void copy_system(Slot& slot, const BlockPattern& pattern, const BlockValues& A,
                          const std::vector<TriangleStiffness>* extra);
  void adopt(const FemModel& fem);  // fem: the body's now (a bridge to it)
  void launch();  // the background factorization of *pending_
  static void factor_pending(void* self);      // the worker's job
  // `slot` (active_ or pending_), or, in a step between begin() and its end, a spare in its place
  // when begin() saw it in use or in flight: rollback() puts that one back as it was.
  Slot& writable(std::unique_ptr<Slot>& slot);
  void clear_columns();
  static void save_slot(const Slot& slot, ByteWriter& out);

  Key key_;
  std::unique_ptr<Slot> active_, pending_;
  bool in_flight_ = false;  // *pending_ is being (or was) factored by worker_, not yet adopted
  std::atomic<bool> stop_preparing_{false};  // adoption is due: the worker makes no more columns
  bool background_columns_ = true;
  std::vector<int32_t> recent_nodes_;  // the nodes with columns of the factor adopt() replaced
  int64_t columns_from_worker_ = 0;
  Slot* job_slot_ = nullptr;  // the worker's job: the slot it factors
  // The changes since the job's launch (remap()): per node and tet now, the job's (empty: none).
  std::vector<int32_t> job_node_, job_tet_;
  // begin() .. commit() / rollback().
  struct Saved {
    Key key;
    int64_t step = 0, launched_at = -1, factorizations = 0;
    const Slot* active = nullptr;
    const Slot* pending = nullptr;
    bool in_flight = false;
    uint64_t columns_id = 0;
    int64_t waits = 0;
  } saved_;
  bool open_ = false;
  std::unique_ptr<Slot> kept_[2], spare_;  // slots of begin() replaced in the step; a free one
  bool launch_staged_ = false;             // a refresh to launch at commit()
  std::vector<Mat3> staged_rotation_;
  int64_t staged_born_ = -1;
  bool columns_cleared_ = false;
  std::vector<int32_t> columns_added_;
  int64_t step_ = 0, launched_at_ = -1;
  int64_t factorizations_ = 0, waits_ = 0;
  int32_t node_count_ = 0;
  bool bridgeable_ = false;
  Bridge bridge_, kept_bridge_;
  bool bridge_kept_ = false;  // kept_bridge_ is the one at begin()
  uint64_t generation_ = 0;  // topology changes so far (remap())
  // The half columns, each marked with the factor it was made from: a new factor marks them all
  // stale instead of freeing them, and prepare_columns() makes them again in the same buffers (a
  // refresh adopted allocates nothing). In a step that may be undone, the first new factor swaps
  // in the other map (kept: stale marks, buffers to reuse), and a rollback swaps back.
  struct CachedColumns {
    SupernodalSolve::HalfColumns h;
    uint64_t made_for = 0;  // a columns_id_
  };
  std::unordered_map<int32_t, CachedColumns> columns_, columns_kept_;
  uint64_t columns_id_ = 1, last_columns_id_ = 1;  // the factor in use's mark; the last one given
  BackgroundThread worker_{"mica-factor"};  // last: destroyed (joined) before the slots it factors
};

// The warped preconditioner z = Q K_f^-1 Q^T r (Q per node, see LaggedFactor::turn).
class WarpedFactorPreconditioner : public Preconditioner {
 public:
  // Takes the turns Q of the factor now in use; bind again after the factor changes.
  void bind(LaggedFactor* factor, const std::vector<Mat3>* node_rotation);
  // In single precision, from the factor's copy: three quarters of the time of a double solve
  // pair on the nidus (bench_factor); the solvers' residuals and projections stay in double.
  void apply(const Vec3List& r, Vec3List& z) override;
  // apply() in halves (LaggedFactor::halves): forward(r) leaves L^-1 P Q^T r in the halves'
  // workspace, where the caller may read and add half columns; backward(z) = Q P^T L^-T of it.
  // The turns go in the same passes as the factor's permutation (SupernodalSolve::forward).
  void forward(const Vec3List& r);
  void backward(Vec3List& z);

 private:
  LaggedFactor* factor_ = nullptr;
  size_t size_ = 0;  // nodes of the last forward()
  std::vector<Mat3> turn_;  // empty: no warping (a linear body)
};

}  // namespace mica
