// The world: bodies, constraints, settings, and the step. Every mutating call validates
// everything before it changes anything, so a call that throws leaves the world as it was.
#pragma once
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <functional>
#include <unordered_map>

#include "core/thread_pool.hpp"
#include "collision/contact.hpp"
#include "haptics/device_link.hpp"
#include "solver/exact_contact_solver.hpp"
#include "solver/factored_mica.hpp"
#include "solver/mica_solver.hpp"
#include "world/body.hpp"
#include "world/slot_map.hpp"
#include "world/stats.hpp"

namespace mica {

enum class SolverKind { Direct, Pcg, Mica };
// How MICA anticipates and updates velocities: the paper's block Gauss-Seidel on the diagonal
// blocks, or the factor of the rest system warped by node rotations (solver/factored_mica.hpp).
enum class MicaSweep { GaussSeidel, Factored };
enum class LogLevel { Error, Warning, Info };

constexpr int32_t kMaxThreads = 1024;  // WorldSettings::threads above this is refused
// The shortest time step World::step takes (s): below it forces (impulse / h) and stiffnesses
// (1 / h^2) leave double precision.
constexpr double kMinTimeStep = 1e-9;
// Above this many contact rows in one step the exact solvers (dense Delassus matrix, one linear
// solve per row) take seconds; the world logs a warning the first time.
constexpr size_t kExactRowsWarning = 500;

struct WorldSettings {
  Vec3 gravity{0, -9.81, 0};
  SolverKind solver = SolverKind::Direct;
  int32_t max_iterations = 200;
  double tolerance = 1e-8;
  bool plan_all_stages = false;  // run every stage even when its effect is absent
  int32_t pgs_sweeps = 1;          // MICA: PGS sweeps over the contacts per iteration
  double max_recovery_speed = 1.0; // m/s, clamps the recovery of penetration (normal_bias)
  bool paper_norm = false;         // MICA: stop on the paper's 2-norm of the change
  double relaxation = 1.0;         // MICA: MBGS over-relaxation omega in (0, 2)
  MicaSweep mica_sweep = MicaSweep::GaussSeidel;
  // Factored sweep: refresh each co-rotational body's factor from its current system every this
  // many steps, factored on a background thread and adopted that many steps later (0: refactor
  // only when the step size, damping or constraint set changes).
  int32_t refactor_interval = 0;
  // Factored sweep: a solve that has used this many conjugate-gradient iterations refactors the
  // current system and goes on with it (about what a factorization costs on a body of some
  // thousand nodes; 0: never).
  int32_t refactor_after = 100;
  double time_budget_ms = 0;       // iterative solvers: > 0 stops the solve after this much wall-clock time
  bool warm_start = true;          // MICA: start from the last step's velocities and impulses (else zero)
  bool body_contact = true;        // contact between bodies (and with static bodies)
  double body_margin = 1e-3;       // m, contacts between bodies are made for gaps below this
  double body_friction = 0;        // Coulomb coefficient between bodies
  // Threads that step the world, the caller's included: 1 runs everything on the caller (the
  // serial code, bit for bit), 0 takes every CPU the process may run on, n > 1 makes n - 1
  // workers with the world. With more than one: rotations and element assembly in parallel, and
  // MICA's MBGS sweep colour-ordered (nodes coloured so a colour's nodes share no block of A),
  // a colour's nodes in parallel. The colour order changes MICA's iterates (not its fixed point)
  // against the paper's natural order; results do not depend on the count once it is above 1.
  int32_t threads = 1;
  // Co-rotational bodies: the step is linearised with the element rotations of its start, which
  // can add energy when elements turn far within one step. After each solve the energy the step
  // gained beyond the work done on the bodies is checked (summed over the steps since the energy
  // last went down); above relinearise_tolerance times the bodies' energy the step is solved
  // again by Newton iterations of the fully implicit step (re-linearised at the rotations of the
  // iterate, with a line search), at most relinearise_max solves in all; relinearise_max < 2
  // turns this off (the frozen-rotation step, unchecked). Costs two element energies per element
  // per step when no step needs it (the rotations it computes are the next step's).
  double relinearise_tolerance = 1e-3;
  int32_t relinearise_max = 8;
  std::function<void(LogLevel, const std::string&)> log;  // optional
};

enum class LpcKind { Fixed, Plane, Line, TwoDirections };

struct LpcSpec {
  LpcKind kind = LpcKind::Fixed;
  Vec3 directions[2] = {Vec3::UnitX(), Vec3::UnitY()};
  Vec3 velocity = Vec3::Zero();  // m/s, prescribed for the constrained components
};

// The constrained directions (I - S) of a constraint kind; throws on a zero or parallel direction.
Mat3 constrained_projector(const LpcSpec& spec);

// A handle that carries target positions: node i follows position + orientation * offset_i.
// Following a tool, the handle takes the tool's pose every step (picking with forceps).
struct Handle {
  Vec3List offsets;  // m, in the handle frame
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Id tool = 0;       // 0: the host moves the handle
};

struct Lpc {
  Id body;
  std::vector<int32_t> nodes;
  Mat3 constrained;  // I - S
  Vec3 velocity;     // prescribed when there is no handle
  std::unique_ptr<Handle> handle;  // targets: z_i = C (target_i - x_i) / h each step
  Vec3 reaction = Vec3::Zero();  // N: the force on whoever holds the constraint (the user), last step
};

// Which stages the scene calls for (each body also checks its own need inside a stage).
struct Plan {
  bool loads = false, rotations = false, elements = false, damping = false;
  bool constraints = false, solve = false, integrate = false;
  bool collide = false, forces = false;
};

class World {
 public:
  explicit World(const WorldSettings& settings);

