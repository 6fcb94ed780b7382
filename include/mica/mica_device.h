/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file mica_device.h
 * @brief libmica: haptic devices, the 1 kHz servo path, force filtering and safety.
 *
 * A device drives a tool of the world and renders the force the tissue puts on that tool, or
 * (since 0.6) moves the handle of a grasp and renders the force the held tissue puts on the hand.
 * Several devices may share a world, each on its own servo thread.
 * The simulation thread calls mica_step() at 10-100 Hz; the servo thread calls
 * mica_device_poll() at 1 kHz (or lets mica_device_start() run it). The two exchange data
 * without locks: the servo path never allocates, locks, blocks or makes a system call.
 *
 * Between two simulation steps the force follows the device at servo rate: each step
 * publishes a local linear model of the tool force around the tool pose it used,
 * F(x) = F0 + H (x - x0), which the servo path evaluates at the device's current pose.
 *
 * Units are SI: m, s, N, N m.
 */
#ifndef MICA_DEVICE_H
#define MICA_DEVICE_H

#include "mica.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Id of a device. */
typedef uint64_t mica_device_id;

/** What a device can do (filled by its backend). */
typedef struct mica_device_info {
  uint32_t struct_size;     /**< sizeof(mica_device_info) */
  int32_t reserved0;        /**< zero */
  char name[64];            /**< model name, NUL-terminated */
  double max_force;         /**< N, peak force the device can render */
  double continuous_force;  /**< N, force it can hold indefinitely */
  double nominal_stiffness; /**< N/m, the stiffest spring it renders stably */
  double nominal_damping;   /**< N s/m */
  double workspace_radius;  /**< m, radius of its usable workspace */
} mica_device_info;

/** One reading of the device, in the device's own frame. */
typedef struct mica_device_state {
  uint32_t struct_size;     /**< sizeof(mica_device_state) */
  int32_t buttons;          /**< bit k set: button k pressed */
  double position[3];       /**< m */
  double orientation[4];    /**< unit quaternion (w, x, y, z); within 1% of unit length it is
                                 normalised, further off the reading is refused (MICA_ERR_DEVICE) */
  double velocity[3];       /**< m/s */
  double timestamp;         /**< s, the device's clock */
} mica_device_state;

/** Callbacks of a device backend, implementable in C or through FFI (C#, Lua, Python).
 *  Every callback returns a mica_status; negative means the device failed. read_state and
 *  write_force run on the servo thread and must neither block nor allocate. */
typedef struct mica_device_callbacks {
  uint32_t struct_size; /**< sizeof(mica_device_callbacks) */
  int32_t reserved0;    /**< zero */
  void* user;           /**< passed to every callback */
  /** Opens the device (any thread but the servo thread). May be NULL. */
  mica_status (*open)(void* user);
  /** Closes the device; after it no other callback is called. May be NULL. */
  void (*close)(void* user);
  /** Describes the device. May be NULL (then the Touch's figures are assumed). */
  mica_status (*info)(void* user, mica_device_info* out);
  /** Reads the current state. Servo thread. Required. */
  mica_status (*read_state)(void* user, mica_device_state* out);
  /** Sends a force (N) and torque (N m) in the device frame. Servo thread. Required. */
  mica_status (*write_force)(void* user, const double force[3], const double torque[3]);
} mica_device_callbacks;

/** Device backends. */
#define MICA_DEVICE_CALLBACKS 0 /**< the host's callback table (mica_device_def.callbacks) */
#define MICA_DEVICE_NULL 1      /**< reads the origin, renders nothing */
#define MICA_DEVICE_SIMULATED 2 /**< a scripted stylus or a closed-loop virtual hand (see mica_device_def) */
#define MICA_DEVICE_TOUCH 3     /**< Geomagic Touch through OpenHaptics' HD API, loaded at run time
                                     (libHD.so; MICA_HD_LIBRARY overrides the path) */

/** How the servo path computes the force between simulation steps. */
#define MICA_FORCE_LOCAL_MODEL 0 /**< F0 + H (x - x0) around the pose the last step used (default) */
#define MICA_FORCE_HOLD 1        /**< the last step's force, held (zero-order hold) */
#define MICA_FORCE_COUPLING 2    /**< a spring-damper between the device and the simulated tool */

/** Simulated device kinds (mica_device_def.simulated_kind). */
#define MICA_SIMULATED_TRAJECTORY 0 /**< the stylus follows `trajectory` (or the CSV at `path`) */
#define MICA_SIMULATED_HAND 1       /**< a mass-spring-damper pulled toward `trajectory`, pushed back by the rendered force */

/** The scripted stylus of a simulated device: writes the position (m) at time t (s). */
typedef void (*mica_trajectory_fn)(double t, double position[3], void* user);

