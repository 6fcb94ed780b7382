// SPDX-License-Identifier: Apache-2.0
// The velocity solve of a step, one contract for every method. Per body k (a SolverBody)
//   A_k v_k = b_k + G_k^T lambda   on the free directions S_k,   (I - S_k) v_k = z_k,
// and per contact (ContactRows) 0 <= lambda_n _|_ G_n v + bias_n >= 0 with the tangent pair on
// Coulomb's disk |lambda_t| <= mu lambda_n. A solver owns whatever it keeps between steps
// (factorizations, workspaces), keyed by SolverBody::key; the world picks one solver when it is
// made (make_velocity_solver) and calls solve() once per solve of a step.
//
// Adding a solver: a class here in solver/ and a case in make_velocity_solver.
#pragma once
#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/byte_stream.hpp"
#include "core/colouring.hpp"
#include "core/thread_pool.hpp"
#include "fem/fem_model.hpp"
#include "solver/contact_rows.hpp"
#include "solver/projected_system.hpp"

namespace mica {

enum class SolverKind { Direct, Pcg, Mica };
// How MICA anticipates and updates velocities: the paper's block Gauss-Seidel on the diagonal
// blocks, or the factor of the rest system warped by node rotations (solver/factored_mica.hpp).
enum class MicaSweep { GaussSeidel, Factored };

// What every solve of a world shares (the first part of WorldSettings).
struct SolverSettings {
  double tolerance = 1e-8;      // the stopping test's (each solver's header says on what)
  int32_t max_iterations = 200;
  bool warm_start = true;       // MICA: start from the velocities the caller gives and the last impulses (else zero)
  int32_t pgs_sweeps = 1;       // MICA: PGS sweeps over the contact rows per iteration
  bool paper_norm = false;      // MICA: stop on the paper's 2-norm of the change of (v, lambda) instead
  double relaxation = 1.0;      // MICA: MBGS over-relaxation omega in (0, 2); 1 is the paper's Gauss-Seidel
  // Factored sweep: refresh each co-rotational body's factor from its current system every this
  // many steps, factored on a background thread and adopted that many steps later (0: refactor
  // only when the step size, damping or constraint set changes).
  int32_t refactor_interval = 0;
  // Factored sweep: a solve that has used this many conjugate-gradient iterations refactors the
  // current system and goes on with it (about what a factorization costs on a body of some
  // thousand nodes; 0: never).
  int32_t refactor_after = 100;
  // Factored sweep: hold the contact rows predicted active as equalities inside one projected
  // conjugate-gradient solve per round (factored_mica_active_set.cpp) instead of alternating
  // impulse updates and velocity solves.
  bool active_set = true;
};

// What one solve may use of its step.
struct SolveContext {
  using Clock = std::chrono::steady_clock;
  std::optional<Clock::time_point> deadline;  // iterative solves stop here (out_of_time)
  ThreadPool* pool = nullptr;                 // null: serial
};

// What a body's A was assembled for: a change of any of these is a new system.
struct SystemKey {
  double h = 0, alpha = 0, beta = 0;
  bool operator==(const SystemKey& o) const { return h == o.h && alpha == o.alpha && beta == o.beta; }
};

// A stiffness A carries on three nodes beyond the body's elements: a rounded tool's contact
// curvature, h^2 F K_c over a triangle's corners (World::add_contact_stiffness). It is of low
// rank and changes every step, so a factored solver factors A without it and adds it back
// exactly (Woodbury; factored_mica.hpp).
struct TriangleStiffness {
  std::array<int32_t, 3> nodes;
  Eigen::Matrix<double, 9, 9> K;  // blocks (r, s) couple nodes[r] and nodes[s]
};

// One body's system as the solver sees it.
struct SolverBody {
  uint64_t key = 0;                          // the body's caches in the solver (unique per world)
  const FemModel* fem = nullptr;             // the pattern of A, node masses, elements
  const BlockValues* A = nullptr;
  const Vec3List* b = nullptr;
  const Projection* projection = nullptr;
  Vec3List* v = nullptr;                     // in: the warm start; out: the velocities
  Vec3List* contact_impulse = nullptr;       // out: G^T lambda per node, N s
  const Colouring* colours = nullptr;        // node blocks for a parallel sweep (node_colouring.hpp), or null
  const std::vector<Mat3>* rotation = nullptr;  // element rotations A is built with (null: linear model)
  const std::vector<TriangleStiffness>* extra_stiffness = nullptr;  // part of A (null: none)
  SystemKey system;
  uint64_t matrix_version = 0;      // changes whenever the values of A change
  uint64_t constraint_version = 0;  // changes whenever the body's constraint set changes
  // The body may be cut (a blade in the world, or a change of its tets before): a solver keeps
  // what carries its caches across a change (remap), at a cost in memory.
  bool may_be_cut = false;

