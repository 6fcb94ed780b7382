// SPDX-License-Identifier: Apache-2.0
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
#include "solver/velocity_solver.hpp"
#include "world/body.hpp"
#include "world/slot_map.hpp"
#include "world/stats.hpp"
#include "world/step_results.hpp"
#include "world/step_context.hpp"
#include "world/topology_change.hpp"

namespace mica {

enum class LogLevel { Error, Warning, Info };

struct StateShape;  // state_io.cpp

constexpr int32_t kMaxThreads = 1024;  // WorldSettings::threads above this is refused
// The shortest time step World::step takes (s): below it forces (impulse / h) and stiffnesses
// (1 / h^2) leave double precision.
constexpr double kMinTimeStep = 1e-9;
// Above this many contact rows in one step the exact solvers (dense Delassus matrix, one linear
// solve per row) take seconds; the world logs a warning the first time.
constexpr size_t kExactRowsWarning = 500;

// The solver's settings (tolerance, max_iterations, warm_start, pgs_sweeps, paper_norm,
// relaxation, refactor_interval, refactor_after: solver/velocity_solver.hpp) and the world's.
struct WorldSettings : SolverSettings {
  Vec3 gravity{0, -9.81, 0};
  // The haptic default (since 0.5): MICA with the factored sweep. Direct is the exact reference.
  SolverKind solver = SolverKind::Mica;
  MicaSweep mica_sweep = MicaSweep::Factored;
  bool plan_all_stages = false;  // run every stage even when its effect is absent
  double max_recovery_speed = 1.0; // m/s, clamps the recovery of penetration (normal_bias)
  double time_budget_ms = 0;       // > 0: every iterative solve of a step stops this long after the step began
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
  HostTasks tasks;  // set: the host's job system lends the threads - 1 workers (else the world makes them)
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
  Vec3 next_reaction = Vec3::Zero();  // the running step's (World::compute_forces), reaction once it commits
};

// A body created overlapping another deeper than contacts look (World::add_body): the two do
// not collide with each other until their bounds part.
struct BodyOverlap {
  Id other = 0;         // the body it overlaps
  double depth = 0;     // m: the deepest surface node of either inside the other
  int32_t node = -1;    // that node
  bool node_of_created = true;  // the node is the created body's (else the other's)
  double reach = 0;     // m: how deep body contacts look for that node (the other body's surface edge, or the margin)
};

// The pose a device gave its tool or grasp handle at the start of a step (World::follow_devices):
// what a recording keeps of the device, and what its replay hands the step instead.
struct AdoptedPose {
  Id target = 0;  // a tool or a constraint
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

class Recorder;  // recording.hpp

// Throws Error(InvalidArgument) naming the first setting out of its domain.
void validate(const WorldSettings& settings);
// Throws Error(InvalidArgument) for a pose that is not finite or has a zero quaternion.
void check_tool_pose(const Vec3& position, const Eigen::Quaterniond& orientation);

class World {
 public:
  explicit World(const WorldSettings& settings);
  ~World();
  World(World&&) noexcept;  // defined where Recorder is complete
  World& operator=(World&&) noexcept;

  const WorldSettings& settings() const { return settings_; }
  void set_gravity(const Vec3& g);

