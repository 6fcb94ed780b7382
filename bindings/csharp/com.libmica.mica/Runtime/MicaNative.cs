// SPDX-License-Identifier: Apache-2.0
// The raw C API of libmica (include/mica/mica.h and mica_device.h) for C#: one [DllImport] per
// function, blittable mirrors of the structs (the C names, the C field order; int for flags,
// fixed buffers for arrays), the constants and the callback delegates.
// tests/bindings/TestMica.cs checks all of it against the header.
using System;
using System.Runtime.InteropServices;

namespace LibMica
{
    public static unsafe class MicaNative
    {
        // "mica" resolves to libmica.so beside the player or on the library path. libmica is built
        // and tested on Linux x86-64 only; there is no mica.dll or libmica.dylib yet.
        public const string Library = "mica";

        // --- Constants (mica.h)
        public const int MICA_VERSION_MAJOR = 0;
        public const int MICA_VERSION_MINOR = 9;
        public const int MICA_VERSION_PATCH = 0;
        public const int MICA_VERSION_NUMBER = MICA_VERSION_MAJOR * 10000 + MICA_VERSION_MINOR * 100 + MICA_VERSION_PATCH;

        public const int MICA_OK = 0;
        public const int MICA_WARN_NOT_CONVERGED = 1;
        public const int MICA_WARN_DEVICE = 2;
        public const int MICA_WARN_BODIES_OVERLAP = 3;
        public const int MICA_ERR_NULL_ARGUMENT = -1;
        public const int MICA_ERR_INVALID_ARGUMENT = -2;
        public const int MICA_ERR_OUT_OF_RANGE = -3;
        public const int MICA_ERR_STALE_ID = -4;
        public const int MICA_ERR_VERSION_MISMATCH = -5;
        public const int MICA_ERR_STRUCT_SIZE = -6;
        public const int MICA_ERR_BAD_MESH = -7;
        public const int MICA_ERR_IO = -8;
        public const int MICA_ERR_PARSE = -9;
        public const int MICA_ERR_NUMERICAL = -10;
        public const int MICA_ERR_WRONG_STATE = -11;
        public const int MICA_ERR_UNSUPPORTED = -12;
        public const int MICA_ERR_BUFFER_TOO_SMALL = -13;
        public const int MICA_ERR_DEVICE = -14;
        public const int MICA_ERR_OUT_OF_MEMORY = -15;
        public const int MICA_ERR_INTERNAL = -16;
        public const int MICA_ERR_DIVERGED = -17;
        public const int MICA_ERR_TRUNCATED = -18;

        public const ulong MICA_NULL_ID = 0;

        public const int MICA_LOG_ERROR = 0;
        public const int MICA_LOG_WARNING = 1;
        public const int MICA_LOG_INFO = 2;

        public const int MICA_SOLVER_DIRECT = 0;
        public const int MICA_SOLVER_PCG = 1;
        public const int MICA_SOLVER_MICA = 2;

        public const int MICA_SWEEP_GAUSS_SEIDEL = 0;
        public const int MICA_SWEEP_FACTORED = 1;

        public const int MICA_MODEL_COROTATIONAL = 0;
        public const int MICA_MODEL_LINEAR = 1;
        public const int MICA_MODEL_NEO_HOOKEAN = 2; // since 0.8
        public const int MICA_MASS_CONSISTENT = 0;
        public const int MICA_MASS_LUMPED = 1;

        public const int MICA_LPC_FIXED = 0;
        public const int MICA_LPC_PLANE = 1;
        public const int MICA_LPC_LINE = 2;
        public const int MICA_LPC_TWO_DIRS = 3;

        public const int MICA_TOOL_SPHERE = 0;
        public const int MICA_TOOL_PLANE = 1;
        public const int MICA_TOOL_CAPSULE = 2;
        public const int MICA_TOOL_BOX = 3;
        public const int MICA_TOOL_HULL = 4;