  const WorldSettings& settings() const { return settings_; }
  void set_gravity(const Vec3& g);

  Id add_body(const TetMesh& mesh, const BodySettings& settings, const Vec3& translation, const Vec3& velocity);
  void remove_body(Id id);
  Body& body(Id id) { return bodies_.get(id, "body"); }
  const Body& body(Id id) const { return bodies_.get(id, "body"); }
  void set_node_forces(Id body, const std::vector<int32_t>& nodes, const Vec3List& forces);

  Id add_lpc(Id body, const std::vector<int32_t>& nodes, const LpcSpec& spec);
  void remove_lpc(Id id);
  const Lpc& lpc(Id id) const { return lpcs_.get(id, "constraint"); }
  void set_lpc_velocity(Id id, const Vec3& velocity);
  // Per-node target positions (m) the constrained nodes reach in one step; count = node count.
  void set_lpc_targets(Id id, const Vec3List& targets);
  // Picking: holds the nodes of `body` within `radius` of `center` (current positions) on a
  // handle at `center`, following `tool` if it is not 0. Throws if no node is in reach.
  Id grab(Id body, const Vec3& center, double radius, Id tool);
  void set_handle_pose(Id lpc, const Vec3& position, const Eigen::Quaterniond& orientation);

  Id add_tool(const Tool& tool);
  void remove_tool(Id id);
  Tool& tool(Id id) { return tools_.get(id, "tool"); }
  const Tool& tool(Id id) const { return tools_.get(id, "tool"); }
  void set_tool_pose(Id id, const Vec3& position, const Eigen::Quaterniond& orientation);
  // Devices: added and removed only while no servo loop runs.
  Id add_device(std::unique_ptr<Device> device, const DeviceSettings& settings);
  void remove_device(Id id);
  DeviceLink& device(Id id) { return devices_.get(id, "device"); }
  const DeviceLink& device(Id id) const { return devices_.get(id, "device"); }
  DeviceLink* find_device(Id id) noexcept { return devices_.find(id); }  // the servo path: no throw
  const DeviceLink* find_device(Id id) const noexcept { return devices_.find(id); }
  // Any thread: while the guard lives, a device found above is not deleted by remove_device on the
  // world's thread (which waits for it); creation never moves a device. Never blocks.
  using DeviceReadGuard = SlotMap<DeviceLink, IdKind::Device>::ReadGuard;
  DeviceReadGuard device_read_guard() const { return DeviceReadGuard(devices_); }

  const std::vector<Contact>& contacts() const { return contacts_; }
  const ContactRows& contact_rows() const { return rows_; }
  const std::vector<double>& impulses() const { return lambda_; }  // per contact row, N s