  // Logs a warning for each body the new one overlaps deeper than contacts look; see
  // overlaps_at_creation().
  Id add_body(const TetMesh& mesh, const BodySettings& settings, const Vec3& translation, const Vec3& velocity);
  // The bodies the last add_body found its body overlapping (overlaps.cpp), and what it logged.
  const std::vector<BodyOverlap>& overlaps_at_creation() const { return last_overlaps_; }
  std::string overlap_message(Id created, const BodyOverlap& overlap) const;
  // Whether contacts between two bodies are skipped: created overlapping, their bounds not yet parted.
  bool contacts_skipped(Id a, Id b) const;
  void remove_body(Id id);
  Body& body(Id id) { return bodies_.get(id, "body"); }
  const Body& body(Id id) const { return bodies_.get(id, "body"); }
  void set_node_forces(Id body, const std::vector<int32_t>& nodes, const Vec3List& forces);
  // The host moves a body's nodes (node_state.cpp): one finite value per node, else throws with
  // the world unchanged. Positions drop what was derived from the old ones (see there).
  void set_positions(Id body, const Vec3List& x);
  void set_velocities(Id body, const Vec3List& v);
  // One material per tet: rebuilds the body's model (stiffness, mass, so damping and gravity) and
  // drops the solver's factors of it; positions and velocities stay. Throws, changing nothing,
  // for a wrong count or a material out of its domain (the message names the tet).
  void set_body_materials(Id body, const std::vector<Material>& materials);
  // Resection (remove_tets.cpp): removes the listed tets; returns their mass (kg). The kept tets
  // keep their order, nodes left without a tet go and the rest are renumbered in order; the
  // model, the state, the constraints and the warm starts follow (see there). Throws, changing
  // nothing, for an index out of range, a duplicate, every tet, or a driven grasp it would empty.
  double remove_tets(Id body, const std::vector<int32_t>& tets);
  // Incision (cut.cpp): separates the body along the triangles (world space, where the body is
  // now) by duplicating the nodes of the faces they cross; no tet is added or removed, so the
  // mass stays. Returns what it separated. Throws, changing nothing, for a triangle not finite.
  struct CutResult {
    int32_t faces = 0;        // faces separated
    int32_t nodes_added = 0;  // node copies made
  };
  CutResult cut(Id body, const Vec3List& triangle_corners);
  // Per tet, the force per metre of blade edge the tissue bears before it parts (N/m, >= 0);
  // throws, changing nothing, for a wrong count or a value not finite or negative.
  void set_cutting_resistance(Id body, const std::vector<double>& per_tet);
  // Makes a capsule tool a blade (blade.cpp) or an ordinary tool; throws for another shape.
  void set_tool_blade(Id tool, bool blade);
  // Told of each change of a body's tets, once it is made (the C layer's render meshes follow).
  void set_topology_listener(TopologyListener listener) { topology_listener_ = std::move(listener); }
  // Numeric factorizations the solver has made of this body's systems so far.
  int64_t factorizations(Id body) const;

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
  // The pose the next step moves the tool to, sweeping from its last pose (continuous contact:
  // the tool pushes what lies on its way, as a hand does).
  void set_tool_pose(Id id, const Vec3& position, const Eigen::Quaterniond& orientation);
  // Puts the tool at a pose without a sweep (the pose it comes from is this one): nothing on the way
  // is pushed, and the warm starts of its contacts are forgotten.
  void teleport_tool(Id id, const Vec3& position, const Eigen::Quaterniond& orientation);
  // Devices: added and removed only while no servo loop runs. A device drives a tool or a grasp
  // (a constraint with a handle that follows no tool), not both; check_device_target throws as
  // add_device would for the ids of `settings` (StaleId, InvalidArgument), changing nothing.
  void check_device_target(const DeviceSettings& settings) const;
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

  // The last step's contacts, their rows of G and the impulses on them.
  const std::vector<Contact>& contacts() const { return last_.contacts; }
  const ContactRows& contact_rows() const { return last_.rows; }
  const std::vector<double>& impulses() const { return last_.lambda; }  // per contact row, N s
  // Per contact, the impulse on its body of the contact-curvature term (rounded tools; else 0), N s.
  const Vec3List& curvature_impulses() const { return last_.curvature_impulse; }
  // The ids behind the last step's indices: Contact::a.body / b.body index step_bodies(),
  // Contact::tool indexes step_tools().
  const std::vector<Id>& step_bodies() const { return last_.bodies; }
  const std::vector<Id>& step_tools() const { return last_.tools; }

  // The dynamic state (state_io.cpp): positions, velocities, warm starts, the solver's lagged
  // factors, tool poses and forces, constraint targets and handles, device filters, counters.
  // save_state() serialises it; restore_state() checks the buffer whole (header, checksum, the
  // world's shape) and throws with the world unchanged, or puts the state back.
  std::vector<uint8_t> save_state() const;
  void restore_state(const uint8_t* data, size_t size);

  // One implicit step of h seconds. Throws Error(Numerical) and keeps the old state when
  // the result is not finite.
  void step(double h);

  // Recording (recording.cpp): from a world with nothing in it yet, every call that changes the
  // world and every step is written to `path` (throws Error(Io) if it cannot be opened,
  // Error(WrongState) if the world already has a body, tool, constraint or device).
  // stop_recording() flushes and closes it, and throws Error(Io) if a write failed.
  void start_recording(const std::string& path);
  void stop_recording();
  bool recording() const { return recorder_ != nullptr; }
  // A replay's step (replay.cpp): the poses the recorded devices gave their tools stand in for
  // the devices (this world's are inert stand-ins made by the replay).
  void step_replayed(double h, const std::vector<AdoptedPose>& poses);
  // FNV-1a of what the last step left: positions and velocities of the bodies, force and torque of
  // the tools, reactions of the constraints. A replay compares it with the recording's.
  uint64_t fingerprint() const;

  Plan plan() const;
  const WorldStats& stats() const { return last_.stats; }
  int32_t thread_count() const { return pool_ ? pool_->size() : 1; }  // settings().threads resolved

  template <class F>
  void for_each_body(F&& f) const { bodies_.for_each(f); }
  // The ids of the live objects of one kind, in slot order (creation order until one is destroyed).
  std::vector<Id> ids(IdKind kind) const;

