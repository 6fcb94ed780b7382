/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file mica.h
 * @brief libmica: the C API.
 *
 * libmica simulates deformable bodies (co-rotational linear tetrahedral FEM, implicit
 * steps) and the two kinds of haptic interaction with them in one solver (MICA:
 * Modified Iterative Constraint Anticipation): direct manipulation through linear
 * projection constraints, and contact with tools.
 *
 * Conventions (see docs/architecture.md):
 * - The header needs C99 or later (stdint.h types, `static inline` functions), or C++.
 * - Units are SI throughout: m, kg, s, N, Pa.
 * - Every call that can fail returns a ::mica_status; 0 is ::MICA_OK, negative values
 *   are errors, positive values are warnings (the call did its work). On an error the
 *   world is left exactly as it was and mica_world_last_error() says what was wrong.
 * - Objects inside a world are named by 64-bit ids (zero is the null id). An id carries a
 *   generation, so an id whose object was destroyed is detected, never dereferenced.
 * - Definition structs start with `struct_size`. Fill them with the matching `*_default()`
 *   function (or `*_init()` from a foreign-function interface), then change what you need.
 *   Upgrades within a major version are drop-in: the library accepts a def of any size from
 *   its size in 0.2.0 (the first release) to its own, so a program built against an older 0.x
 *   header runs unchanged, the fields its header lacked taking their defaults. A def larger
 *   than the library's (a newer header than the library) is refused with MICA_ERR_STRUCT_SIZE.
 * - Threads: a world is used by one thread at a time. Each function says who may call it.
 * - Each function lists the statuses it returns; any that allocates may also return
 *   MICA_ERR_OUT_OF_MEMORY, and any may return MICA_ERR_INTERNAL (a bug in libmica: please report
 *   it with the message).
 */
#ifndef MICA_H
#define MICA_H

#include <stddef.h>
#include <stdint.h>

/* Exported functions. libmica is built and tested on Linux (GCC) only; the Windows branch is
 * the usual DLL export/import for a future port, not a supported build. */
