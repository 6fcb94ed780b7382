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
  void update(const FemModel& fem, const Key& key, const BlockValues& A, const Projection& projection,
              const std::vector<Mat3>* node_rotation, int32_t interval,
              const std::vector<TriangleStiffness>* extra = nullptr);
  // Factors the given system now, on the calling thread (the factored sweep's remedy when a solve
  // with the current factor drags on). A background factorization in flight goes on, and is
  // dropped at adoption as older than this one.
  void refactor_now(const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
                    const std::vector<Mat3>* node_rotation, const std::vector<TriangleStiffness>* extra = nullptr);
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
    return active_->rotation.empty() ? (*node_rotation)[i] : Mat3((*node_rotation)[i] * active_->rotation[i].transpose());
  }
  int64_t factorizations() const { return factorizations_; }
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
  void load(ByteReader& in, const BlockPattern& pattern);

 private:
  struct Slot {
    // The preconditioner's solves: half or single, and only the copy kept (see set_copy).
    Slot() { direct.set_copy(SupernodalSolve::Copy::Half, false); }
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
  };
  void factor(Slot& slot, const BlockPattern& pattern, const BlockValues& A, const Projection& projection,
              const std::vector<Mat3>* node_rotation, const std::vector<TriangleStiffness>* extra);
  // Throws Error(Unsupported) unless the slot's factor can be solved in halves (halves()).
  static void require_halves(const Slot& slot);
  // slot.A = A - extra.
  static void copy_system(Slot& slot, const BlockPattern& pattern, const BlockValues& A,
                          const std::vector<TriangleStiffness>* extra);
  void adopt();
  void launch(const BlockPattern& pattern);  // the background factorization of *pending_
  static void factor_pending(void* self);      // the worker's job
  // `slot` (active_ or pending_), or, in a step between begin() and its end, a spare in its place
  // when begin() saw it in use or in flight: rollback() puts that one back as it was.
  Slot& writable(std::unique_ptr<Slot>& slot);
  void clear_columns();
  static void save_slot(const Slot& slot, ByteWriter& out);
  static void load_slot(Slot& slot, ByteReader& in, const BlockPattern& pattern);

  Key key_;
  std::unique_ptr<Slot> active_, pending_;
  bool in_flight_ = false;  // *pending_ is being (or was) factored by worker_, not yet adopted
  std::atomic<bool> stop_preparing_{false};  // adoption is due: the worker makes no more columns
  bool background_columns_ = true;
  std::vector<int32_t> recent_nodes_;  // the nodes with columns of the factor adopt() replaced
  int64_t columns_from_worker_ = 0;
  Slot* job_slot_ = nullptr;  // the worker's job: the slot and pattern it factors
  const BlockPattern* job_pattern_ = nullptr;
  // begin() .. commit() / rollback().
  struct Saved {
    Key key;
    int64_t step = 0, launched_at = -1, factorizations = 0;
    const Slot* active = nullptr;
    const Slot* pending = nullptr;
    bool in_flight = false;
    uint64_t columns_id = 0;
  } saved_;
  bool open_ = false;
  std::unique_ptr<Slot> kept_[2], spare_;  // slots of begin() replaced in the step; a free one
  bool launch_staged_ = false;             // a refresh to launch at commit()
  const BlockPattern* staged_pattern_ = nullptr;
  std::vector<Mat3> staged_rotation_;
  int64_t staged_born_ = -1;
  bool columns_cleared_ = false;
  std::vector<int32_t> columns_added_;
  int64_t step_ = 0, launched_at_ = -1;
  int64_t factorizations_ = 0;
  int32_t node_count_ = 0;
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