 private:
  // The stages of a step (step.cpp), in the order advance() runs them.
  void advance(double h);
  void prepare_step(double h);  // fills step_ and next_ for a step of h seconds
  void follow_devices();
  void collide(StepContext& ctx);
  bool bounds_overlap(const SurfaceView& a, const SurfaceView& b) const;
  // Bodies placed overlapping (overlaps.cpp).
  std::vector<BodyOverlap> find_overlaps(Body& created);
  void forget_parted_overlaps();
  // Logs a warning when a tool's origin is inside a body: its first sweep would drag the tissue.
  void warn_if_inside_a_body(Id tool) const;
  void apply_loads(Body& b) const;
  void assemble_elements(const StepContext& ctx, Body& b) const;
  void add_contact_stiffness(const StepContext& ctx, Body& b) const;
  void add_damping(const StepContext& ctx, Body& b) const;
  void build_projection(const StepContext& ctx, Body& b) const;
  void form_rhs(const StepContext& ctx, Body& b) const;
  void solve(const StepContext& ctx);
  // Co-rotational re-linearisation (relinearise.cpp).
  void start_rotations(const StepContext& ctx, Body& b) const;
  void relinearise(const StepContext& ctx, StageRunner& stage);
  void add_to_stats(const SolveReport& report);
  // Numeric factorizations the solver has made of the step's bodies so far (the stats' per step).
  int64_t factorizations(const StepContext& ctx) const;
  int64_t factor_waits(const StepContext& ctx) const;  // of them, those the stepping thread waited for
  void check_finite(const StepContext& ctx) const;
  void compute_forces(const StepContext& ctx);  // the three below
  void tool_forces(const StepContext& ctx);
  void curvature_forces(const StepContext& ctx);
  void constraint_reactions(const StepContext& ctx);
  void check_forces() const;
  void commit(const StepContext& ctx);
  void publish_force_models();
  // A failed step (undo.cpp): what the step took from the devices (the host's input) goes back.
  void save_undo();
  void undo();

  void state_shape(StateShape& out) const;  // state_io.cpp
  // Visits the list of the state (state_fields.hpp) over the whole world, in the saved order;
  // body_extra(v, body) adds what the solver keeps for each body.
  template <class V, class BodyExtra>
  void visit_world_state(V& v, BodyExtra&& body_extra) const;
  Id insert_lpc(Id body, const std::vector<int32_t>& nodes, const LpcSpec& spec);  // add_lpc, unrecorded

  // The keys of the rows of the last step's contacts that touch a body or a tool (their warm starts).
  std::vector<uint64_t> contact_row_keys(Id id) const;
  // A world with threads > 1 colours a dynamic body's tets and nodes for its parallel loops.
  void colour_for_threads(Body& b) const;

  // Makes the body's model, state and constraints follow a new topology (topology_change.cpp);
  // throws, changing nothing, when it cannot (a driven grasp left without nodes).
  void adopt_topology(Id body, NewTopology& topology);
  CutResult cut_body(Id body, const Vec3List& triangle_corners);  // cut(), unrecorded
  // After a step: the cuts its blades made (blade.cpp).
  void cut_with_blades(const StepContext& ctx);

  bool needs_loads(const Body& b) const;
  bool needs_damping(const Body& b) const;

  WorldSettings settings_;
  SlotMap<Body, IdKind::Body> bodies_;
  SlotMap<Lpc, IdKind::Lpc> lpcs_;
  SlotMap<Tool, IdKind::Tool> tools_;
  SlotMap<DeviceLink, IdKind::Device> devices_;
  // The last step's results (published) and the running step's (written by its stages); commit
  // swaps them. The warm start is keyed by row and rewritten at commit.
  StepResults last_, next_;
  std::unordered_map<uint64_t, double> warm_start_; // impulses by row key
  mutable std::vector<std::pair<uint64_t, double>> warm_start_list_;  // warm_start_ in key order: a saved state's
  StepContext step_;                                // the running step's context, kept for its capacity
  struct SavedPose {  // save_undo(): a device-driven tool's or handle's pose before the step
    Id target;
    Vec3 position;
    Eigen::Quaterniond orientation;
  };
  std::vector<SavedPose> saved_poses_;
  int64_t bodies_created_ = 0;
  bool warned_exact_rows_ = false;
  std::vector<BodyOverlap> last_overlaps_;          // of the last add_body
  std::unique_ptr<Recorder> recorder_;              // while recording
  TopologyListener topology_listener_;              // the C layer's, told of each topology change
  std::vector<AdoptedPose> adopted_;                // the poses follow_devices gave tools this step
  const std::vector<AdoptedPose>* replayed_ = nullptr;  // step_replayed: these instead of the devices
  std::vector<std::pair<Id, Id>> overlapping_;      // pairs whose contacts are skipped until their bounds part
  std::unique_ptr<ThreadPool> pool_;                // threads > 1 only; the step's parallel loops
  // Chosen once from the settings; keeps per-body factors (some factored in the background on
  // the bodies' patterns), so it goes before the bodies do.
  std::unique_ptr<VelocitySolver> solver_;
  std::vector<SolverBody> solver_bodies_;           // the solver's view of the dynamic bodies, rebuilt per solve
};

}  // namespace mica