#if defined(MICA_STATIC)
#define MICA_API
#elif defined(_WIN32)
#if defined(MICA_BUILDING_LIBRARY)
#define MICA_API __declspec(dllexport)
#else
#define MICA_API __declspec(dllimport)
#endif
#elif defined(MICA_BUILDING_LIBRARY)
#define MICA_API __attribute__((visibility("default")))
#else
#define MICA_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/** @name Version
 *  @{ */
/** Major version: incompatible ABI changes. */
#define MICA_VERSION_MAJOR 0
/** Minor version: compatible additions. */
#define MICA_VERSION_MINOR 9
/** Patch version: fixes. */
#define MICA_VERSION_PATCH 0
/** major * 10000 + minor * 100 + patch */
#define MICA_VERSION_NUMBER (MICA_VERSION_MAJOR * 10000 + MICA_VERSION_MINOR * 100 + MICA_VERSION_PATCH)

/** The version of the library actually loaded. Thread: any.
 *  @return MICA_VERSION_NUMBER of the loaded libmica (major * 10000 + minor * 100 + patch). */
MICA_API int32_t mica_version(void);
/** @} */

/** @name Status codes
 *  @{ */
/** A status: 0 success, > 0 warning (the call did its work), < 0 error (nothing changed). */
typedef int32_t mica_status;
/** Success. */
#define MICA_OK 0
/** Warning: the step finished but the solver stopped at its cap before its tolerance. */
#define MICA_WARN_NOT_CONVERGED 1
/** Warning: the haptic device reported a warning (warm motors, force clamped by the device). */
#define MICA_WARN_DEVICE 2
/** Warning (since 0.5): the body was created overlapping another body deeper than body contacts
 *  look (about one surface edge). The body exists; the two do not collide with each other until
 *  their bounding boxes part (a tangled pair would cost seconds a step). The log callback
 *  (MICA_LOG_WARNING) and mica_world_last_error() name both bodies and the depth. */
#define MICA_WARN_BODIES_OVERLAP 3
#define MICA_ERR_NULL_ARGUMENT (-1)    /**< a required pointer is NULL */
#define MICA_ERR_INVALID_ARGUMENT (-2) /**< a value is outside its domain (NaN, negative, bad enum) */
#define MICA_ERR_OUT_OF_RANGE (-3)     /**< an index is outside its array */
#define MICA_ERR_STALE_ID (-4)         /**< the id is null, of the wrong kind, or its object was destroyed */
#define MICA_ERR_VERSION_MISMATCH (-5) /**< the header the caller compiled with does not match the library */
#define MICA_ERR_STRUCT_SIZE (-6)      /**< a def's struct_size is not one this library knows */
#define MICA_ERR_BAD_MESH (-7)         /**< the mesh has a degenerate or inverted rest element */
#define MICA_ERR_IO (-8)               /**< a file cannot be opened, read or written */
#define MICA_ERR_PARSE (-9)            /**< a file is malformed */
#define MICA_ERR_NUMERICAL (-10)       /**< the step produced non-finite values (the step was undone) */
#define MICA_ERR_WRONG_STATE (-11)     /**< the call is not allowed now */
#define MICA_ERR_UNSUPPORTED (-12)     /**< not available in this build or for this object */
#define MICA_ERR_BUFFER_TOO_SMALL (-13)/**< the caller's buffer is smaller than the result (the needed count is returned) */
#define MICA_ERR_DEVICE (-14)          /**< a haptic device failed */
#define MICA_ERR_OUT_OF_MEMORY (-15)   /**< an allocation failed */
#define MICA_ERR_INTERNAL (-16)        /**< a bug in libmica: please report it with the message */
#define MICA_ERR_DIVERGED (-17)        /**< since 0.6: a replay did not reproduce its recording (mica_replay_step) */
#define MICA_ERR_TRUNCATED (-18)       /**< since 0.7: a recording ends before its end entry: it was cut short (mica_replay_step) */

/** Static text naming a status ("MICA_ERR_STALE_ID: ..."). Thread: any.
 *  @param status any ::mica_status (unknown values get a generic text).
 *  @return a static NUL-terminated string, never NULL. */
MICA_API const char* mica_status_string(mica_status status);
/** @} */

/** @name Ids
 *  A 64-bit id: bits 0-31 slot + 1, bits 32-55 generation, bits 56-63 kind. 0 is null.
 *  @{ */
/** Id of a body. */
typedef uint64_t mica_body_id;
/** Id of a linear projection constraint group. */
typedef uint64_t mica_lpc_id;
/** Id of a tool. */
typedef uint64_t mica_tool_id;
/** The null id: never names an object. */
#define MICA_NULL_ID 0u
/** @} */

/** @name World
 *  @{ */

/** An opaque simulation world. */
typedef struct mica_world mica_world;

/** Log levels for ::mica_log_fn. */
#define MICA_LOG_ERROR 0   /**< a call failed */
#define MICA_LOG_WARNING 1 /**< something worth knowing went wrong, the call succeeded */
#define MICA_LOG_INFO 2    /**< information */

/** Receives library messages on the thread that made the call. `message` is valid only during
 *  the call. Must not call back into the same world. */
typedef void (*mica_log_fn)(int32_t level, const char* message, void* user);

/** Velocity solvers. The default world (since 0.5) uses MICA_SOLVER_MICA with MICA_SWEEP_FACTORED,
 *  the haptic choice: contact and grasping in one iterative solve that converges in tens of
 *  iterations on stiff and fine meshes (docs/getting-started.md, "Choosing a solver"). */
#define MICA_SOLVER_DIRECT 0 /**< sparse Cholesky (CHOLMOD) of the projected system: exact, the reference; costly with many contacts (the default before 0.5) */
#define MICA_SOLVER_PCG 1    /**< projected conjugate gradient, block-Jacobi preconditioner */
#define MICA_SOLVER_MICA 2   /**< MICA: constraint anticipation, PGS on contacts, and the velocity sweep of `mica_sweep`; the default */

#define MICA_SWEEP_GAUSS_SEIDEL 0 /**< MICA's velocity sweep as in the paper: modified block Gauss-Seidel; cheap per iteration, slow to converge on stiff or fine meshes */
/** MICA with a factored anticipation: a sparse Cholesky factor of a recent system (the first
 *  step's after any change of time step, damping or constraint set), warped by node rotations,
 *  preconditions the velocity solve (conjugate gradients) and gives the contact rows their
 *  compliance; far fewer iterations on stiff or fine meshes. A solve that has used 100
 *  conjugate-gradient iterations (crushed elements turning fast under a tool) refactors the
 *  current system and ends in a few more; `refactor_interval` also refreshes the factor in the
 *  background (docs/solvers.md). The default. */
#define MICA_SWEEP_FACTORED 1

/** A task of the host's job system (since 0.7): libmica's function that runs the items
 *  [start_index, end_index) of a task, given with the task's `task_context`. Called by a worker
 *  of the host's job system (or by the thread that stepped, inside ::mica_enqueue_task_fn or
 *  ::mica_finish_task_fn). */
typedef void (*mica_task_fn)(int32_t start_index, int32_t end_index, void* task_context);
/** Hands a task to the host's job system (since 0.7): the host must call `task` on ranges that
 *  together cover the items [0, item_count) once each, each range at least `min_range` items long
 *  (but the last), on its workers, in any order, concurrently or not, then return a handle for
 *  ::mica_finish_task_fn. Or it may run every range before returning and return NULL (then
 *  finish_task is not called for it). Called on the thread in mica_step, and only there, one
 *  task of a world at a time (its finish_task comes before the next enqueue_task). `user` is
 *  mica_world_def.task_user. Must not throw or call into the world. */
typedef void* (*mica_enqueue_task_fn)(mica_task_fn task, int32_t item_count, int32_t min_range,
                                      void* task_context, void* user);
/** Waits for a task (since 0.7): returns once every range of the task `handle` names (the
 *  non-NULL return of ::mica_enqueue_task_fn) has returned, their writes visible to the caller.
 *  It may run ranges (the task's or others) on the calling thread meanwhile. Called on the thread
 *  in mica_step, once per non-NULL handle. Must not throw or call into the world. */
typedef void (*mica_finish_task_fn)(void* handle, void* user);

/** How to create a world: fill with mica_world_def_default(), then change fields. */
typedef struct mica_world_def {
  uint32_t struct_size;    /**< sizeof(mica_world_def) as the caller compiled it */
  uint32_t header_version; /**< MICA_VERSION_NUMBER the caller compiled with */
  double gravity[3];       /**< m/s^2; default (0, -9.81, 0) */
  int32_t solver;          /**< MICA_SOLVER_*; default MICA_SOLVER_MICA (0.2-0.4: MICA_SOLVER_DIRECT) */
  int32_t max_iterations;  /**< cap for iterative solvers; default 200 */
  double tolerance;        /**< relative residual for iterative solvers; default 1e-8 */
  /** 1: run every stage of the step even when the scene does not call for it (for
   *  measuring what the plan saves). Default 0: the plan holds only the effects present. */
  int32_t plan_all_stages;
  int32_t reserved0;       /**< zero */
  mica_log_fn log;         /**< optional log callback, NULL for none */
  void* log_user;          /**< passed to `log` */
  int32_t pgs_sweeps;      /**< MICA: PGS sweeps over the contacts per iteration; default 1 */
  int32_t paper_norm;      /**< MICA: 1 stops on the paper's 2-norm of the change of (v, lambda);
                                default 0: relative changes of v and of lambda, each below tolerance */
  double max_recovery_speed; /**< m/s: penetration is recovered at most this fast (for a tool, beyond its own approach); default 1 */
  int32_t body_contact;    /**< 1: bodies collide with each other and with static bodies; default 1 */
  int32_t reserved1;       /**< zero */
  double body_margin;      /**< m: contacts between bodies are made for gaps below this; default 0.001 */
  double body_friction;    /**< Coulomb coefficient between bodies, >= 0; default 0 */
  /* Since 0.3: */
  int32_t warm_start;      /**< MICA: 1 starts each step's iteration from the velocities extrapolated
                                from the last two steps (since 0.6; the last step's before) and from
                                its impulses (matched by persistent contact keys); 0 from zero; default 1 */
  int32_t reserved2;       /**< zero */
  double relaxation;       /**< MICA, Gauss-Seidel sweep: over-relaxation omega in (0, 2); default 1 (the paper) */
  /** Iterative solvers: > 0 stops the solve when the step has used this many milliseconds of
   *  wall-clock time; the step then completes with what the solver reached, mica_step returns
   *  MICA_WARN_NOT_CONVERGED and the statistics say out_of_time and the residual. Default 0: no budget;
   *  a budget above a day (86 400 000 ms, up to DBL_MAX) is no budget either. */
  double time_budget_ms;
  int32_t mica_sweep;      /**< MICA_SWEEP_*; default MICA_SWEEP_FACTORED (0.3-0.4: MICA_SWEEP_GAUSS_SEIDEL);
                                a caller whose header lacks the field (0.2) gets the default */
  /* Since 0.4 (threads was reserved3 in 0.3: a 0.3 def gets the default, 1): */
  /** Threads for the step (rotations, element assembly, a colour-ordered Gauss-Seidel sweep):
   *  1 (default) runs the serial code and the paper's sweep order; 0 every CPU the process may
   *  run on; n > 1 starts n - 1 workers owned by the world (they sleep between steps). See
   *  docs/performance.md before raising it: a haptic host also needs a core for the servo loop.
   *  A host with its own job system sets task_worker_count and enqueue_task instead (since 0.7). */
  int32_t threads;
  /** Co-rotational bodies: a step linearised at its start's rotations can gain energy when
   *  elements turn far within it. When a step gained more than this fraction of the bodies'
   *  energy beyond the work done on them, it is solved again by Newton iterations re-linearised at
   *  the new rotations, with a line search (docs/stability.md, K1). Default 1e-3.
   *  MICA_MODEL_NEO_HOOKEAN bodies (since 0.8): the Newton iterations of their step stop when the
   *  quadratic model a solve used is within this fraction of the body's energy of the true energy
   *  at its end; a step that misses in relinearise_max solves returns MICA_WARN_NOT_CONVERGED
   *  (docs/materials.md). */
  double relinearise_tolerance;
  int32_t relinearise_max; /**< at most this many solves per step for that; < 2 turns the check off; default 8 */
  /** MICA_SWEEP_FACTORED on co-rotational and (since 0.8) neo-Hookean bodies: every this many solves (one per
   *  step, more when a step is re-linearised) the factor is refreshed from the current system:
   *  copied, factored on a background thread (one per body, "mica-factor", made at its first
   *  refresh and kept until the world is destroyed) while the steps go on, and used from
   *  that many solves later (in lockstep: the step waits for a late factorization, so results do
   *  not depend on timing). Meant for bodies that keep turning far from the factor's shape; on the
   *  nidus benchmark (a tool moving in a soft blob), every 6 steps: 7.6 conjugate-gradient
   *  iterations per step instead of 10.1, but on a 2-core machine the median step is about the
   *  same (4.5-5.3 ms against 4.5-4.7) and its p95 less steady, as the second core's
   *  factorization slows the step; every 4, a factorization outlasts four steps and the adopting
   *  steps wait for it (docs/performance.md).
   *  Default 0: factor when the time step, damping or constraint set changes, and when a solve
   *  drags on. Costs a second core while it runs, and a second copy of the factor's memory (the
   *  factorization's double-precision values only while it runs). (With or
   *  without a refresh, so that a failed step can be undone, a factor replaced within a step
   *  is kept until the step ends and then reused as the next one's storage: one factor's
   *  memory more.) */
  int32_t refactor_interval;
  /* Since 0.7: the host's job system (docs/embedding.md, "Running on the host's job system"). */
  /** The workers of the host's job system that may run a step's loops at once, the thread in
   *  mica_step included: with enqueue_task set, it takes the place of `threads` (leave that at 1),
   *  >= 1 (1: the serial code, the callbacks are never called). Default 0, the only value
   *  accepted without enqueue_task. */
  int32_t task_worker_count;
  int32_t reserved4;       /**< zero */
  /** Optional, with finish_task (both or neither): the step's parallel loops (rotations, element
   *  assembly, the colour-ordered sweep) run on the host's workers instead of workers the world
   *  makes; with the same results, bit for bit, as `threads` = task_worker_count. Each loop is
   *  one task of at most task_worker_count - 1 items; an item stands for a worker, not a share of
   *  the work: any range joins the loop the thread in mica_step is running, taking its pieces in
   *  order until none is left (a range that starts late finds nothing to do), so the ranges may
   *  run in any order or on any thread without a deadlock. A loop waits in finish_task; a step
   *  has a few loops per body and solver iteration, so the host's enqueue and finish should cost
   *  microseconds. The world then starts no thread for a step, except the factor refresh's
   *  (`refactor_interval` > 0: a factorization outlasts several steps, which a host's job
   *  system expects of none of its tasks, so it stays on the body's own "mica-factor" thread;
   *  default 0: no such thread). Default NULL. */
  mica_enqueue_task_fn enqueue_task;
  mica_finish_task_fn finish_task; /**< waits for a task enqueue_task returned; default NULL */
  void* task_user;                 /**< passed to enqueue_task and finish_task */
} mica_world_def;

/** Fills `def` with defaults, writing only its first `struct_size` bytes, and records
 *  `header_version`. The entry point for foreign-function interfaces; C and C++ use
 *  mica_world_def_default(). Thread: any.
 *  @param def the def to fill.
 *  @param struct_size sizeof(mica_world_def) as the caller compiled it: from its size in 0.2.0 up
 *         to this library's.
 *  @param header_version MICA_VERSION_NUMBER the caller compiled with.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` is NULL); MICA_ERR_STRUCT_SIZE (`struct_size`
 *          outside the accepted sizes: nothing is written). */
MICA_API mica_status mica_world_def_init(mica_world_def* def, uint32_t struct_size,
                                         uint32_t header_version);

/** The default world definition for the header you compiled with. Thread: any.
 *  @return a def with `struct_size` = sizeof(mica_world_def), `header_version` =
 *          MICA_VERSION_NUMBER and every field at its default. Should the loaded library be older
 *          than this header, the def keeps only those two fields and mica_world_create() refuses
 *          it, naming its size. */
static inline mica_world_def mica_world_def_default(void) {
  mica_world_def def;
  /* Set before the call: should init refuse (a library older than this header), the def still
   * names its size and mica_world_create says what is wrong. */
  def.struct_size = (uint32_t)sizeof def;
  def.header_version = MICA_VERSION_NUMBER;
  mica_world_def_init(&def, (uint32_t)sizeof def, MICA_VERSION_NUMBER);
  return def;
}

/** Creates a world. On failure mica_world_last_error(NULL) says why. Thread: any; the world is then
 *  used by one thread at a time.
 *  @param def the definition (mica_world_def_default(), then changed); only its first
 *         `def->struct_size` bytes are read (see the conventions at the top).
 *  @param out_world receives the world; NULL on failure.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` or `out_world` is NULL); MICA_ERR_STRUCT_SIZE
 *          (`def->struct_size` is not one this library accepts); MICA_ERR_VERSION_MISMATCH
 *          (`def->header_version` has another major version; any 0.x header works);
 *          MICA_ERR_INVALID_ARGUMENT (a field outside its domain: the message names it);
 *          MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_world_create(const mica_world_def* def, mica_world** out_world);

/** Destroys a world and everything in it (its devices are stopped and closed first). Thread: the
 *  world's; no other thread may be in a call on it (mica_device_poll() included).
 *  @param world the world, or NULL (nothing happens). */
MICA_API void mica_world_destroy(mica_world* world);

/** The message of the last failed call on `world` ("mica_body_create: tet 41 has zero volume"), or,
 *  for world == NULL, of the last failed call on this thread that had no world (creation, the
 *  *_init functions). A call that returned MICA_WARN_BODIES_OVERLAP leaves its warning here too.
 *  Thread: the world's (NULL: any; each thread has its own).
 *  @param world a world, or NULL.
 *  @return the message, never NULL; empty when no call failed. Valid until the next call on that
 *          world (or, for NULL, on this thread). */
MICA_API const char* mica_world_last_error(const mica_world* world);

/** Sets gravity. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param gravity m/s^2, 3 values.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_INVALID_ARGUMENT (a value is not finite). */
MICA_API mica_status mica_world_set_gravity(mica_world* world, const double gravity[3]);
/** @} */

/** @name Bodies
 *  @{ */
#define MICA_MODEL_COROTATIONAL 0 /**< co-rotational linear elasticity: large rotations, small strains */
#define MICA_MODEL_LINEAR 1       /**< linear elasticity: constant stiffness, factored once */
/** Since 0.8: stable neo-Hookean hyperelasticity (Smith, de Goes, Kim 2018): large strains,
 *  nearly incompressible tissue (Poisson ratio up to 0.495 tested), inversion-safe; each step is
 *  solved by Newton iterations with a line search (mica_world_def.relinearise_tolerance and
 *  relinearise_max). See docs/materials.md for when to pick it and what it costs. */
#define MICA_MODEL_NEO_HOOKEAN 2
#define MICA_MASS_CONSISTENT 0    /**< consistent mass (rho V / 20)(1 + delta_ab) */
#define MICA_MASS_LUMPED 1        /**< lumped mass rho V / 4 per node */

/** How to create a body: material, model, mass, damping, placement. Fill with mica_body_def_default().
 *  Creation refuses a material that takes a tet's mass (kg) or stiffness (Young's modulus times the
 *  tet's size, N/m) outside [1e-100, 1e100] (E = 1e300 Pa, density = 1e-300 kg/m^3), naming the tet
 *  and the value. Within that range a body is accepted even where double precision cannot step it:
 *  tets whose mass is negligible against h^2 times their stiffness (a 1e-12 m box of tissue at
 *  h = 10 ms: a ratio of 1e21) make every step fail with MICA_ERR_NUMERICAL, the message naming the
 *  body ("the system matrix is not positive definite"), the world unchanged. */
typedef struct mica_body_def {
  uint32_t struct_size;  /**< sizeof(mica_body_def) as the caller compiled it */
  int32_t model;         /**< MICA_MODEL_*; default co-rotational */
  int32_t mass;          /**< MICA_MASS_*; default consistent */
  int32_t is_static;     /**< 1: never moves (an obstacle); default 0 */
  double youngs_modulus; /**< Pa, > 0; default 1e4 */
  double poisson_ratio;  /**< in [0, 0.5); default 0.3 */
  double density;        /**< kg/m^3, > 0; default 1000 */
  double rayleigh_alpha; /**< mass-proportional damping, 1/s, >= 0; default 0 */
  double rayleigh_beta;  /**< stiffness-proportional damping, s, >= 0; default 0 */
  double translation[3]; /**< m, added to every node at creation; default 0 */
  double velocity[3];    /**< m/s, initial velocity of every node; default 0 */
  double cutting_resistance; /**< N per m of blade edge the tissue bears before a blade parts it
                                  (mica_tool_def.blade), >= 0, every tet (since 0.8; per tet:
                                  mica_body_set_cutting_resistance()); default 200 */
} mica_body_def;

/** Fills `def` with defaults, writing only its first `struct_size` bytes. Thread: any.
 *  @param def the def to fill.
 *  @param struct_size sizeof(mica_body_def) as the caller compiled it.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` is NULL); MICA_ERR_STRUCT_SIZE (`struct_size`
 *          outside the accepted sizes: nothing is written). */
MICA_API mica_status mica_body_def_init(mica_body_def* def, uint32_t struct_size);

/** The default body definition. Thread: any.
 *  @return a def with `struct_size` = sizeof(mica_body_def) and every field at its default. */
static inline mica_body_def mica_body_def_default(void) {
  mica_body_def def;
  def.struct_size = (uint32_t)sizeof def; /* kept if init refuses: the create call names it */
  mica_body_def_init(&def, (uint32_t)sizeof def);
  return def;
}

/** Creates a body from caller arrays. The arrays are copied. The world's thread (the one thread
 *  using the world at a time).
 *  @param world the world.
 *  @param def the body's definition (mica_body_def_default(), then changed).
 *  @param nodes 3 * `node_count` coordinates (m).
 *  @param node_count number of nodes, >= 4.
 *  @param tets 4 * `tet_count` 0-based node indices, each tet with positive volume (det[X1-X0,
 *         X2-X0, X3-X0] > 0).
 *  @param tet_count number of tets, >= 1.
 *  @param out_body receives the body's id.
 *  @return MICA_OK; MICA_WARN_BODIES_OVERLAP (created, but deep inside another body: the two do not
 *          collide until they part; the message names them); or MICA_ERR_NULL_ARGUMENT (`world` or a
 *          required pointer is NULL);
 *          MICA_ERR_STRUCT_SIZE (`def->struct_size`); MICA_ERR_INVALID_ARGUMENT (a count, a def
 *          field or a coordinate out of its domain); MICA_ERR_OUT_OF_RANGE (a node index outside
 *          0..node_count-1); MICA_ERR_BAD_MESH (a degenerate or inverted tet);
 *          MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_body_create(mica_world* world, const mica_body_def* def,
                                      const double* nodes, int32_t node_count,
                                      const int32_t* tets, int32_t tet_count,
                                      mica_body_id* out_body);

/** Creates a body from a mesh file: Gmsh .msh (2.2 or 4.1 ASCII) or a TetGen .node/.ele pair
 *  (either name). Only regular files of at most 256 MiB are read. The world's thread (the one
 *  thread using the world at a time).
 *  @param world the world.
 *  @param def the body's definition.
 *  @param path the file (UTF-8, as fopen takes it).
 *  @param out_body receives the body's id.
 *  @return MICA_OK; MICA_WARN_BODIES_OVERLAP (created, but deep inside another body: the two do not
 *          collide until they part; the message names them); or MICA_ERR_NULL_ARGUMENT (`world` or a
 *          required pointer is NULL);
 *          MICA_ERR_STRUCT_SIZE (`def->struct_size`); MICA_ERR_INVALID_ARGUMENT (a def field);
 *          MICA_ERR_UNSUPPORTED (an extension other than .msh, .node, .ele); MICA_ERR_IO (the file
 *          cannot be read, or is a FIFO, a device such as /dev/zero, a directory or larger than
 *          256 MiB); MICA_ERR_PARSE (the file is malformed: the message gives the line);
 *          MICA_ERR_BAD_MESH (a degenerate or inverted tet, a repeated tet, a face shared by three
 *          tets, or no boundary surface, as for mica_body_create); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_body_create_from_file(mica_world* world, const mica_body_def* def,
                                                const char* path, mica_body_id* out_body);

/** Creates a box [lo, hi] meshed as cells[0] x cells[1] x cells[2] cubes, each cut into
 *  `tets_per_cell` tetrahedra. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param def the body's definition.
 *  @param lo the low corner (m).
 *  @param hi the high corner (m), > lo on every axis.
 *  @param cells cubes along x, y and z, each >= 1.
 *  @param tets_per_cell 5 or 6.
 *  @param out_body receives the body's id.
 *  @return MICA_OK; MICA_WARN_BODIES_OVERLAP (created, but deep inside another body: the two do not
 *          collide until they part; the message names them); or MICA_ERR_NULL_ARGUMENT (`world` or a
 *          required pointer is NULL);
 *          MICA_ERR_STRUCT_SIZE (`def->struct_size`); MICA_ERR_INVALID_ARGUMENT (corners, cell
 *          counts, tets_per_cell or a def field); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_body_create_box(mica_world* world, const mica_body_def* def,
                                          const double lo[3], const double hi[3],
                                          const int32_t cells[3], int32_t tets_per_cell,
                                          mica_body_id* out_body);

/** Destroys a body and the constraints on it. The world's thread (the one thread using the world at
 *  a time).
 *  @param world the world.
 *  @param body the body.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed); MICA_ERR_WRONG_STATE
 *          (a device drives a grasp on the body, mica_device_def.lpc: destroy the device first;
 *          since 0.6). */
MICA_API mica_status mica_body_destroy(mica_world* world, mica_body_id body);

/** Counts of a body's nodes, tets and surface triangles. The world's thread (the one thread using
 *  the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param node_count receives the node count, or NULL.
 *  @param tet_count receives the tet count, or NULL.
 *  @param triangle_count receives the surface triangle count, or NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed). */
MICA_API mica_status mica_body_get_counts(const mica_world* world, mica_body_id body,
                                          int32_t* node_count, int32_t* tet_count,
                                          int32_t* triangle_count);

/** Current positions (m), 3 doubles per node, copied into the caller's buffer. With out == NULL
 *  only *out_count is written (the size query). The world's thread (the one thread using the world
 *  at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_positions(const mica_world* world, mica_body_id body,
                                             double* out, int32_t capacity, int32_t* out_count);
/** Current velocities (m/s), 3 doubles per node; as mica_body_get_positions(). The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_velocities(const mica_world* world, mica_body_id body,
                                              double* out, int32_t capacity, int32_t* out_count);
/** Rest positions (m), 3 doubles per node; as mica_body_get_positions(). The world's thread (the
 *  one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_rest_positions(const mica_world* world, mica_body_id body,
                                                  double* out, int32_t capacity,
                                                  int32_t* out_count);
/** Surface triangles, 3 node indices each, counter-clockwise seen from outside; as
 *  mica_body_get_positions(). The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in triangles (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_surface(const mica_world* world, mica_body_id body,
                                           int32_t* out, int32_t capacity, int32_t* out_count);

/** Zero-copy view of the current positions: 3 * node_count doubles owned by the world, valid until
 *  the next mica_step() or the destruction of the body or the world. The world's thread (the one
 *  thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out receives the pointer.
 *  @param out_node_count receives the node count, or NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed). */
MICA_API mica_status mica_body_positions_view(const mica_world* world, mica_body_id body,
                                              const double** out, int32_t* out_node_count);

/** Sets persistent external forces (N) on nodes. They add to gravity until changed; zero forces
 *  remove them. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param nodes `count` node indices (may be NULL when count is 0).
 *  @param forces 3 * `count` values, N (may be NULL when count is 0).
 *  @param count number of nodes, >= 0.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`count` < 0 or a force not finite); MICA_ERR_OUT_OF_RANGE (a
 *          node index outside the body). */
MICA_API mica_status mica_body_set_node_forces(mica_world* world, mica_body_id body,
                                               const int32_t* nodes, const double* forces,
                                               int32_t count);

/** Nodes inside the axis-aligned box [lo, hi], in rest or current positions. Buffer protocol as
 *  mica_body_get_positions(). The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param lo the low corner (m).
 *  @param hi the high corner (m).
 *  @param use_rest 1: rest positions, 0: current positions.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (corners not finite, `use_rest` not 0 or 1, `capacity` < 0);
 *          MICA_ERR_BUFFER_TOO_SMALL (nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_select_nodes_in_box(const mica_world* world, mica_body_id body,
                                                   const double lo[3], const double hi[3],
                                                   int32_t use_rest, int32_t* out,
                                                   int32_t capacity, int32_t* out_count);
/** Nodes with (p - point) . normal <= tolerance, i.e. on the side the normal points away from.
 *  Buffer protocol as mica_body_get_positions(). The world's thread (the one thread using the world
 *  at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param point a point of the plane (m).
 *  @param normal the plane's normal (any non-zero length).
 *  @param tolerance m, how far past the plane a node still counts.
 *  @param use_rest 1: rest positions, 0: current positions.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (a value not finite, a zero normal, `use_rest` not 0 or 1,
 *          `capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (nothing copied, `*out_count` = the count
 *          needed). */
MICA_API mica_status mica_body_select_nodes_by_plane(const mica_world* world, mica_body_id body,
                                                     const double point[3], const double normal[3],
                                                     double tolerance, int32_t use_rest,
                                                     int32_t* out, int32_t capacity,
                                                     int32_t* out_count);

/** Total kinetic, elastic and gravitational potential energy of a body (J). The world's thread (the
 *  one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param kinetic receives the kinetic energy, or NULL.
 *  @param elastic receives the elastic energy, or NULL.
 *  @param potential receives the gravitational potential energy, or NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed). */
MICA_API mica_status mica_body_get_energy(const mica_world* world, mica_body_id body,
                                          double* kinetic, double* elastic, double* potential);

/* Since 0.6: setting node state. */
/** Sets the current positions (m) of every node of a body, 3 doubles per node (a checker's or a
 *  host's own state; a body placed anew). What was derived from the old positions goes with them:
 *  the rotations kept for the next step, the collision tree (refitted at once), and the warm-start
 *  impulses of the body's contacts. Velocities are kept (mica_body_set_velocities() sets them).
 *  A static body may be moved too: it stays where it is put. The world's thread (the one thread
 *  using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param xyz 3 * `node_count` coordinates, m, finite.
 *  @param node_count the body's node count (mica_body_get_counts()).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `xyz` is NULL); MICA_ERR_STALE_ID
 *          (`body` is null, of another kind or destroyed); MICA_ERR_INVALID_ARGUMENT (`node_count`
 *          is not the body's node count, a value is not finite: the message names the node). On an
 *          error the world is unchanged. */
MICA_API mica_status mica_body_set_positions(mica_world* world, mica_body_id body, const double* xyz,
                                             int32_t node_count);
/** Sets the current velocities (m/s) of every node of a dynamic body, 3 doubles per node; the next
 *  step starts from them. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param xyz 3 * `node_count` values, m/s, finite.
 *  @param node_count the body's node count.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `xyz` is NULL); MICA_ERR_STALE_ID
 *          (`body` is null, of another kind or destroyed); MICA_ERR_INVALID_ARGUMENT (`node_count`
 *          is not the body's node count, a value is not finite); MICA_ERR_WRONG_STATE (the body is
 *          static). On an error the world is unchanged. */
MICA_API mica_status mica_body_set_velocities(mica_world* world, mica_body_id body, const double* xyz,
                                              int32_t node_count);
/* Since 0.6: tissue regions (a material per tet), the mesh and its fields. */

/** The tets, 4 node indices each (0-based, positive rest volume as at creation); as
 *  mica_body_get_positions(). The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in tets (not in values). @param out_count receives the tet count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_tets(const mica_world* world, mica_body_id body,
                                        int32_t* out, int32_t capacity, int32_t* out_count);

/** The region of each tet, 1 value per tet in the order of mica_body_get_tets(): for a Gmsh .msh
 *  file the tet's physical tag (2.2: the element's first tag; 4.1: the first physical tag of its
 *  volume in $Entities), for a TetGen .ele the first tet attribute (tetgen -A) when every tet's
 *  is an integer, else 0; 0 for a tet without one and for bodies made from arrays or boxes. Map
 *  regions to materials with mica_body_set_materials(). Buffer protocol as
 *  mica_body_get_positions(). The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in tets. @param out_count receives the tet count (may be NULL when `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_tet_regions(const mica_world* world, mica_body_id body,
                                               int32_t* out, int32_t capacity,
                                               int32_t* out_count);

/** Sets the material of every tet (a stiff nodule in soft tissue): Young's modulus, Poisson
 *  ratio and density per tet, in the order of mica_body_get_tets(). The body's model is rebuilt:
 *  element stiffness, mass (so gravity and node masses) and Rayleigh damping (alpha M + beta K,
 *  with the body's alpha and beta) follow each tet's material, and the solver's factors of the
 *  body are dropped (the next step factors anew). Positions, velocities, loads and constraints
 *  stay. Cost: like creating the body; call it after creation, not per step. The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param youngs_modulus `tet_count` values, Pa, each finite and > 0; NULL keeps every tet's.
 *  @param poisson_ratio `tet_count` values, each in [0, 0.5); NULL keeps every tet's.
 *  @param density `tet_count` values, kg/m^3, each finite and > 0; NULL keeps every tet's.
 *  @param tet_count the body's tet count (mica_body_get_counts()).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_STALE_ID (`body` is
 *          null, of another kind or destroyed); MICA_ERR_INVALID_ARGUMENT (`tet_count` is not the
 *          body's tet count, or a value out of its domain: the message names the tet and the
 *          property); MICA_ERR_BAD_MESH (a value so large that a tet's stiffness or mass
 *          overflows double precision); MICA_ERR_OUT_OF_MEMORY. On any error nothing changes. */
MICA_API mica_status mica_body_set_materials(mica_world* world, mica_body_id body,
                                             const double* youngs_modulus,
                                             const double* poisson_ratio, const double* density,
                                             int32_t tet_count);

/** Resection: removes tets from a body, with everything that depends on them, in one call.
 *  The kept tets keep their order (tet indices above a removed one move down). Nodes no kept tet
 *  holds are removed and the others renumbered in their order: node indices change, so re-read
 *  counts, tets, surface and positions after a removal (mica_body_get_topology_version() tells
 *  that one happened). What follows:
 *  - the model (stiffness and mass of the kept tets with their materials and regions, the
 *    surface, the solver's factors, rebuilt as mica_body_set_materials() does);
 *  - positions, velocities and node forces of the kept nodes;
 *  - constraints and grabs: removed nodes leave their group, kept ones follow their new indices
 *    (a grab's handle keeps their offsets); a group left with no node is destroyed and its id
 *    becomes stale;
 *  - contacts: the warm starts of the body's contacts are dropped, and the last step's contacts
 *    readout (mica_world_get_contacts() and what reads contacts) is cleared for the
 *    whole world, its indices being of the old numbering (the statistics stay);
 *  - saved states: a state saved before the removal no longer fits the world (its shape
 *    differs); a recording records the removal and replays it;
 *  - render meshes embedded in the body (mica_embedding_create(), since 0.7): a vertex whose tet
 *    is kept keeps its weights and follows the tet's new nodes, to the bit where it was; a vertex
 *    whose tet is removed is bound again as at creation (inside another tet, projected within the
 *    embedding's radius, or unbound: mica_embedding_get_kinds() and _get_counts() say which).
 *  A part of the body left without a fixed node moves freely (it falls under gravity). The
 *  world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body, static or dynamic.
 *  @param tets `count` distinct tet indices in 0..tet_count-1 (NULL when `count` is 0; count 0
 *         changes nothing).
 *  @param count the number of tets to remove, fewer than the body has.
 *  @param out_removed_mass receives the removed tets' mass, kg (the sum of density times rest
 *         volume); may be NULL.
 *  @return MICA_OK; MICA_WARN_UNBOUND_VERTICES (removed, but vertices of an embedded render mesh
 *          whose tets went are now unbound: the message says how many, and the update leaves
 *          their positions as they were); or MICA_ERR_NULL_ARGUMENT (`world` NULL, or `tets` NULL
 *          with `count` > 0); MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_OUT_OF_RANGE (a tet index outside the body's tets: the message names it and
 *          its position); MICA_ERR_INVALID_ARGUMENT (`count` < 0, a tet listed twice, or every
 *          tet: destroy the body instead); MICA_ERR_WRONG_STATE (the removal would empty a grasp a
 *          device drives); MICA_ERR_OUT_OF_MEMORY. On any error nothing changes. */
MICA_API mica_status mica_body_remove_tets(mica_world* world, mica_body_id body, const int32_t* tets,
                                           int32_t count, double* out_removed_mass);

/** Incision (since 0.8): separates a body along a cut surface, given as triangles where the body
 *  is now (world space; a blade's sweep between two poses is two triangles). A face shared by two
 *  tets is cut when the segment between the two tets' centroids crosses a triangle, except that a
 *  cut frees no piece of fewer than 12 tets (since 0.8.3; 8 before 0.9: such a piece stays joined across one of
 *  its faces; remove its tets to take it out); the nodes of the cut faces are then duplicated so
 *  that the tets on either side no longer share them (a node
 *  at the cut's edge, whose tets stay joined around it, is kept whole: the cut stops there). No tet
 *  is added, removed or changed in shape: the mass and every tet's quality stay, and the cut
 *  follows the element faces (within one element of the triangles; docs/cutting.md). Node copies
 *  are numbered after the body's nodes; tet indices stay, and each tet keeps its region and
 *  material. What follows is as for mica_body_remove_tets(), and: a held node's copies are all
 *  held by its groups (a grab's handle holds each copy at the node's offset); each copy starts at
 *  its node's position and velocity, with its share of the node's force. A cut that separates no
 *  node changes nothing (the topology version stays). Recorded and replayed. The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body, static or dynamic.
 *  @param triangles 9 * `triangle_count` coordinates, m: each triangle's three corners (NULL when
 *         `triangle_count` is 0).
 *  @param triangle_count the number of triangles, >= 0.
 *  @param out_faces_cut receives the number of faces cut (those the triangles crossed, less those
 *         that stayed joined so as to free no sliver); may be NULL.
 *  @param out_nodes_added receives the number of node copies made; may be NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` NULL, or `triangles` NULL with a count
 *          above 0); MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`triangle_count` < 0, a corner not finite: the message names
 *          the triangle); MICA_ERR_OUT_OF_MEMORY. On any error nothing changes.
 *          MICA_WARN_UNBOUND_VERTICES: the cut was made, and a render mesh embedded in the body
 *          (mica_embedding_create) was left with vertices it could not bind again (the message
 *          says how many). */
MICA_API mica_status mica_body_cut(mica_world* world, mica_body_id body, const double* triangles,
                                   int32_t triangle_count, int32_t* out_faces_cut, int32_t* out_nodes_added);

/** Sets each tet's cutting resistance (since 0.8): the force per metre of blade edge the tissue
 *  bears before a blade (mica_tool_def.blade) parts it, N/m. The world's thread (the one thread
 *  using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param per_tet `tet_count` values, finite and >= 0 (0: any press cuts).
 *  @param tet_count the body's tet count.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `per_tet` NULL); MICA_ERR_STALE_ID
 *          (`body`); MICA_ERR_INVALID_ARGUMENT (`tet_count` not the body's, a value negative or
 *          not finite: the message names the tet). On any error nothing changes. */
MICA_API mica_status mica_body_set_cutting_resistance(mica_world* world, mica_body_id body, const double* per_tet,
                                                      int32_t tet_count);

/** How many times the body's tets have changed (mica_body_remove_tets(), mica_body_cut(), a
 *  blade's cut): 0 at creation. A host
 *  that keeps node or tet indices of a body re-reads them when this changes. The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out receives the version.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `out` is NULL); MICA_ERR_STALE_ID
 *          (`body` is null, of another kind or destroyed). */
MICA_API mica_status mica_body_get_topology_version(const mica_world* world, mica_body_id body, uint64_t* out);

/** Mass of each node (kg), 1 value per node: the row sums of the body's mass matrix, the mass
 *  gravity pulls on. For linear tets each tet gives rho V / 4 to each of its nodes with either
 *  MICA_MASS_CONSISTENT or MICA_MASS_LUMPED, so the sum is the body's mass (density times
 *  volume, per tet). Buffer protocol as mica_body_get_positions(). The world's thread (the one
 *  thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes. @param out_count receives the node count (may be NULL when `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_body_get_node_masses(const mica_world* world, mica_body_id body,
                                               double* out, int32_t capacity, int32_t* out_count);

/** Strain of each tet at the current positions (dimensionless), 6 values per tet: xx, yy, zz,
 *  yz, xz, xy, with tensor shear components (half the engineering shear). It is the strain the
 *  model uses: co-rotational bodies eps = sym(R^T F) - I, with F the tet's deformation gradient
 *  and R its rotation, expressed in the tet's rest axes (a rigid rotation of the body gives 0);
 *  MICA_MODEL_LINEAR bodies the small strain sym(F) - I; MICA_MODEL_NEO_HOOKEAN bodies (since
 *  0.8) the Green strain (F^T F - I) / 2. Constant over each (linear) tet.
 *  Buffer protocol as mica_body_get_positions(). The world's thread (the one thread using the
 *  world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in tets (not in values). @param out_count receives the tet count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_body_get_strains(const mica_world* world, mica_body_id body,
                                           double* out, int32_t capacity, int32_t* out_count);

/** Von Mises stress of each tet at the current positions (Pa), 1 value per tet:
 *  sqrt(3/2 s:s), s the deviatoric part of the stress 2 mu eps + lambda tr(eps) I of the tet's
 *  own material and its strain as mica_body_get_strains() gives it; for MICA_MODEL_NEO_HOOKEAN
 *  bodies (since 0.8) s is the deviatoric part of the tet's Cauchy stress. Buffer protocol as
 *  mica_body_get_positions(). The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in tets. @param out_count receives the tet count (may be NULL when `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_body_get_von_mises(const mica_world* world, mica_body_id body,
                                             double* out, int32_t capacity, int32_t* out_count);
/** @} */

/** @name Linear projection constraints (LPC)
 *  Per node a projector S = I - sum of constrained directions; the constrained velocity
 *  components are prescribed: (I - S) v = (I - S) velocity.
 *  @{ */
#define MICA_LPC_FIXED 0    /**< all three directions constrained: S = 0 */
#define MICA_LPC_PLANE 1    /**< slide on a plane with normal direction[0]: S = I - p p^T */
#define MICA_LPC_LINE 2     /**< move only along direction[0]: S = d d^T */
#define MICA_LPC_TWO_DIRS 3 /**< directions direction[0] and direction[1] constrained: S = I - pp^T - qq^T */

/** A projection constraint: its kind, directions and prescribed velocity. Fill with mica_lpc_def_default(). */
typedef struct mica_lpc_def {
  uint32_t struct_size;  /**< sizeof(mica_lpc_def) as the caller compiled it */
  int32_t kind;          /**< MICA_LPC_*; default MICA_LPC_FIXED */
  double direction[2][3];/**< unit vectors as the kind needs them (normalised by the library) */
  double velocity[3];    /**< m/s, prescribed velocity of the constrained components; default 0 */
} mica_lpc_def;

/** Fills `def` with defaults, writing only its first `struct_size` bytes. Thread: any.
 *  @param def the def to fill.
 *  @param struct_size sizeof(mica_lpc_def) as the caller compiled it.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` is NULL); MICA_ERR_STRUCT_SIZE (`struct_size`
 *          outside the accepted sizes: nothing is written). */
MICA_API mica_status mica_lpc_def_init(mica_lpc_def* def, uint32_t struct_size);

/** The default constraint definition (fixed, zero velocity). Thread: any.
 *  @return a def with `struct_size` = sizeof(mica_lpc_def) and every field at its default. */
static inline mica_lpc_def mica_lpc_def_default(void) {
  mica_lpc_def def;
  def.struct_size = (uint32_t)sizeof def; /* kept if init refuses: the create call names it */
  mica_lpc_def_init(&def, (uint32_t)sizeof def);
  return def;
}

/** Adds a projection constraint on nodes of a body. Where constraints overlap on a node, the
 *  constrained directions add up and the later constraint's velocity wins on its directions. The
 *  world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param nodes `count` node indices.
 *  @param count number of nodes, >= 1.
 *  @param def the constraint (mica_lpc_def_default(), then changed).
 *  @param out_lpc receives the constraint's id.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed); MICA_ERR_STRUCT_SIZE
 *          (`def->struct_size`); MICA_ERR_INVALID_ARGUMENT (`count` < 1, an unknown kind, a zero or
 *          parallel direction, a velocity not finite); MICA_ERR_OUT_OF_RANGE (a node index outside
 *          the body). */
MICA_API mica_status mica_add_lpc(mica_world* world, mica_body_id body, const int32_t* nodes,
                                  int32_t count, const mica_lpc_def* def, mica_lpc_id* out_lpc);

/** Removes a constraint. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param lpc the constraint.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`lpc` is null, of another kind or destroyed); MICA_ERR_WRONG_STATE
 *          (a device drives the grasp, mica_device_def.lpc: destroy the device first; since 0.6). */
MICA_API mica_status mica_lpc_remove(mica_world* world, mica_lpc_id lpc);

/** Changes the prescribed velocity of a constraint's constrained components (and drops any targets
 *  or handle it had). The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param lpc the constraint.
 *  @param velocity m/s, 3 values.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`lpc` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (a value not finite). */
MICA_API mica_status mica_lpc_set_velocity(mica_world* world, mica_lpc_id lpc, const double velocity[3]);

/** Gives each node of the constraint a target position: every step the constrained components move
 *  so that the node reaches its target in that step. The world's thread (the one thread using the
 *  world at a time).
 *  @param world the world.
 *  @param lpc the constraint.
 *  @param targets 3 * `count` values, m.
 *  @param count the constraint's node count.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`lpc` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`count` is not the constraint's node count, a value not
 *          finite). */
MICA_API mica_status mica_lpc_set_targets(mica_world* world, mica_lpc_id lpc, const double* targets,
                                          int32_t count);

/** Picking: holds every node of `body` within `radius` of `center` (current positions) on a handle,
 *  fully constrained (S = 0). The handle starts at `center` and moves with
 *  mica_lpc_set_handle_pose(); given a tool, it follows that tool's pose instead, like forceps.
 *  Release with mica_lpc_remove(). The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param body the body.
 *  @param center m.
 *  @param radius m, > 0.
 *  @param tool a tool whose pose the handle follows, or MICA_NULL_ID for a hand-held handle.
 *  @param out_lpc receives the constraint's id.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body`, or a non-null `tool`, is stale); MICA_ERR_INVALID_ARGUMENT
 *          (centre or radius not finite, radius <= 0, no node within the radius). */
MICA_API mica_status mica_lpc_grab(mica_world* world, mica_body_id body, const double center[3], double radius,
                                   mica_tool_id tool, mica_lpc_id* out_lpc);

/** Moves a grab's handle. The held nodes keep their offsets in the handle frame. The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world.
 *  @param lpc the constraint (from mica_lpc_grab() without a tool).
 *  @param position m.
 *  @param orientation unit quaternion (w, x, y, z).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`lpc` is null, of another kind or destroyed); MICA_ERR_WRONG_STATE
 *          (the constraint has no handle, or its handle follows a tool or, since 0.6, a device:
 *          mica_device_def.lpc); MICA_ERR_INVALID_ARGUMENT
 *          (a value not finite, a zero quaternion). */
MICA_API mica_status mica_lpc_set_handle_pose(mica_world* world, mica_lpc_id lpc, const double position[3],
                                              const double orientation[4]);

/** The nodes a constraint holds; buffer protocol as mica_body_get_positions(). The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param lpc the constraint.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity the buffer's
 *         size in nodes (not in values). @param out_count receives the count (may be NULL when
 *         `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`lpc` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below
 *          the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_lpc_get_nodes(const mica_world* world, mica_lpc_id lpc, int32_t* out, int32_t capacity,
                                        int32_t* out_count);

/** Reaction force of a constraint group in the last step: the force on whoever holds the constraint
 *  (the user's hand in a grasp). Lifting a grasped region up against gravity gives a downward
 *  force; a device driving the grasp (mica_device_def.lpc) renders this force. A node held by several groups is counted once: each group C_g gets the share
 *  C_g (sum of the node's groups' C)^+ of its reaction (two groups fixing it get half each), so
 *  the groups' reactions add up to what holds the body. The world's thread (the one thread
 *  using the world at a time).
 *  @param world the world (not changed).
 *  @param lpc the constraint.
 *  @param out_force receives the force, N.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`lpc` is null, of another kind or destroyed). */
MICA_API mica_status mica_lpc_get_reaction(const mica_world* world, mica_lpc_id lpc, double out_force[3]);
/** @} */

/** @name Tools
 *  Kinematic rigid tools: the host sets their pose; bodies cannot push them, they feel the
 *  force of the contact.
 *  @{ */
#define MICA_TOOL_SPHERE 0  /**< a sphere of `radius` around the tool origin */
#define MICA_TOOL_PLANE 1   /**< a half-space: bodies stay on the side `normal` points to */
#define MICA_TOOL_CAPSULE 2 /**< the segment from -half_length to +half_length along local z, inflated by `radius` */
#define MICA_TOOL_BOX 3     /**< a box of `half_extents` centred on the tool origin, its edges and corners rounded (inside it) by a tenth of its smallest half extent, at most 1 mm */
#define MICA_TOOL_HULL 4    /**< the convex hull of `hull_points` (4 to 64 points, tool frame), rounded inside it as a box (by a tenth of the distance from its centre to its nearest face, at most 1 mm) */

/** A kinematic tool: shape, size, initial pose, contact margin. Fill with mica_tool_def_default(). */
typedef struct mica_tool_def {
  uint32_t struct_size;  /**< sizeof(mica_tool_def) as the caller compiled it */
  int32_t shape;         /**< MICA_TOOL_*; default sphere */
  double radius;         /**< m, sphere; default 0.01 */
  double normal[3];      /**< plane normal in the tool frame; default (0, 0, 1) */
  double position[3];    /**< m, initial tool origin; default 0 */
  double orientation[4]; /**< initial unit quaternion (w, x, y, z); default identity */
  double margin;         /**< m: contacts are made for gaps below this; default 0.001 */
  double friction;       /**< Coulomb coefficient between tool and tissue, >= 0; default 0 */
  double half_length;    /**< m, capsule; default 0.01 */
  double half_extents[3];/**< m, box; default 0.01 each */
  const double* hull_points; /**< m, hull: 3 * hull_point_count coordinates in the tool frame (copied) */
  int32_t hull_point_count;  /**< hull: number of points, 4 to 64 */
  int32_t reserved0;     /**< zero */
  int32_t blade;         /**< 1: a capsule that is a blade, as a scalpel's: its segment (local z)
                              the edge, its local x-z plane the blade's plane. Where it presses a
                              body along its local x harder than the tissue's cutting resistance
                              times the length of edge in the tissue, the body is cut, after the
                              step, in the blade's plane from the edge to about one element ahead
                              (docs/cutting.md); since 0.8; default 0 */
  int32_t reserved1;     /**< zero */
} mica_tool_def;

/** Fills `def` with defaults, writing only its first `struct_size` bytes. Thread: any.
 *  @param def the def to fill.
 *  @param struct_size sizeof(mica_tool_def) as the caller compiled it.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` is NULL); MICA_ERR_STRUCT_SIZE (`struct_size`
 *          outside the accepted sizes: nothing is written). */
MICA_API mica_status mica_tool_def_init(mica_tool_def* def, uint32_t struct_size);

/** The default tool definition (a 1 cm sphere at the origin). Thread: any.
 *  @return a def with `struct_size` = sizeof(mica_tool_def) and every field at its default. */
static inline mica_tool_def mica_tool_def_default(void) {
  mica_tool_def def;
  def.struct_size = (uint32_t)sizeof def; /* kept if init refuses: the create call names it */
  mica_tool_def_init(&def, (uint32_t)sizeof def);
  return def;
}

/** Creates a tool. Every solver handles its contacts (MICA; DIRECT and PCG through the Delassus
 *  matrix). Create it at its start pose (`def->position`): mica_tool_set_pose() sweeps a tool from
 *  its last pose, so a tool created inside a body and then set elsewhere drags the tissue on its
 *  way; such a creation logs a warning. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param def the tool (mica_tool_def_default(), then changed).
 *  @param out_tool receives the tool's id.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL) (also
 *          `def->hull_points` for a hull); MICA_ERR_STRUCT_SIZE (`def->struct_size`);
 *          MICA_ERR_INVALID_ARGUMENT (an unknown shape, a size, pose, margin or friction out of its
 *          domain, 4..64 hull points). */
MICA_API mica_status mica_tool_create(mica_world* world, const mica_tool_def* def, mica_tool_id* out_tool);
/** Destroys a tool. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param tool the tool.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`tool` is null, of another kind or destroyed); MICA_ERR_WRONG_STATE
 *          (a device drives the tool: destroy it first). */
MICA_API mica_status mica_tool_destroy(mica_world* world, mica_tool_id tool);
/** Moves a tool for the next step, which sweeps it from its last pose to this one (continuous
 *  contact: what lies on the way is pushed, as a hand would push it; a fast move does not pass
 *  through thin tissue). To put a tool somewhere without a sweep (a start pose, a jump of the
 *  scene), use mica_tool_teleport(). The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param tool the tool.
 *  @param position m.
 *  @param orientation unit quaternion (w, x, y, z).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`tool` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (a value not finite, a zero quaternion). */
MICA_API mica_status mica_tool_set_pose(mica_world* world, mica_tool_id tool, const double position[3],
                                        const double orientation[4]);
/** Puts a tool at a pose without a sweep (since 0.7): the next step starts it there, so nothing
 *  between its last pose and this one is pushed, and the warm starts of its contacts are forgotten.
 *  For a tool's start pose (or create it there: mica_tool_def.position), a scene's jump, a reset.
 *  Recorded and replayed. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param tool the tool.
 *  @param position m.
 *  @param orientation unit quaternion (w, x, y, z).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`tool` is null, of another kind or destroyed);
 *          MICA_ERR_INVALID_ARGUMENT (a value not finite, a zero quaternion). */
MICA_API mica_status mica_tool_teleport(mica_world* world, mica_tool_id tool, const double position[3],
                                        const double orientation[4]);
/** The tool's current pose. A tool driven by a device takes the device's pose at each step. The
 *  world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param tool the tool.
 *  @param out_position receives the position (m), or NULL.
 *  @param out_orientation receives the unit quaternion (w, x, y, z), or NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`tool` is null, of another kind or destroyed). */
MICA_API mica_status mica_tool_get_pose(const mica_world* world, mica_tool_id tool, double out_position[3],
                                        double out_orientation[4]);
/** Force and torque the bodies put on the tool in the last step, and its active contacts: those
 *  whose normal impulse was positive (pressing). mica_world_get_contacts() lists every contact
 *  the step made with the tool, pressing or not (features closer than the margin). The
 *  world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param tool the tool.
 *  @param out_force receives the force (N), or NULL.
 *  @param out_torque receives the torque about the tool origin (N m), or NULL.
 *  @param out_contacts receives the number of active (pressing) contacts, or NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`tool` is null, of another kind or destroyed). */
MICA_API mica_status mica_tool_get_force(const mica_world* world, mica_tool_id tool, double out_force[3],
                                         double out_torque[3], int32_t* out_contacts);
/** @} */

/** @name Stepping
 *  @{ */

/** Advances the world by one implicit step. The world's thread (the one thread using the world at a
 *  time).
 *  @param world the world.
 *  @param dt the step, s: 1e-9 <= dt <= 1 (a shorter step would take forces, impulse / dt, out of
 *         double precision).
 *  @return MICA_OK; MICA_WARN_NOT_CONVERGED (an iterative solver stopped at its cap or its time
 *          budget: the step is kept, mica_world_get_stats() says how far it got); or
 *          MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_INVALID_ARGUMENT (`dt` out of range);
 *          MICA_ERR_NUMERICAL (the result - positions, velocities, tool forces, constraint
 *          reactions - was not finite); MICA_ERR_OUT_OF_MEMORY. A step that fails is undone whole:
 *          tool poses taken from devices and the solvers' schedules included. */
MICA_API mica_status mica_step(mica_world* world, double dt);
/** @} */

/** @name State and contacts (since 0.6)
 *  Saving a world's dynamic state to restore it later (a session's checkpoint, two solvers from
 *  one state, a bug report), and reading the contacts of the last step.
 *  @{ */

/** The size in bytes mica_world_save_state() needs now. The size changes as the world steps (the
 *  contacts and warm-start impulses, the lagged factors the solver keeps): ask right before saving.
 *  The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param out_bytes receives the size.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `out_bytes` is NULL); MICA_ERR_WRONG_STATE
 *          (a device's servo loop runs: stop it first); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_world_state_size(const mica_world* world, size_t* out_bytes);

/** Saves the world's dynamic state into the caller's buffer: node positions and velocities, node
 *  forces, the warm-start impulses and the last step's contacts, the solver's lagged factors (the
 *  systems they were made from), tool poses, velocities and forces, constraint targets, velocities
 *  and handle poses, each device's force filter (moving average) and rate limit, the step counter
 *  and statistics. Restoring it into this world (or one built the same way) and stepping repeats
 *  the original steps bit for bit, given the same host input. The buffer begins with a header
 *  (magic "MICASTAT", format version, size, checksum) and the world's shape (bodies and their node
 *  and tet counts, tools, constraints, devices, solver). It is for this libmica on this kind of
 *  machine (native byte order), not an archive format. Meshes, materials and settings are not in
 *  it: restore into a world made the same way. Devices must be stopped (their servo loop reads the
 *  filter). The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param buffer the caller's buffer.
 *  @param bytes its size in bytes.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `buffer` is NULL); MICA_ERR_BUFFER_TOO_SMALL
 *          (`bytes` below mica_world_state_size(): nothing written, the message gives the size);
 *          MICA_ERR_WRONG_STATE (a device's servo loop runs); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_world_save_state(const mica_world* world, void* buffer, size_t bytes);

/** Restores a state saved by mica_world_save_state(). The whole buffer is checked first; on any
 *  error the world is unchanged. The contacts readout, tool forces and constraint reactions are
 *  those of the step before the save. The world's thread (the one thread using the world at a
 *  time).
 *  @param world the world: of the same shape as the one saved (the same bodies with the same node
 *         and tet counts in creation order, tools of the same shapes, constraints on the same
 *         bodies with the same node counts, devices with the same filter windows, the same solver).
 *  @param buffer the saved state.
 *  @param bytes its size in bytes (the size it was saved with).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `buffer` is NULL); MICA_ERR_PARSE (not a
 *          saved state, another format version, truncated, a checksum mismatch, or inconsistent
 *          contents: the message says which); MICA_ERR_INVALID_ARGUMENT (the state is of a world of
 *          another shape: the message names the first difference); MICA_ERR_WRONG_STATE (a
 *          device's servo loop runs); MICA_ERR_NUMERICAL (a saved factor no longer factors);
 *          MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_world_restore_state(mica_world* world, const void* buffer, size_t bytes);

#define MICA_CONTACT_NODE 1     /**< the body's point is a node (weights[0] = 1) */
#define MICA_CONTACT_EDGE 2     /**< a point of a surface edge: two nodes and their weights */
#define MICA_CONTACT_TRIANGLE 3 /**< a point of a surface triangle: three nodes, barycentric weights */
#define MICA_CONTACT_OTHER_TOOL 0 /**< the other side is a tool */
#define MICA_CONTACT_OTHER_BODY 1 /**< the other side is a body (dynamic or static) */

/** One contact of the last step. The body's point is pushed along +normal; the other side feels
 *  the opposite. Impulses are over the step (N s): the force is impulse / dt. */
typedef struct mica_contact {
  uint32_t struct_size;    /**< set by the caller in out[0] (the array's stride): sizeof(mica_contact) */
  int32_t kind;            /**< MICA_CONTACT_NODE, _EDGE or _TRIANGLE: the body's point */
  mica_body_id body;       /**< the body */
  int32_t nodes[3];        /**< the point's nodes (node_count = kind; unused ones -1) */
  int32_t other_kind;      /**< MICA_CONTACT_OTHER_TOOL or MICA_CONTACT_OTHER_BODY */
  double weights[3];       /**< the nodes' weights (barycentric, sum 1; unused ones 0) */
  uint64_t other;          /**< the tool's id (mica_tool_id) or the other body's (mica_body_id) */
  int32_t other_nodes[3];  /**< another dynamic body: its triangle's nodes; -1 for a tool or a static body */
  int32_t reserved0;       /**< zero */
  double other_weights[3]; /**< their barycentric weights; 0 when unused */
  double point[3];         /**< m, the contact point where it was detected */
  double normal[3];        /**< unit, separates the body from the other side (points towards the body) */
  double gap;              /**< m, signed distance at the start of the step (negative: penetrating) */
  double normal_impulse;   /**< N s, >= 0: the impulse on the body along `normal` */
  double tangent_impulse[3]; /**< N s, the friction impulse on the body (perpendicular to `normal`; 0 without friction) */
  double friction;         /**< the Coulomb coefficient of the contact */
  double curvature_impulse[3]; /**< N s, the impulse on the body of the contact's curvature term: a
                                    rounded tool on a triangle adds the turn of the contact normal
                                    within the step to the implicit system (docs/solvers.md); 0 for
                                    other contacts */
} mica_contact;

/** The contacts of the last step. With out == NULL only *out_count is written (the size query).
 *  The impulse on the body is normal * normal_impulse + tangent_impulse + curvature_impulse; summed over a tool's
 *  contacts and divided by -dt it is mica_tool_get_force() (within round-off). The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param out the caller's array, out[0].struct_size set to sizeof(mica_contact) (its stride), or
 *         NULL to ask for the count only.
 *  @param capacity the array's size in contacts.
 *  @param out_count receives the count (may be NULL when `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL, or both `out` and `out_count`);
 *          MICA_ERR_INVALID_ARGUMENT (`capacity` < 0); MICA_ERR_STRUCT_SIZE (out[0].struct_size
 *          is not a size this library knows); MICA_ERR_BUFFER_TOO_SMALL (`capacity` below the count:
 *          nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_world_get_contacts(const mica_world* world, mica_contact* out, int32_t capacity,
                                             int32_t* out_count);
/** @} */

/** @name Object ids (since 0.6)
 *  @{ */

#define MICA_OBJECT_BODY 1   /**< mica_world_get_ids(): bodies (since 0.6) */
#define MICA_OBJECT_LPC 2    /**< mica_world_get_ids(): constraints (since 0.6) */
#define MICA_OBJECT_TOOL 3   /**< mica_world_get_ids(): tools (since 0.6) */
#define MICA_OBJECT_DEVICE 4 /**< mica_world_get_ids(): devices (since 0.6) */
#define MICA_OBJECT_EMBEDDING 5 /**< mica_world_get_ids(): embedded meshes (since 0.7) */

/** The ids of the world's live objects of one kind (since 0.6): what a tool that did not build the
 *  world (an inspector, the replay tool) needs to read it. In slot order: creation order until an
 *  object of the kind is destroyed (a later one may then take its slot). The world's thread.
 *  @param world the world (not changed).
 *  @param kind MICA_OBJECT_BODY, _LPC, _TOOL, _DEVICE or _EMBEDDING.
 *  @param out the caller's buffer (mica_body_id, mica_lpc_id, mica_tool_id, mica_device_id or
 *         mica_embedding_id values), or NULL to ask for the count only. @param capacity its size in ids.
 *  @param out_count receives the count (may be NULL when `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world`, or both `out` and `out_count`, NULL);
 *          MICA_ERR_INVALID_ARGUMENT (an unknown kind, `capacity` < 0); MICA_ERR_BUFFER_TOO_SMALL
 *          (`capacity` below the count: nothing copied, `*out_count` = the count needed). */
MICA_API mica_status mica_world_get_ids(const mica_world* world, int32_t kind, uint64_t* out, int32_t capacity,
                                        int32_t* out_count);
/** @} */

/** @name Recording and replay (since 0.6)
 *  A recording keeps what the host fed a world - every call that changes it (bodies with their
 *  meshes, materials, constraints, grabs, tools, devices, poses, targets, node forces, positions,
 *  restored states) and every step with the poses its devices gave their tools or grasp handles -
 *  so that a fresh world replays the session bit for bit: to score a training session afterwards,
 *  or to attach to a bug report. What a device did between steps (the servo path's forces) is not recorded: the
 *  steps do not depend on it. A world with a time budget (mica_world_def.time_budget_ms) may not
 *  replay bit for bit: its steps depend on the clock. A recording is for this libmica on this kind
 *  of machine (native byte order), like a saved state. The tool `mica_replay` (installed with the
 *  library) replays one and writes CSV and VTK.
 *
 *  A recording ends with an end entry (since 0.7: format 2), written when the recording is stopped
 *  (mica_world_record_stop, or the world destroyed): a file without it was cut short (a host that
 *  died, a copy cut off), and its replay says so after its last whole step (MICA_ERR_TRUNCATED).
 *  A recording of 0.6 (format 1) has no end entry: it is replayed to the end of its file, and a
 *  cut one cannot be told from a whole one.
 *  @{ */

/** Starts recording the world into a file (created or truncated). A recording starts from a new
 *  world: call it after mica_world_create(), before anything is added. Each step is flushed to the
 *  file as it ends, so a host that crashes leaves a recording of every step before the crash.
 *  The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param path the file (UTF-8).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `path` is NULL); MICA_ERR_WRONG_STATE
 *          (already recording, or a body, tool, constraint or device was ever added); MICA_ERR_IO
 *          (the file cannot be opened or written: the message names it). */
MICA_API mica_status mica_world_record_start(mica_world* world, const char* path);

/** Stops recording: writes the end entry (the replay's proof that the recording is whole),
 *  flushes and closes the file (destroying the world does the same). A write that failed during
 *  the recording (a full disk) did not fail the call that made it: it is reported here. The
 *  world's thread.
 *  @param world the world.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_WRONG_STATE (not
 *          recording); MICA_ERR_IO (a write failed: the recording ends at the last whole entry
 *          before it, without the end entry, and the message says why). */
MICA_API mica_status mica_world_record_stop(mica_world* world);

/** A recording being replayed into a world of its own. */
typedef struct mica_replay mica_replay;

/** Opens a recording and makes the world it was recorded in (the recorded settings; no log
 *  callback). Thread: any; the replay and its world are then used by one thread at a time.
 *  @param path the recording (UTF-8).
 *  @param out_replay receives the replay, or NULL on failure.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`path` or `out_replay` is NULL); MICA_ERR_IO (the
 *          file cannot be read); MICA_ERR_PARSE (not a recording, of another format or machine
 *          kind); MICA_ERR_TRUNCATED (cut short inside its header); MICA_ERR_INVALID_ARGUMENT
 *          (recorded settings this libmica refuses);
 *          MICA_ERR_OUT_OF_MEMORY. The message: mica_world_last_error(NULL). */
MICA_API mica_status mica_replay_open(const char* path, mica_replay** out_replay);

/** Closes a replay and destroys its world. The replay's thread (the one thread using the replay
 *  and its world at a time).
 *  @param replay the replay, or NULL (nothing happens). */
MICA_API void mica_replay_close(mica_replay* replay);

/** The replay's world, to read between steps with any call that reads a world (positions, tool
 *  forces, contacts, mica_world_write_vtk, mica_world_last_error). Ids are the recorded ones.
 *  Changing the world makes the rest of the replay diverge. Owned by the replay. The replay's
 *  thread (the one thread using the replay and its world at a time).
 *  @param replay the replay.
 *  @return the world, or NULL when `replay` is NULL. */
MICA_API mica_world* mica_replay_world(const mica_replay* replay);

/** Makes the recorded calls up to the next step, then that step, and checks the step's results
 *  (positions, velocities, tool forces and torques, constraint reactions) against the recording's
 *  fingerprint of them. The replay's thread.
 *  @param replay the replay.
 *  @param out_stepped receives 1 when a step was replayed, 0 at the end of the recording (the
 *         calls recorded after its last step have been made) or when it was cut short. May be NULL.
 *  @return the step's status as mica_step() returned it when recorded (MICA_OK,
 *          MICA_WARN_NOT_CONVERGED, or the error of a step that failed then and now); MICA_OK with
 *          `*out_stepped` 0 at the end entry; or MICA_ERR_NULL_ARGUMENT (`replay` is NULL);
 *          MICA_ERR_DIVERGED (a recorded call failed, a creation got another id, or the step's
 *          results differ: the message says which and at which step); MICA_ERR_TRUNCATED (the file
 *          ends, inside an entry or between two, before the end entry: the message says after how
 *          many steps; the steps before were replayed and checked); MICA_ERR_PARSE (a corrupt
 *          entry, or bytes after the end entry). Messages:
 *          mica_world_last_error(mica_replay_world(replay)). */
MICA_API mica_status mica_replay_step(mica_replay* replay, int32_t* out_stepped);
/** @} */

/** @name Statistics
 *  The step is a plan of stages derived from the scene; a stage whose effect is absent
 *  is not in the plan and never runs.
 *  @{ */
#define MICA_STAGE_GRAVITY 0     /**< external loads: gravity and node forces */
#define MICA_STAGE_ROTATIONS 1   /**< per-element rotations (co-rotational bodies) */
#define MICA_STAGE_ELEMENTS 2    /**< elastic forces and the stiffness part of A */
#define MICA_STAGE_DAMPING 3     /**< Rayleigh damping terms */
#define MICA_STAGE_CONSTRAINTS 4 /**< projection constraints (S, z per node) */
#define MICA_STAGE_SOLVE 5       /**< the velocity solve */
#define MICA_STAGE_INTEGRATE 6   /**< positions from velocities */
#define MICA_STAGE_COLLIDE 7     /**< contacts between tools and body surfaces (runs first) */
#define MICA_STAGE_FORCES 8      /**< tool forces and constraint reactions (runs last) */
#define MICA_STAGE_COUNT 9        /**< number of stages */

/** Counters and timing of one stage of the step. */
typedef struct mica_stage_stats {
  int32_t runs_last_step; /**< times the stage ran in the last step (0 or 1) */
  int32_t reserved0;      /**< zero */
  int64_t runs_total;     /**< since creation */
  double ms_last_step;    /**< wall-clock milliseconds in the last step */
  double ms_total;        /**< since creation */
} mica_stage_stats;

/** Statistics of the last step and since creation: see mica_world_get_stats(). */
typedef struct mica_world_stats {
  uint32_t struct_size;          /**< set by the caller: sizeof(mica_world_stats) */
  int32_t converged;             /**< 1 if every solve of the last step met its tolerance */
  int64_t step_count;            /**< steps taken */
  int32_t solver_iterations;     /**< iterations of the last step (summed over bodies; 1 for direct) */
  int32_t out_of_time;           /**< 1 if a solve of the last step stopped at time_budget_ms (since 0.3) */
  double solver_residual;        /**< largest relative residual of the last step */
  double ms_last_step;           /**< wall-clock milliseconds of the last step */
  mica_stage_stats stages[MICA_STAGE_COUNT]; /**< indexed by MICA_STAGE_* */
  /* Since 0.5: */
  int32_t contacts;              /**< contacts the last step made (tool and body features closer than their margins) */
  int32_t body_contacts;         /**< of them, between two bodies (or a body and a static body) */
  /* Since 0.6: */
  /** Velocity solves of the last step: the factored sweep's rounds (each solves every body's
   *  velocities with the contact impulses, or the predicted contact set, held), 1 per solve for
   *  the other solvers; more when the step was re-linearised (mica_world_def.relinearise_tolerance). */
  int32_t solves;
  /** Numeric factorizations the last step made, or started in the background
   *  (mica_world_def.refactor_interval), summed over bodies: the steps that paid for one. */
  int32_t factorizations;
  /* Since 0.9: */
  /** Of those, the factorizations the last step waited for: made on the stepping thread, or
   *  adopted from the background thread before it was done (0 in a step whose factor stayed
   *  ahead; after a cut the factor is made in the background: docs/cutting.md). */
  int32_t factor_waits;
} mica_world_stats;

/** Copies the statistics of the last step and since creation into `out`, writing at most
 *  `out->struct_size` bytes (set it first). The world's thread (the one thread using the world at a
 *  time).
 *  @param world the world (not changed).
 *  @param out the caller's struct, its `struct_size` set.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STRUCT_SIZE (`out->struct_size` smaller than the fields before `stages` or
 *          larger than this library's). */
MICA_API mica_status mica_world_get_stats(const mica_world* world, mica_world_stats* out);

/** Static name of a stage ("gravity", "rotations", ...). Thread: any.
 *  @param stage a MICA_STAGE_* value.
 *  @return a static string, "unknown" for any other value. */
MICA_API const char* mica_stage_name(int32_t stage);
/** @} */

/** @name Output
 *  @{ */
/** Writes one body (current positions, velocities and displacements per node; since 0.6 also the
 *  von Mises stress "von_mises" (Pa, as mica_body_get_von_mises()) and "region" (as
 *  mica_body_get_tet_regions()) per tet, as CELL_DATA) as a VTK legacy unstructured grid that
 *  ParaView opens. The world's thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param path the file to write (replaced if it exists).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL);
 *          MICA_ERR_STALE_ID (`body` is null, of another kind or destroyed); MICA_ERR_IO (the file
 *          cannot be written). */
MICA_API mica_status mica_body_write_vtk(const mica_world* world, mica_body_id body,
                                         const char* path);
/** Writes every body of the world into one VTK file (cell scalar "piece" = body order; the fields
 *  of mica_body_write_vtk()). The world's
 *  thread (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param path the file to write (replaced if it exists).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or a required pointer is NULL); MICA_ERR_IO
 *          (the file cannot be written). */
MICA_API mica_status mica_world_write_vtk(const mica_world* world, const char* path);
/** @} */

/** @name Embedded meshes (since 0.7)
 *  A host's fine render mesh driven by a body's tets: each vertex is bound once to a tet and four
 *  barycentric weights at the body's rest shape, then placed from that tet's current nodes after
 *  each step, with area-weighted vertex normals (docs/embedding.md, "Rendering"). An embedding
 *  belongs to its world: named by an id, freed by mica_embedding_destroy() or with the world. It
 *  reads its body but changes nothing in the world (it is not recorded, saved or replayed). A body
 *  destroyed under it is detected: the embedding's calls then return MICA_ERR_STALE_ID.
 *  @{ */

/** Id of an embedded mesh. */
typedef uint64_t mica_embedding_id;

#define MICA_EMBED_INSIDE 0    /**< in a tet (or on its boundary): weights in [0, 1] */
/** outside the body, its nearest surface point within the radius: it follows the tet under that
 *  point with extrapolated weights (some negative), so it keeps its offset from the surface */
#define MICA_EMBED_PROJECTED 1
/** outside the body and farther than the radius from it: mica_embedding_update() leaves its
 *  entries of out_xyz as they are (never moves it, never writes the origin) */
#define MICA_EMBED_UNBOUND 2

/** Warning (since 0.7): the embedding was made, but some vertices are farther than its radius from
 *  the body and are unbound (MICA_EMBED_UNBOUND); the message names how many and the first. */
#define MICA_WARN_UNBOUND_VERTICES 4

/** How to bind a mesh: fill with mica_embedding_def_default(). */
typedef struct mica_embedding_def {
  uint32_t struct_size; /**< sizeof(mica_embedding_def) as the caller compiled it */
  int32_t reserved0;    /**< zero */
  /** m, >= 0: a vertex outside the body whose nearest point of the body's rest surface is at most
   *  this far is projected (MICA_EMBED_PROJECTED), a farther one unbound; default 0.001 */
  double radius;
} mica_embedding_def;

/** Fills `def` with defaults, writing only its first `struct_size` bytes. Thread: any.
 *  @param def the def to fill.
 *  @param struct_size sizeof(mica_embedding_def) as the caller compiled it.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` is NULL); MICA_ERR_STRUCT_SIZE (`struct_size`
 *          outside the accepted sizes: nothing is written). */
MICA_API mica_status mica_embedding_def_init(mica_embedding_def* def, uint32_t struct_size);

/** The default embedding definition (radius 1 mm). Thread: any.
 *  @return a def with `struct_size` = sizeof(mica_embedding_def) and every field at its default. */
static inline mica_embedding_def mica_embedding_def_default(void) {
  mica_embedding_def def;
  def.struct_size = (uint32_t)sizeof def; /* kept if init refuses: the create call names it */
  mica_embedding_def_init(&def, (uint32_t)sizeof def);
  return def;
}

/** Binds a host's mesh to a body: each vertex to the tet that holds it at the body's rest shape,
 *  found through a grid over the rest tets, with its four barycentric weights; a vertex in no tet
 *  to the tet under its nearest rest surface point if that is within `def->radius` (its weights
 *  extrapolated: it keeps its place relative to that tet), else left unbound. The arrays are
 *  copied. Cost: under a microsecond a vertex (bench/bench_embedding). The world's thread (the one
 *  thread using the world at a time).
 *  @param world the world (not changed).
 *  @param body the body.
 *  @param def the definition (mica_embedding_def_default(), then changed).
 *  @param xyz 3 * `vertex_count` coordinates (m) in the frame of the body's rest positions
 *         (mica_body_get_rest_positions(), which include mica_body_def.translation), finite.
 *  @param vertex_count number of vertices, >= 1.
 *  @param triangles 3 * `triangle_count` 0-based vertex indices, counter-clockwise seen from where
 *         the normals should point; may be NULL when `triangle_count` is 0 (then no normals).
 *  @param triangle_count number of triangles, >= 0.
 *  @param out_embedding receives the embedding's id.
 *  @return MICA_OK; MICA_WARN_UNBOUND_VERTICES (made, but some vertices are unbound: the message
 *          names how many and the first; mica_embedding_get_kinds() says which); or
 *          MICA_ERR_NULL_ARGUMENT (`world`, `def`, `xyz`, `out_embedding`, or `triangles` with a
 *          count above 0, is NULL); MICA_ERR_STALE_ID (`body`); MICA_ERR_STRUCT_SIZE
 *          (`def->struct_size`); MICA_ERR_INVALID_ARGUMENT (a count out of its domain, the radius
 *          negative or not finite, a coordinate not finite: the message names the vertex);
 *          MICA_ERR_OUT_OF_RANGE (a triangle names a vertex outside 0..vertex_count-1: the message
 *          names the triangle); MICA_ERR_OUT_OF_MEMORY. */
MICA_API mica_status mica_embedding_create(mica_world* world, mica_body_id body, const mica_embedding_def* def,
                                           const double* xyz, int32_t vertex_count, const int32_t* triangles,
                                           int32_t triangle_count, mica_embedding_id* out_embedding);

/** Destroys an embedding. The world's thread (the one thread using the world at a time).
 *  @param world the world.
 *  @param embedding the embedding.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_STALE_ID (`embedding` is
 *          null, of another kind or destroyed). */
MICA_API mica_status mica_embedding_destroy(mica_world* world, mica_embedding_id embedding);

/** How many vertices an embedding has, and of each kind. The world's thread (the one thread using
 *  the world at a time).
 *  @param world the world (not changed).
 *  @param embedding the embedding.
 *  @param vertex_count receives the vertex count, or NULL.
 *  @param inside receives the count of MICA_EMBED_INSIDE vertices, or NULL.
 *  @param projected receives the count of MICA_EMBED_PROJECTED vertices, or NULL.
 *  @param unbound receives the count of MICA_EMBED_UNBOUND vertices, or NULL.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_STALE_ID (`embedding`). */
MICA_API mica_status mica_embedding_get_counts(const mica_world* world, mica_embedding_id embedding,
                                               int32_t* vertex_count, int32_t* inside, int32_t* projected,
                                               int32_t* unbound);

/** The kind of each vertex (MICA_EMBED_INSIDE, _PROJECTED or _UNBOUND), 1 value per vertex; buffer
 *  protocol as mica_body_get_positions(). The world's thread (the one thread using the world at a
 *  time).
 *  @param world the world (not changed).
 *  @param embedding the embedding.
 *  @param out the caller's buffer, or NULL to ask for the count only. @param capacity its size in
 *         vertices. @param out_count receives the vertex count (may be NULL when `out` is not).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world`, or both `out` and `out_count`, NULL);
 *          MICA_ERR_STALE_ID (`embedding`); MICA_ERR_INVALID_ARGUMENT (`capacity` < 0);
 *          MICA_ERR_BUFFER_TOO_SMALL (`capacity` below the count: nothing copied, `*out_count` = the
 *          count needed). */
MICA_API mica_status mica_embedding_get_kinds(const mica_world* world, mica_embedding_id embedding, int32_t* out,
                                              int32_t capacity, int32_t* out_count);

/** Places the mesh on the body as it is now (call it after each mica_step()): each bound vertex's
 *  position (m) is its weights times its tet's current node positions, written into `out_xyz`;
 *  an unbound vertex's three values are left as they are (fill them once, e.g. with the array you
 *  bound, or hide those vertices). With `out_normals`, then the area-weighted unit normal of each
 *  vertex over its triangles at `out_xyz` (unbound vertices' values included); a vertex in no
 *  triangle, or whose triangles have no area, gets (0, 0, 0). Allocates nothing. The world's thread
 *  (the one thread using the world at a time).
 *  @param world the world (not changed).
 *  @param embedding the embedding.
 *  @param out_xyz the caller's array of 3 * vertex_count doubles (m).
 *  @param out_normals the caller's array of 3 * vertex_count doubles, apart from `out_xyz`, or NULL
 *         for no normals.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `out_xyz` is NULL); MICA_ERR_STALE_ID
 *          (`embedding`, or its body was destroyed: the message names the body);
 *          MICA_ERR_WRONG_STATE (`out_normals` given to an embedding made without triangles);
 *          MICA_ERR_INVALID_ARGUMENT (`out_normals` overlaps `out_xyz`).
 *          On an error nothing is written. */
MICA_API mica_status mica_embedding_update(const mica_world* world, mica_embedding_id embedding, double* out_xyz,
                                           double* out_normals);
/** @} */

#ifdef __cplusplus
}
#endif

#endif /* MICA_H */