/** How to create a device. Fill with mica_device_def_default(). */
typedef struct mica_device_def {
  uint32_t struct_size;      /**< sizeof(mica_device_def) as the caller compiled it */
  int32_t backend;           /**< MICA_DEVICE_*; default MICA_DEVICE_NULL */
  const mica_device_callbacks* callbacks; /**< MICA_DEVICE_CALLBACKS: the table (copied) */
  const char* name;          /**< MICA_DEVICE_TOUCH: the HD device name, NULL for the default;
                                  MICA_DEVICE_SIMULATED: a CSV of "t,x,y,z" rows (s, m) or NULL */
  mica_tool_id tool;         /**< the tool the device drives; MICA_NULL_ID for none */
  double scale;              /**< workspace mapping: scene = rotation * (scale * device) + offset; default 1 */
  double offset[3];          /**< m, default 0 */
  double rotation[4];        /**< unit quaternion (w, x, y, z), default identity */
  int32_t force_mode;        /**< MICA_FORCE_*; default MICA_FORCE_LOCAL_MODEL */
  int32_t filter_window;     /**< moving-average window in servo samples, 1 to 10000; default 20 */
  double max_force;          /**< N, clamp on the rendered force; 0: the device's own max_force
                                  (a device reporting more than 100 N is then refused) */
  double max_force_rate;     /**< N/s, limit on the growth of the rendered force, per cycle at most
                                  that of 2 ms however long the cycle; default 1000 */
  double stall_timeout;      /**< s: with no simulation step for this long the force ramps to zero; default 0.1 */
  double stall_ramp;         /**< s, duration of that ramp; default 0.05 */
  double coupling_stiffness; /**< N/m, MICA_FORCE_COUPLING; default 300 */
  double coupling_damping;   /**< N s/m, MICA_FORCE_COUPLING; default 2 */
  int32_t simulated_kind;    /**< MICA_SIMULATED_*; default MICA_SIMULATED_TRAJECTORY */
  /** 1: a plain moving average that averages across contact changes; default 0: the window
   *  restarts at every onset and release (the paper's post-contact correction). Since 0.3. */
  int32_t filter_plain;
  mica_trajectory_fn trajectory; /**< simulated: the scripted position, or NULL (rest at the origin) */
  void* trajectory_user;     /**< passed to `trajectory` */
  double hand_mass;          /**< kg, simulated hand; default 0.1 */
  double hand_stiffness;     /**< N/m, pull toward the trajectory; default 200 */
  double hand_damping;       /**< N s/m; default 5 */
  /** The grasp whose handle follows the device (Since 0.6): a constraint from mica_lpc_grab()
   *  without a tool (or one given targets by mica_lpc_set_targets(): they become offsets from the
 *  device's pose); MICA_NULL_ID (default) for
   *  none. A device drives a tool or a grasp, not both. Each step moves the handle to the device's
   *  newest pose (absolute, like a tool: start the device where the grab was made, or map it there
   *  with `offset`), and the device renders the force the held tissue puts on the hand: the
   *  grasp's mica_lpc_get_reaction() (pulling tissue up, the hand is pulled down), modelled between
   *  steps as F0 - k (x - x0) with k the tissue's stiffness along the handle's last move, within
   *  [0, the device's nominal stiffness] (docs/haptics.md). */
  mica_lpc_id lpc;
} mica_device_def;

/** Fills `def` with defaults, writing only its first `struct_size` bytes. Thread: any.
 *  @param def the def to fill.
 *  @param struct_size sizeof(mica_device_def) as the caller compiled it.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`def` is NULL); MICA_ERR_STRUCT_SIZE (`struct_size`
 *          outside the accepted sizes: nothing is written). */
MICA_API mica_status mica_device_def_init(mica_device_def* def, uint32_t struct_size);

/** The default device definition (a null device). Thread: any.
 *  @return a def with `struct_size` = sizeof(mica_device_def) and every field at its default. */
static inline mica_device_def mica_device_def_default(void) {
  mica_device_def def;
  def.struct_size = (uint32_t)sizeof def; /* kept if init refuses: the create call names it */
  mica_device_def_init(&def, (uint32_t)sizeof def);
  return def;
}

/** Creates and opens a device. Thread: the world's; other threads may meanwhile read the world's
 *  other devices with mica_device_get_stats, mica_device_get_info and mica_device_poll (each
 *  device's servo loop, its own thread, runs on while another device is created).
 *  @param world the world.
 *  @param def the device (mica_device_def_default(), then changed).
 *  @param out_device receives the device's id.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world`, `def`, `out_device`, or the callback table
 *          a backend needs, is NULL); MICA_ERR_STALE_ID (`def->tool` is not MICA_NULL_ID and
 *          stale); MICA_ERR_STRUCT_SIZE (`def->struct_size` or the callback table's);
 *          MICA_ERR_INVALID_ARGUMENT (an unknown backend or force mode, a mapping, filter or safety
 *          value out of its domain); MICA_ERR_IO or MICA_ERR_PARSE (the simulated device's
 *          trajectory CSV); MICA_ERR_DEVICE (the device failed to open - a missing OpenHaptics
 *          library names the path tried - or its figures are not finite and positive, or absurd:
 *          docs/haptics.md). */