        public const int MICA_STAGE_GRAVITY = 0;
        public const int MICA_STAGE_ROTATIONS = 1;
        public const int MICA_STAGE_ELEMENTS = 2;
        public const int MICA_STAGE_DAMPING = 3;
        public const int MICA_STAGE_CONSTRAINTS = 4;
        public const int MICA_STAGE_SOLVE = 5;
        public const int MICA_STAGE_INTEGRATE = 6;
        public const int MICA_STAGE_COLLIDE = 7;
        public const int MICA_STAGE_FORCES = 8;
        public const int MICA_STAGE_COUNT = 9;

        public const int MICA_CONTACT_NODE = 1;
        public const int MICA_CONTACT_EDGE = 2;
        public const int MICA_CONTACT_TRIANGLE = 3;
        public const int MICA_CONTACT_OTHER_TOOL = 0;
        public const int MICA_CONTACT_OTHER_BODY = 1;

        public const int MICA_OBJECT_BODY = 1;
        public const int MICA_OBJECT_LPC = 2;
        public const int MICA_OBJECT_TOOL = 3;
        public const int MICA_OBJECT_DEVICE = 4;
        public const int MICA_OBJECT_EMBEDDING = 5;

        // Since 0.7: embedded meshes.
        public const int MICA_EMBED_INSIDE = 0;
        public const int MICA_EMBED_PROJECTED = 1;
        public const int MICA_EMBED_UNBOUND = 2;
        public const int MICA_WARN_UNBOUND_VERTICES = 4;

        // --- Constants (mica_device.h)
        public const int MICA_DEVICE_CALLBACKS = 0;
        public const int MICA_DEVICE_NULL = 1;
        public const int MICA_DEVICE_SIMULATED = 2;
        public const int MICA_DEVICE_TOUCH = 3;

        public const int MICA_FORCE_LOCAL_MODEL = 0;
        public const int MICA_FORCE_HOLD = 1;
        public const int MICA_FORCE_COUPLING = 2;

        public const int MICA_SIMULATED_TRAJECTORY = 0;
        public const int MICA_SIMULATED_HAND = 1;

        // --- Callback types. Under IL2CPP the functions behind them must be static methods marked
        // [AOT.MonoPInvokeCallback] (see Mica.cs); the user pointer carries the instance.
        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate void mica_log_fn(int level, IntPtr message, IntPtr user);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate void mica_trajectory_fn(double t, double* position, IntPtr user);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate void mica_task_fn(int start_index, int end_index, IntPtr task_context);

        // `task` is libmica's mica_task_fn (Marshal.GetDelegateForFunctionPointer to call it).
        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate IntPtr mica_enqueue_task_fn(IntPtr task, int item_count, int min_range, IntPtr task_context, IntPtr user);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate void mica_finish_task_fn(IntPtr handle, IntPtr user);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate int mica_device_open_fn(IntPtr user);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate void mica_device_close_fn(IntPtr user);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate int mica_device_info_fn(IntPtr user, mica_device_info* info);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate int mica_device_read_state_fn(IntPtr user, mica_device_state* state);

        [UnmanagedFunctionPointer(CallingConvention.Cdecl)]
        public delegate int mica_device_write_force_fn(IntPtr user, double* force, double* torque);