  // One implicit step of h seconds. Throws Error(Numerical) and keeps the old state when
  // the result is not finite.
  void step(double h);

  Plan plan() const;
  const WorldStats& stats() const { return stats_; }
  int32_t thread_count() const { return pool_ ? pool_->size() : 1; }  // settings().threads resolved

  template <class F>
  void for_each_body(F&& f) const { bodies_.for_each(f); }

 private:
  void follow_devices();
  void publish_force_models();
  void collide(const std::vector<Body*>& dynamic, double h);
  bool bounds_overlap(const SurfaceView& a, const SurfaceView& b) const;
  void solve_mica(const std::vector<Body*>& dynamic, double h);
  void solve_delassus(const std::vector<Body*>& dynamic, double h);
  LinearSolver& linear_solver(Body& b);
  void compute_forces(const std::vector<Body*>& dynamic, double h);
  void apply_loads(Body& b) const;
  void assemble_elements(Body& b, double h, bool damping) const;
  void add_damping(Body& b, double h) const;
  void add_contact_stiffness(Body& b, double h) const;
  // The end of the step's time budget (none without one).
  std::optional<std::chrono::steady_clock::time_point> deadline() const;
  void build_projection(Body& b, double h) const;
  void form_rhs(Body& b, double h) const;
  void solve_velocities(Body& b, double h);
  // Co-rotational re-linearisation (relinearise.cpp).
  void start_rotations(Body& b) const;
  void relinearise(const std::vector<Body*>& dynamic, double h, StageRunner& stage, const std::function<void()>& solve);
  void advance(double h);
  void record(const SolveReport& report);
  void check_finite(const std::vector<Body*>& dynamic) const;
  void check_forces() const;
  // Undoing a failed step (undo.cpp): what the step may write before it fails.
  void save_undo();
  void undo();
  void commit(const std::vector<Body*>& dynamic);

  bool needs_loads(const Body& b) const;
  bool needs_damping(const Body& b) const;

  WorldSettings settings_;
  SlotMap<Body, IdKind::Body> bodies_;
  SlotMap<Lpc, IdKind::Lpc> lpcs_;
  SlotMap<Tool, IdKind::Tool> tools_;
  SlotMap<DeviceLink, IdKind::Device> devices_;
  std::vector<double> row_diagonal_;                // W_rr (or B_rr) per row: the compliance a row sees
  std::vector<Body*> dynamic_;                      // this step's dynamic bodies
  struct {  // relinearise: the energy (J) the steps since it last went down added, net
    double committed = 0, pending = 0;
    int64_t pending_step = -1;  // the step whose completion commits `pending`
  } debt_;
  std::vector<Tool*> step_tools_;
  std::chrono::steady_clock::time_point step_start_;  // for the time budget
  std::vector<SurfaceView> views_;
  std::vector<Contact> contacts_;
  ContactRows rows_;                                // this step's rows of G
  std::vector<double> lambda_;                      // impulse per row, N s
  std::unordered_map<uint64_t, double> warm_start_; // last step's impulses by row key
  std::vector<double> exact_warm_start_;            // the same per row of this step, for the exact solver
  MicaSolver mica_;
  FactoredMicaSolver factored_mica_;
  std::vector<MicaBody> mica_bodies_;
  std::vector<FactoredBody> factored_bodies_;
  std::vector<ExactBody> exact_bodies_;
  WorldStats stats_;
  WorldStats saved_stats_;
  decltype(debt_) saved_debt_;
  struct SavedTool {  // save_undo(): what a failed step puts back
    Tool* tool;
    Vec3 position;
    Eigen::Quaterniond orientation;
    Vec3 velocity, angular_velocity, force, torque;
    Mat3 stiffness;
    int32_t contact_count;
  };
  std::vector<SavedTool> saved_tools_;
  Vec3List saved_reactions_;
  int64_t bodies_created_ = 0;
  bool warned_exact_rows_ = false;
  std::unique_ptr<ThreadPool> pool_;                // threads > 1 only; the step's parallel loops
};

}  // namespace mica