  const BlockPattern& pattern() const { return fem->pattern; }
  int32_t node_count() const { return fem->node_count(); }
  ProjectedSystem projected() const { return {fem->pattern, *A, *projection}; }
};

// A change of a body's topology, as a solver sees it (World::adopt_topology).
struct BodyRemap {
  const FemModel& before;                   // the body's model before the change
  const FemModel& after;                    // and after
  const std::vector<int32_t>& node_origin;  // per node after, its node before
  const std::vector<int32_t>& tet_origin;   // per tet after, its tet before
  uint64_t constraint_version;              // the body's constraint set after (bumped by a change)
  bool elements_linear;                     // its stiffness is the linear or co-rotational model's
};

class VelocitySolver {
 public:
  virtual ~VelocitySolver() = default;
  // lambda: in, the warm start per row (the last step's impulses, or zero); out, the impulses
  // (N s). Writes each body's v and contact_impulse.
  virtual SolveReport solve(const SolveContext& ctx, std::vector<SolverBody>& bodies, const ContactRows& rows,
                            std::vector<double>& lambda) = 0;
  // The compliance each row of the last solve saw (its diagonal of G A^-1 G^T or of the
  // solver's approximation of it), 0 for a row nothing can move along.
  virtual const std::vector<double>& row_diagonal() const = 0;
  // Drops what the solver keeps for a body (before the body goes).
  virtual void forget(uint64_t /*key*/) {}
  // After a change of a body's topology (World::adopt_topology), between steps. A solver that can
  // go on with what it keeps (a lagged factor: LaggedFactor::remap) carries it over; by default it
  // is dropped, as by forget(). Never throws.
  virtual void remap(uint64_t key, const BodyRemap& /*change*/) { forget(key); }
  // Numeric factorizations made for a body so far (0 for a solver that does not factor).
  virtual int64_t factorizations(uint64_t /*key*/) const { return 0; }
  // Of them, those the stepping thread waited for (made in the step, or adopted from a background
  // thread that was not done).
  virtual int64_t factor_waits(uint64_t key) const { return factorizations(key); }
  // A step that may fail (World::step): begin_step() before it, then commit_step() when it is
  // kept or rollback_step() when it is undone, which puts back what the solver keeps across steps
  // as it was at begin_step() (a failed step leaves no trace in later ones).
  virtual void begin_step() {}
  virtual void commit_step() {}
  virtual void rollback_step() {}
  // A saved state (World::save_state), between steps: what the solver keeps for a body that
  // changes later results (a lagged factor; not a factor of the current matrix, which
  // World::restore_state makes the solver redo by bumping the body's matrix_version).
  virtual void save_body(uint64_t /*key*/, ByteWriter& /*out*/) const {}
  // Reads, for each body, what save_body wrote, and replaces what the solver keeps for it: all
  // or nothing (throws with nothing replaced).
  struct SavedBody {
    uint64_t key;
    const FemModel* fem;
    const uint8_t* data;
    size_t size;
  };
  virtual void restore_bodies(const std::vector<SavedBody>& /*bodies*/) {}
};

// A solver that keeps a Cache per body (factors, workspaces), by SolverBody::key, made on first
// use and dropped by forget(); Cache::factorizations() counts the factorizations it made.
template <class Cache>
class CachingVelocitySolver : public VelocitySolver {
 public:
  void forget(uint64_t key) override { caches_.erase(key); }
  int64_t factorizations(uint64_t key) const override {
    const auto it = caches_.find(key);
    return it == caches_.end() ? 0 : it->second->factorizations();
  }

 protected:
  Cache& cache_of(const SolverBody& body) {
    std::unique_ptr<Cache>& cache = caches_[body.key];
    if (!cache) cache = std::make_unique<Cache>();
    return *cache;
  }
  template <class F>
  void for_each_cache(F&& f) {
    for (auto& [key, cache] : caches_) f(*cache);
  }
  const Cache* find_cache(uint64_t key) const {
    const auto it = caches_.find(key);
    return it == caches_.end() ? nullptr : it->second.get();
  }
  Cache* find_cache(uint64_t key) {
    const auto it = caches_.find(key);
    return it == caches_.end() ? nullptr : it->second.get();
  }
  // Puts these caches in place of the bodies' (a null one: none); no-throw once reserved.
  void replace_caches(std::vector<std::pair<uint64_t, std::unique_ptr<Cache>>>& caches) {
    caches_.reserve(caches_.size() + caches.size());
    for (auto& [key, cache] : caches) {
      if (cache) caches_[key] = std::move(cache);
      else caches_.erase(key);
    }
  }

 private:
  std::unordered_map<uint64_t, std::unique_ptr<Cache>> caches_;
};

std::unique_ptr<VelocitySolver> make_velocity_solver(SolverKind kind, MicaSweep sweep, const SolverSettings& settings);

// v_k of every body from the warm start to zero (MICA without warm start).
void zero_velocities(std::vector<SolverBody>& bodies);
// contact_impulse of every body = G^T lambda.
void scatter_contact_impulses(const ContactRows& rows, const std::vector<double>& lambda,
                              std::vector<SolverBody>& bodies);
// |S (b + G^T lambda - A v)| / max(|S b|, |S G^T lambda|, |S A v|, |S M v|, 1 um/s of momentum
// per node), the worst body's, with M lumped and G^T lambda from SolverBody::contact_impulse.
double momentum_residual(const std::vector<SolverBody>& bodies);

}  // namespace mica