        // --- Structs (mica.h). Function pointers are IntPtr (Marshal.GetFunctionPointerForDelegate).
        [StructLayout(LayoutKind.Sequential)]
        public struct mica_world_def
        {
            public uint struct_size;
            public uint header_version;
            public fixed double gravity[3];
            public int solver;
            public int max_iterations;
            public double tolerance;
            public int plan_all_stages;
            public int reserved0;
            public IntPtr log;
            public IntPtr log_user;
            public int pgs_sweeps;
            public int paper_norm;
            public double max_recovery_speed;
            public int body_contact;
            public int reserved1;
            public double body_margin;
            public double body_friction;
            public int warm_start;
            public int reserved2;
            public double relaxation;
            public double time_budget_ms;
            public int mica_sweep;
            public int threads;
            public double relinearise_tolerance;
            public int relinearise_max;
            public int refactor_interval;
            public int task_worker_count;
            public int reserved4;
            public IntPtr enqueue_task;
            public IntPtr finish_task;
            public IntPtr task_user;
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_body_def
        {
            public uint struct_size;
            public int model;
            public int mass;
            public int is_static;
            public double youngs_modulus;
            public double poisson_ratio;
            public double density;
            public double rayleigh_alpha;
            public double rayleigh_beta;
            public fixed double translation[3];
            public fixed double velocity[3];
            public double cutting_resistance; // since 0.8
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_lpc_def
        {
            public uint struct_size;
            public int kind;
            public fixed double direction[6]; // double direction[2][3], row-major
            public fixed double velocity[3];
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_tool_def
        {
            public uint struct_size;
            public int shape;
            public double radius;
            public fixed double normal[3];
            public fixed double position[3];
            public fixed double orientation[4];
            public double margin;
            public double friction;
            public double half_length;
            public fixed double half_extents[3];
            public IntPtr hull_points; // const double*, copied by mica_tool_create
            public int hull_point_count;
            public int reserved0;
            public int blade; // since 0.8
            public int reserved1;
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_stage_stats
        {
            public int runs_last_step;
            public int reserved0;
            public long runs_total;
            public double ms_last_step;
            public double ms_total;
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_contact
        {
            public uint struct_size;
            public int kind;
            public ulong body;
            public fixed int nodes[3];
            public int other_kind;
            public fixed double weights[3];
            public ulong other;
            public fixed int other_nodes[3];
            public int reserved0;
            public fixed double other_weights[3];
            public fixed double point[3];
            public fixed double normal[3];
            public double gap;
            public double normal_impulse;
            public fixed double tangent_impulse[3];
            public double friction;
            public fixed double curvature_impulse[3];
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_world_stats
        {
            public uint struct_size;
            public int converged;
            public long step_count;
            public int solver_iterations;
            public int out_of_time;
            public double solver_residual;
            public double ms_last_step;
            // mica_stage_stats stages[MICA_STAGE_COUNT]: fixed buffers hold primitives only, so
            // the bytes are kept here and Stage(i) reads them.
            public fixed byte stages[MICA_STAGE_COUNT * 32];
            public int contacts;
            public int body_contacts;
            public int solves;          // since 0.6
            public int factorizations;
            public int factor_waits;    // since 0.9

            public mica_stage_stats Stage(int stage)
            {
                if (stage < 0 || stage >= MICA_STAGE_COUNT) throw new ArgumentOutOfRangeException("stage");
                fixed (byte* p = stages) return ((mica_stage_stats*)p)[stage];
            }
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_embedding_def // since 0.7
        {
            public uint struct_size;
            public int reserved0;
            public double radius;
        }

        // --- Structs (mica_device.h)
        [StructLayout(LayoutKind.Sequential)]
        public struct mica_device_info
        {
            public uint struct_size;
            public int reserved0;
            public fixed byte name[64]; // NUL-terminated
            public double max_force;
            public double continuous_force;
            public double nominal_stiffness;
            public double nominal_damping;
            public double workspace_radius;
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_device_state
        {
            public uint struct_size;
            public int buttons;
            public fixed double position[3];
            public fixed double orientation[4];
            public fixed double velocity[3];
            public double timestamp;
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_device_callbacks
        {
            public uint struct_size;
            public int reserved0;
            public IntPtr user;
            public IntPtr open;        // mica_device_open_fn
            public IntPtr close;       // mica_device_close_fn
            public IntPtr info;        // mica_device_info_fn
            public IntPtr read_state;  // mica_device_read_state_fn
            public IntPtr write_force; // mica_device_write_force_fn
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_device_def
        {
            public uint struct_size;
            public int backend;
            public IntPtr callbacks; // const mica_device_callbacks*, copied by mica_device_create
            public IntPtr name;      // const char*
            public ulong tool;
            public double scale;
            public fixed double offset[3];
            public fixed double rotation[4];
            public int force_mode;
            public int filter_window;
            public double max_force;
            public double max_force_rate;
            public double stall_timeout;
            public double stall_ramp;
            public double coupling_stiffness;
            public double coupling_damping;
            public int simulated_kind;
            public int filter_plain;
            public IntPtr trajectory; // mica_trajectory_fn
            public IntPtr trajectory_user;
            public double hand_mass;
            public double hand_stiffness;
            public double hand_damping;
            public ulong lpc; // since 0.6: the grasp whose handle follows the device
        }

        [StructLayout(LayoutKind.Sequential)]
        public struct mica_device_stats
        {
            public uint struct_size;
            public int last_status;
            public long polls;
            public long failures;
            public long clamped;
            public double rate_hz;
            public fixed double last_force[3];
            public fixed double last_raw_force[3];
        }

        // --- Functions (mica.h). mica_world* is a WorldHandle (a SafeHandle), except where NULL
        // is meaningful (mica_world_last_error) or the handle releases itself (mica_world_destroy).
        // Strings out are IntPtr (static or library-owned UTF-8); paths in are NUL-terminated
        // UTF-8 byte arrays (Mica.Utf8z). double[] and int[] pass as pointers (null for NULL).
        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_version();

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern IntPtr mica_status_string(int status);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_def_init(ref mica_world_def def, uint struct_size, uint header_version);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_create(ref mica_world_def def, out WorldHandle out_world);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern void mica_world_destroy(IntPtr world);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern IntPtr mica_world_last_error(IntPtr world);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_set_gravity(WorldHandle world, double[] gravity);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_def_init(ref mica_body_def def, uint struct_size);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_create(WorldHandle world, ref mica_body_def def, double[] nodes, int node_count,
                                                  int[] tets, int tet_count, out ulong out_body);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_create_from_file(WorldHandle world, ref mica_body_def def, byte[] path,
                                                            out ulong out_body);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_create_box(WorldHandle world, ref mica_body_def def, double[] lo, double[] hi,
                                                      int[] cells, int tets_per_cell, out ulong out_body);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_destroy(WorldHandle world, ulong body);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_counts(WorldHandle world, ulong body, out int node_count, out int tet_count,
                                                      out int triangle_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_positions(WorldHandle world, ulong body, double[] @out, int capacity,
                                                         out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_velocities(WorldHandle world, ulong body, double[] @out, int capacity,
                                                          out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_rest_positions(WorldHandle world, ulong body, double[] @out, int capacity,
                                                              out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_surface(WorldHandle world, ulong body, int[] @out, int capacity,
                                                       out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_positions_view(WorldHandle world, ulong body, out IntPtr @out,
                                                          out int out_node_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_set_node_forces(WorldHandle world, ulong body, int[] nodes, double[] forces,
                                                           int count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_select_nodes_in_box(WorldHandle world, ulong body, double[] lo, double[] hi,
                                                               int use_rest, int[] @out, int capacity, out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_select_nodes_by_plane(WorldHandle world, ulong body, double[] point,
                                                                 double[] normal, double tolerance, int use_rest,
                                                                 int[] @out, int capacity, out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_energy(WorldHandle world, ulong body, out double kinetic, out double elastic,
                                                      out double potential);

        // Since 0.6: tissue regions, the mesh and its fields.
        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_tets(WorldHandle world, ulong body, int[] @out, int capacity,
                                                    out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_tet_regions(WorldHandle world, ulong body, int[] @out, int capacity,
                                                           out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_set_materials(WorldHandle world, ulong body, double[] youngs_modulus,
                                                         double[] poisson_ratio, double[] density, int tet_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_remove_tets(WorldHandle world, ulong body, int[] tets, int count,
                                                       out double out_removed_mass);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_cut(WorldHandle world, ulong body, double[] triangles, int triangle_count,
                                               out int out_faces_cut, out int out_nodes_added);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_set_cutting_resistance(WorldHandle world, ulong body, double[] per_tet,
                                                                  int tet_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_topology_version(WorldHandle world, ulong body, out ulong @out);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_node_masses(WorldHandle world, ulong body, double[] @out, int capacity,
                                                           out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_strains(WorldHandle world, ulong body, double[] @out, int capacity,
                                                       out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_get_von_mises(WorldHandle world, ulong body, double[] @out, int capacity,
                                                         out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_set_positions(WorldHandle world, ulong body, double[] xyz, int node_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_set_velocities(WorldHandle world, ulong body, double[] xyz, int node_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_def_init(ref mica_lpc_def def, uint struct_size);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_add_lpc(WorldHandle world, ulong body, int[] nodes, int count, ref mica_lpc_def def,
                                              out ulong out_lpc);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_remove(WorldHandle world, ulong lpc);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_set_velocity(WorldHandle world, ulong lpc, double[] velocity);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_set_targets(WorldHandle world, ulong lpc, double[] targets, int count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_grab(WorldHandle world, ulong body, double[] center, double radius, ulong tool,
                                               out ulong out_lpc);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_set_handle_pose(WorldHandle world, ulong lpc, double[] position,
                                                          double[] orientation);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_get_nodes(WorldHandle world, ulong lpc, int[] @out, int capacity,
                                                    out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_lpc_get_reaction(WorldHandle world, ulong lpc, double[] out_force);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_def_init(ref mica_tool_def def, uint struct_size);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_create(WorldHandle world, ref mica_tool_def def, out ulong out_tool);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_destroy(WorldHandle world, ulong tool);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_set_pose(WorldHandle world, ulong tool, double[] position, double[] orientation);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_teleport(WorldHandle world, ulong tool, double[] position, double[] orientation);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_get_pose(WorldHandle world, ulong tool, double[] out_position,
                                                    double[] out_orientation);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_tool_get_force(WorldHandle world, ulong tool, double[] out_force, double[] out_torque,
                                                     out int out_contacts);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_step(WorldHandle world, double dt);

        // size_t is ulong: the bindings are for 64-bit hosts.
        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_state_size(WorldHandle world, out ulong out_bytes);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_save_state(WorldHandle world, byte[] buffer, ulong bytes);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_restore_state(WorldHandle world, byte[] buffer, ulong bytes);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_get_contacts(WorldHandle world, [In, Out] mica_contact[] @out, int capacity,
                                                         out int out_count);

        // Since 0.6: ids, recording and replay. mica_replay* is a ReplayHandle (it closes the
        // replay); the replay's world comes back as an IntPtr that World.Borrowed wraps.
        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_get_ids(WorldHandle world, int kind, ulong[] @out, int capacity,
                                                    out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_record_start(WorldHandle world, byte[] path);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_record_stop(WorldHandle world);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_replay_open(byte[] path, out ReplayHandle out_replay);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern void mica_replay_close(IntPtr replay);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern IntPtr mica_replay_world(ReplayHandle replay);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_replay_step(ReplayHandle replay, out int out_stepped);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_get_stats(WorldHandle world, ref mica_world_stats @out);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern IntPtr mica_stage_name(int stage);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_body_write_vtk(WorldHandle world, ulong body, byte[] path);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_world_write_vtk(WorldHandle world, byte[] path);

        // Since 0.7: embedded meshes. The output arrays are the host's double[] (3 values a vertex).
        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_embedding_def_init(ref mica_embedding_def def, uint struct_size);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_embedding_create(WorldHandle world, ulong body, ref mica_embedding_def def,
                                                       double[] xyz, int vertex_count, int[] triangles,
                                                       int triangle_count, out ulong out_embedding);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_embedding_destroy(WorldHandle world, ulong embedding);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_embedding_get_counts(WorldHandle world, ulong embedding, out int vertex_count,
                                                           out int inside, out int projected, out int unbound);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_embedding_get_kinds(WorldHandle world, ulong embedding, int[] @out, int capacity,
                                                          out int out_count);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_embedding_update(WorldHandle world, ulong embedding, [In, Out] double[] out_xyz,
                                                       [In, Out] double[] out_normals);

        // --- Functions (mica_device.h)
        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_def_init(ref mica_device_def def, uint struct_size);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_create(WorldHandle world, ref mica_device_def def, out ulong out_device);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_destroy(WorldHandle world, ulong device);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_get_info(WorldHandle world, ulong device, ref mica_device_info @out);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_poll(WorldHandle world, ulong device, ref mica_device_state out_state,
                                                  double[] out_force);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_start(WorldHandle world, ulong device);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_stop(WorldHandle world, ulong device);

        [DllImport(Library, CallingConvention = CallingConvention.Cdecl)]
        public static extern int mica_device_get_stats(WorldHandle world, ulong device, ref mica_device_stats @out);
    }
}