MICA_API mica_status mica_device_create(mica_world* world, const mica_device_def* def, mica_device_id* out_device);

/** Stops, closes and destroys a device; waits for a mica_device_get_stats, _get_info or _poll
 *  running on it on another thread to return. Thread: the world's (not the servo thread).
 *  @param world the world.
 *  @param device the device.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_STALE_ID (`device` is
 *          null, of another kind or destroyed). */
MICA_API mica_status mica_device_destroy(mica_world* world, mica_device_id device);

/** The device's description. Thread: any but the servo thread.
 *  @param world the world.
 *  @param device the device.
 *  @param out receives the description (the whole struct).
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `out` is NULL); MICA_ERR_STALE_ID
 *          (`device` is null, of another kind or destroyed). */
MICA_API mica_status mica_device_get_info(const mica_world* world, mica_device_id device, mica_device_info* out);

/** One servo cycle: read the device, map it onto its tool, evaluate the force model, filter, apply
 *  the safety limits, write the force. It never allocates, locks or blocks. A device failure, a
 *  non-finite reading, a jump back in time, an orientation that is not a unit quaternion or a pose
 *  not finite (or beyond 1e6 m) once mapped into the scene sends zero force and returns
 *  MICA_ERR_DEVICE without disturbing the simulation. No message is recorded (the world's message
 *  belongs to the simulation thread). Thread: the servo thread only (one), concurrently with
 *  mica_step() on the simulation thread.
 *  @param world the world.
 *  @param device the device.
 *  @param out_state receives the state read (device frame), or NULL.
 *  @param out_force receives the force sent (device frame, N), or NULL.
 *  @return MICA_OK; MICA_WARN_DEVICE (the device reported a warning); or MICA_ERR_NULL_ARGUMENT
 *          (`world` is NULL); MICA_ERR_STALE_ID (`device`); MICA_ERR_DEVICE (the cycle failed: zero
 *          force sent). */
MICA_API mica_status mica_device_poll(mica_world* world, mica_device_id device, mica_device_state* out_state,
                                      double out_force[3]);

/** Runs mica_device_poll() at 1 kHz on an internal thread (or the backend's own scheduler, for the
 *  Touch); nothing happens when it already runs. Thread: the world's.
 *  @param world the world.
 *  @param device the device.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_STALE_ID (`device` is
 *          null, of another kind or destroyed); MICA_ERR_OUT_OF_MEMORY or MICA_ERR_INTERNAL (the
 *          thread could not be started). */
MICA_API mica_status mica_device_start(mica_world* world, mica_device_id device);
/** Stops the servo loop started by mica_device_start() and waits for it (nothing happens when it is
 *  not running). Thread: the world's.
 *  @param world the world.
 *  @param device the device.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` is NULL); MICA_ERR_STALE_ID (`device` is
 *          null, of another kind or destroyed). */
MICA_API mica_status mica_device_stop(mica_world* world, mica_device_id device);

/** Servo statistics of a device. */
typedef struct mica_device_stats {
  uint32_t struct_size;     /**< set by the caller: sizeof(mica_device_stats) */
  int32_t last_status;      /**< status of the last poll */
  int64_t polls;            /**< servo cycles run */
  int64_t failures;         /**< polls that sent zero force because of a device or value failure */
  int64_t clamped;          /**< polls whose force was clamped or rate-limited */
  double rate_hz;           /**< servo rate measured over the last second */
  double last_force[3];     /**< N, the last force sent (device frame) */
  double last_raw_force[3]; /**< N, the last force of the model before filtering and limits (device frame) */
} mica_device_stats;

/** Copies the servo statistics, writing at most `out->struct_size` bytes (set it first). No message
 *  is recorded. Thread: any.
 *  @param world the world.
 *  @param device the device.
 *  @param out the caller's struct, its `struct_size` set.
 *  @return MICA_OK, or MICA_ERR_NULL_ARGUMENT (`world` or `out` is NULL); MICA_ERR_STALE_ID
 *          (`device` is null, of another kind or destroyed); MICA_ERR_STRUCT_SIZE
 *          (`out->struct_size` smaller than 4 or larger than this library's). */
MICA_API mica_status mica_device_get_stats(const mica_world* world, mica_device_id device, mica_device_stats* out);

#ifdef __cplusplus
}
#endif

#endif /* MICA_DEVICE_H */
