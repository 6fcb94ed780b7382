# SPDX-License-Identifier: Apache-2.0
"""The raw ctypes layer: the library, the struct mirrors, the constants and every prototype.

Everything here mirrors include/mica/mica.h and mica_device.h one to one (same names, same
field order and types); tests/bindings/test_python.py checks it against the header.
"""
import ctypes
import ctypes.util
import os
from ctypes import (CFUNCTYPE, POINTER, Structure, c_char, c_char_p, c_double, c_int32, c_int64,
                    c_size_t, c_uint32, c_uint64, c_void_p)

# --- Constants (mica.h)
MICA_VERSION_MAJOR = 0
MICA_VERSION_MINOR = 9
MICA_VERSION_PATCH = 0
MICA_VERSION_NUMBER = MICA_VERSION_MAJOR * 10000 + MICA_VERSION_MINOR * 100 + MICA_VERSION_PATCH

MICA_OK = 0
MICA_WARN_NOT_CONVERGED = 1
MICA_WARN_DEVICE = 2
MICA_WARN_BODIES_OVERLAP = 3
MICA_ERR_NULL_ARGUMENT = -1
MICA_ERR_INVALID_ARGUMENT = -2
MICA_ERR_OUT_OF_RANGE = -3
MICA_ERR_STALE_ID = -4
MICA_ERR_VERSION_MISMATCH = -5
MICA_ERR_STRUCT_SIZE = -6
MICA_ERR_BAD_MESH = -7
MICA_ERR_IO = -8
MICA_ERR_PARSE = -9
MICA_ERR_NUMERICAL = -10
MICA_ERR_WRONG_STATE = -11
MICA_ERR_UNSUPPORTED = -12
MICA_ERR_BUFFER_TOO_SMALL = -13
MICA_ERR_DEVICE = -14
MICA_ERR_OUT_OF_MEMORY = -15
MICA_ERR_INTERNAL = -16
MICA_ERR_DIVERGED = -17
MICA_ERR_TRUNCATED = -18

MICA_NULL_ID = 0

MICA_LOG_ERROR = 0
MICA_LOG_WARNING = 1
MICA_LOG_INFO = 2

MICA_SOLVER_DIRECT = 0
MICA_SOLVER_PCG = 1
MICA_SOLVER_MICA = 2

MICA_SWEEP_GAUSS_SEIDEL = 0
MICA_SWEEP_FACTORED = 1

MICA_MODEL_COROTATIONAL = 0
MICA_MODEL_LINEAR = 1
MICA_MODEL_NEO_HOOKEAN = 2  # since 0.8
MICA_MASS_CONSISTENT = 0
MICA_MASS_LUMPED = 1

MICA_LPC_FIXED = 0
MICA_LPC_PLANE = 1
MICA_LPC_LINE = 2
MICA_LPC_TWO_DIRS = 3

MICA_TOOL_SPHERE = 0
MICA_TOOL_PLANE = 1
MICA_TOOL_CAPSULE = 2
MICA_TOOL_BOX = 3
MICA_TOOL_HULL = 4

MICA_STAGE_GRAVITY = 0
MICA_STAGE_ROTATIONS = 1
MICA_STAGE_ELEMENTS = 2
MICA_STAGE_DAMPING = 3
MICA_STAGE_CONSTRAINTS = 4
MICA_STAGE_SOLVE = 5
MICA_STAGE_INTEGRATE = 6
MICA_STAGE_COLLIDE = 7
MICA_STAGE_FORCES = 8
MICA_STAGE_COUNT = 9

MICA_CONTACT_NODE = 1
MICA_CONTACT_EDGE = 2
MICA_CONTACT_TRIANGLE = 3
MICA_CONTACT_OTHER_TOOL = 0
MICA_CONTACT_OTHER_BODY = 1

MICA_OBJECT_BODY = 1
MICA_OBJECT_LPC = 2
MICA_OBJECT_TOOL = 3
MICA_OBJECT_DEVICE = 4
MICA_OBJECT_EMBEDDING = 5

MICA_EMBED_INSIDE = 0  # since 0.7: embedded meshes
MICA_EMBED_PROJECTED = 1
MICA_EMBED_UNBOUND = 2
MICA_WARN_UNBOUND_VERTICES = 4

# --- Constants (mica_device.h)
MICA_DEVICE_CALLBACKS = 0
MICA_DEVICE_NULL = 1
MICA_DEVICE_SIMULATED = 2
MICA_DEVICE_TOUCH = 3

MICA_FORCE_LOCAL_MODEL = 0
MICA_FORCE_HOLD = 1
MICA_FORCE_COUPLING = 2

MICA_SIMULATED_TRAJECTORY = 0
MICA_SIMULATED_HAND = 1

# --- Scalar typedefs
mica_status = c_int32
mica_body_id = c_uint64
mica_lpc_id = c_uint64
mica_tool_id = c_uint64
mica_device_id = c_uint64
mica_embedding_id = c_uint64
mica_world_p = c_void_p  # opaque mica_world*
mica_replay_p = c_void_p  # opaque mica_replay*

# --- Callback types (the C calling convention of the platform)
mica_log_fn = CFUNCTYPE(None, c_int32, c_char_p, c_void_p)
mica_trajectory_fn = CFUNCTYPE(None, c_double, POINTER(c_double), c_void_p)
mica_task_fn = CFUNCTYPE(None, c_int32, c_int32, c_void_p)
mica_enqueue_task_fn = CFUNCTYPE(c_void_p, mica_task_fn, c_int32, c_int32, c_void_p, c_void_p)
mica_finish_task_fn = CFUNCTYPE(None, c_void_p, c_void_p)


# --- Structs (mica.h)
class mica_world_def(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("header_version", c_uint32),
        ("gravity", c_double * 3),
        ("solver", c_int32),
        ("max_iterations", c_int32),
        ("tolerance", c_double),
        ("plan_all_stages", c_int32),
        ("reserved0", c_int32),
        ("log", mica_log_fn),
        ("log_user", c_void_p),
        ("pgs_sweeps", c_int32),
        ("paper_norm", c_int32),
        ("max_recovery_speed", c_double),
        ("body_contact", c_int32),
        ("reserved1", c_int32),
        ("body_margin", c_double),
        ("body_friction", c_double),
        ("warm_start", c_int32),
        ("reserved2", c_int32),
        ("relaxation", c_double),
        ("time_budget_ms", c_double),
        ("mica_sweep", c_int32),
        ("threads", c_int32),
        ("relinearise_tolerance", c_double),
        ("relinearise_max", c_int32),
        ("refactor_interval", c_int32),
        ("task_worker_count", c_int32),
        ("reserved4", c_int32),
        ("enqueue_task", mica_enqueue_task_fn),
        ("finish_task", mica_finish_task_fn),
        ("task_user", c_void_p),
    ]


class mica_body_def(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("model", c_int32),
        ("mass", c_int32),
        ("is_static", c_int32),
        ("youngs_modulus", c_double),
        ("poisson_ratio", c_double),
        ("density", c_double),
        ("rayleigh_alpha", c_double),
        ("rayleigh_beta", c_double),
        ("translation", c_double * 3),
        ("velocity", c_double * 3),
        ("cutting_resistance", c_double),  # since 0.8
    ]


class mica_lpc_def(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("kind", c_int32),
        ("direction", (c_double * 3) * 2),
        ("velocity", c_double * 3),
    ]


class mica_tool_def(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("shape", c_int32),
        ("radius", c_double),
        ("normal", c_double * 3),
        ("position", c_double * 3),
        ("orientation", c_double * 4),
        ("margin", c_double),
        ("friction", c_double),
        ("half_length", c_double),
        ("half_extents", c_double * 3),
        ("hull_points", POINTER(c_double)),
        ("hull_point_count", c_int32),
        ("reserved0", c_int32),
        ("blade", c_int32),  # since 0.8
        ("reserved1", c_int32),
    ]


class mica_stage_stats(Structure):
    _fields_ = [
        ("runs_last_step", c_int32),
        ("reserved0", c_int32),
        ("runs_total", c_int64),
        ("ms_last_step", c_double),
        ("ms_total", c_double),
    ]


class mica_world_stats(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("converged", c_int32),
        ("step_count", c_int64),
        ("solver_iterations", c_int32),
        ("out_of_time", c_int32),
        ("solver_residual", c_double),
        ("ms_last_step", c_double),
        ("stages", mica_stage_stats * MICA_STAGE_COUNT),
        ("contacts", c_int32),
        ("body_contacts", c_int32),
        ("solves", c_int32),  # since 0.6
        ("factorizations", c_int32),
        ("factor_waits", c_int32),
    ]


class mica_contact(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("kind", c_int32),
        ("body", c_uint64),
        ("nodes", c_int32 * 3),
        ("other_kind", c_int32),
        ("weights", c_double * 3),
        ("other", c_uint64),
        ("other_nodes", c_int32 * 3),
        ("reserved0", c_int32),
        ("other_weights", c_double * 3),
        ("point", c_double * 3),
        ("normal", c_double * 3),
        ("gap", c_double),
        ("normal_impulse", c_double),
        ("tangent_impulse", c_double * 3),
        ("friction", c_double),
        ("curvature_impulse", c_double * 3),
    ]


class mica_embedding_def(Structure):  # since 0.7
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved0", c_int32),
        ("radius", c_double),
    ]


# --- Structs (mica_device.h)
class mica_device_info(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved0", c_int32),
        ("name", c_char * 64),
        ("max_force", c_double),
        ("continuous_force", c_double),
        ("nominal_stiffness", c_double),
        ("nominal_damping", c_double),
        ("workspace_radius", c_double),
    ]


class mica_device_state(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("buttons", c_int32),
        ("position", c_double * 3),
        ("orientation", c_double * 4),
        ("velocity", c_double * 3),
        ("timestamp", c_double),
    ]


# The device callback table's function types.
mica_device_open_fn = CFUNCTYPE(c_int32, c_void_p)
mica_device_close_fn = CFUNCTYPE(None, c_void_p)
mica_device_info_fn = CFUNCTYPE(c_int32, c_void_p, POINTER(mica_device_info))
mica_device_read_state_fn = CFUNCTYPE(c_int32, c_void_p, POINTER(mica_device_state))
mica_device_write_force_fn = CFUNCTYPE(c_int32, c_void_p, POINTER(c_double), POINTER(c_double))


class mica_device_callbacks(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("reserved0", c_int32),
        ("user", c_void_p),
        ("open", mica_device_open_fn),
        ("close", mica_device_close_fn),
        ("info", mica_device_info_fn),
        ("read_state", mica_device_read_state_fn),
        ("write_force", mica_device_write_force_fn),
    ]


class mica_device_def(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("backend", c_int32),
        ("callbacks", POINTER(mica_device_callbacks)),
        ("name", c_char_p),
        ("tool", mica_tool_id),
        ("scale", c_double),
        ("offset", c_double * 3),
        ("rotation", c_double * 4),
        ("force_mode", c_int32),
        ("filter_window", c_int32),
        ("max_force", c_double),
        ("max_force_rate", c_double),
        ("stall_timeout", c_double),
        ("stall_ramp", c_double),
        ("coupling_stiffness", c_double),
        ("coupling_damping", c_double),
        ("simulated_kind", c_int32),
        ("filter_plain", c_int32),
        ("trajectory", mica_trajectory_fn),
        ("trajectory_user", c_void_p),
        ("hand_mass", c_double),
        ("hand_stiffness", c_double),
        ("hand_damping", c_double),
        ("lpc", mica_lpc_id),  # since 0.6
    ]


class mica_device_stats(Structure):
    _fields_ = [
        ("struct_size", c_uint32),
        ("last_status", c_int32),
        ("polls", c_int64),
        ("failures", c_int64),
        ("clamped", c_int64),
        ("rate_hz", c_double),
        ("last_force", c_double * 3),
        ("last_raw_force", c_double * 3),
    ]


# --- Prototypes: name -> (restype, argtypes), in header order.
_p = POINTER
_d, _i, _u = c_double, c_int32, c_uint32
PROTOTYPES = {
    # mica.h: version and status
    "mica_version": (c_int32, []),
    "mica_status_string": (c_char_p, [mica_status]),
    # world
    "mica_world_def_init": (mica_status, [_p(mica_world_def), _u, _u]),
    "mica_world_create": (mica_status, [_p(mica_world_def), _p(mica_world_p)]),
    "mica_world_destroy": (None, [mica_world_p]),
    "mica_world_last_error": (c_char_p, [mica_world_p]),
    "mica_world_set_gravity": (mica_status, [mica_world_p, _p(_d)]),
    # bodies
    "mica_body_def_init": (mica_status, [_p(mica_body_def), _u]),
    "mica_body_create": (mica_status, [mica_world_p, _p(mica_body_def), _p(_d), _i, _p(_i), _i,
                                       _p(mica_body_id)]),
    "mica_body_create_from_file": (mica_status, [mica_world_p, _p(mica_body_def), c_char_p,
                                                 _p(mica_body_id)]),
    "mica_body_create_box": (mica_status, [mica_world_p, _p(mica_body_def), _p(_d), _p(_d), _p(_i), _i,
                                           _p(mica_body_id)]),
    "mica_body_destroy": (mica_status, [mica_world_p, mica_body_id]),
    "mica_body_get_counts": (mica_status, [mica_world_p, mica_body_id, _p(_i), _p(_i), _p(_i)]),
    "mica_body_get_positions": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i)]),
    "mica_body_get_velocities": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i)]),
    "mica_body_get_rest_positions": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i)]),
    "mica_body_get_surface": (mica_status, [mica_world_p, mica_body_id, _p(_i), _i, _p(_i)]),
    "mica_body_positions_view": (mica_status, [mica_world_p, mica_body_id, _p(_p(_d)), _p(_i)]),
    "mica_body_set_node_forces": (mica_status, [mica_world_p, mica_body_id, _p(_i), _p(_d), _i]),
    "mica_body_select_nodes_in_box": (mica_status, [mica_world_p, mica_body_id, _p(_d), _p(_d), _i, _p(_i),
                                                    _i, _p(_i)]),
    "mica_body_select_nodes_by_plane": (mica_status, [mica_world_p, mica_body_id, _p(_d), _p(_d), _d, _i,
                                                      _p(_i), _i, _p(_i)]),
    "mica_body_get_energy": (mica_status, [mica_world_p, mica_body_id, _p(_d), _p(_d), _p(_d)]),
    "mica_body_set_positions": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i]),
    "mica_body_set_velocities": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i]),
    # since 0.6: tissue regions, the mesh and its fields
    "mica_body_get_tets": (mica_status, [mica_world_p, mica_body_id, _p(_i), _i, _p(_i)]),
    "mica_body_get_tet_regions": (mica_status, [mica_world_p, mica_body_id, _p(_i), _i, _p(_i)]),
    "mica_body_set_materials": (mica_status, [mica_world_p, mica_body_id, _p(_d), _p(_d), _p(_d), _i]),
    # resection
    "mica_body_remove_tets": (mica_status, [mica_world_p, mica_body_id, _p(_i), _i, _p(_d)]),
    # since 0.8: incision and cutting resistance
    "mica_body_cut": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i), _p(_i)]),
    "mica_body_set_cutting_resistance": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i]),
    "mica_body_get_topology_version": (mica_status, [mica_world_p, mica_body_id, _p(c_uint64)]),
    "mica_body_get_node_masses": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i)]),
    "mica_body_get_strains": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i)]),
    "mica_body_get_von_mises": (mica_status, [mica_world_p, mica_body_id, _p(_d), _i, _p(_i)]),
    # projection constraints
    "mica_lpc_def_init": (mica_status, [_p(mica_lpc_def), _u]),
    "mica_add_lpc": (mica_status, [mica_world_p, mica_body_id, _p(_i), _i, _p(mica_lpc_def), _p(mica_lpc_id)]),
    "mica_lpc_remove": (mica_status, [mica_world_p, mica_lpc_id]),
    "mica_lpc_set_velocity": (mica_status, [mica_world_p, mica_lpc_id, _p(_d)]),
    "mica_lpc_set_targets": (mica_status, [mica_world_p, mica_lpc_id, _p(_d), _i]),
    "mica_lpc_grab": (mica_status, [mica_world_p, mica_body_id, _p(_d), _d, mica_tool_id, _p(mica_lpc_id)]),
    "mica_lpc_set_handle_pose": (mica_status, [mica_world_p, mica_lpc_id, _p(_d), _p(_d)]),
    "mica_lpc_get_nodes": (mica_status, [mica_world_p, mica_lpc_id, _p(_i), _i, _p(_i)]),
    "mica_lpc_get_reaction": (mica_status, [mica_world_p, mica_lpc_id, _p(_d)]),
    # tools
    "mica_tool_def_init": (mica_status, [_p(mica_tool_def), _u]),
    "mica_tool_create": (mica_status, [mica_world_p, _p(mica_tool_def), _p(mica_tool_id)]),
    "mica_tool_destroy": (mica_status, [mica_world_p, mica_tool_id]),
    "mica_tool_set_pose": (mica_status, [mica_world_p, mica_tool_id, _p(_d), _p(_d)]),
    "mica_tool_teleport": (mica_status, [mica_world_p, mica_tool_id, _p(_d), _p(_d)]),
    "mica_tool_get_pose": (mica_status, [mica_world_p, mica_tool_id, _p(_d), _p(_d)]),
    "mica_tool_get_force": (mica_status, [mica_world_p, mica_tool_id, _p(_d), _p(_d), _p(_i)]),
    # stepping, statistics, output
    "mica_step": (mica_status, [mica_world_p, _d]),
    # state and contacts
    "mica_world_state_size": (mica_status, [mica_world_p, _p(c_size_t)]),
    "mica_world_save_state": (mica_status, [mica_world_p, c_void_p, c_size_t]),
    "mica_world_restore_state": (mica_status, [mica_world_p, c_void_p, c_size_t]),
    "mica_world_get_contacts": (mica_status, [mica_world_p, _p(mica_contact), _i, _p(_i)]),
    # since 0.6: ids, recording and replay
    "mica_world_get_ids": (mica_status, [mica_world_p, _i, _p(c_uint64), _i, _p(_i)]),
    "mica_world_record_start": (mica_status, [mica_world_p, c_char_p]),
    "mica_world_record_stop": (mica_status, [mica_world_p]),
    "mica_replay_open": (mica_status, [c_char_p, _p(mica_replay_p)]),
    "mica_replay_close": (None, [mica_replay_p]),
    "mica_replay_world": (mica_world_p, [mica_replay_p]),
    "mica_replay_step": (mica_status, [mica_replay_p, _p(_i)]),
    "mica_world_get_stats": (mica_status, [mica_world_p, _p(mica_world_stats)]),
    "mica_stage_name": (c_char_p, [_i]),
    "mica_body_write_vtk": (mica_status, [mica_world_p, mica_body_id, c_char_p]),
    "mica_world_write_vtk": (mica_status, [mica_world_p, c_char_p]),
    # since 0.7: embedded meshes
    "mica_embedding_def_init": (mica_status, [_p(mica_embedding_def), _u]),
    "mica_embedding_create": (mica_status, [mica_world_p, mica_body_id, _p(mica_embedding_def), _p(_d), _i, _p(_i),
                                            _i, _p(mica_embedding_id)]),
    "mica_embedding_destroy": (mica_status, [mica_world_p, mica_embedding_id]),
    "mica_embedding_get_counts": (mica_status, [mica_world_p, mica_embedding_id, _p(_i), _p(_i), _p(_i), _p(_i)]),
    "mica_embedding_get_kinds": (mica_status, [mica_world_p, mica_embedding_id, _p(_i), _i, _p(_i)]),
    "mica_embedding_update": (mica_status, [mica_world_p, mica_embedding_id, _p(_d), _p(_d)]),
    # mica_device.h
    "mica_device_def_init": (mica_status, [_p(mica_device_def), _u]),
    "mica_device_create": (mica_status, [mica_world_p, _p(mica_device_def), _p(mica_device_id)]),
    "mica_device_destroy": (mica_status, [mica_world_p, mica_device_id]),
    "mica_device_get_info": (mica_status, [mica_world_p, mica_device_id, _p(mica_device_info)]),
    "mica_device_poll": (mica_status, [mica_world_p, mica_device_id, _p(mica_device_state), _p(_d)]),
    "mica_device_start": (mica_status, [mica_world_p, mica_device_id]),
    "mica_device_stop": (mica_status, [mica_world_p, mica_device_id]),
    "mica_device_get_stats": (mica_status, [mica_world_p, mica_device_id, _p(mica_device_stats)]),
}
del _p, _d, _i, _u


def _candidates():
    """Where to look for libmica, in order (see find_library)."""
    env = os.environ.get("MICA_LIBRARY")
    if env:
        return [env]
    names = ["libmica.so.%d" % MICA_VERSION_MAJOR, "libmica.so", "libmica.dylib", "mica.dll"]
    found = []
    # A build tree: the package copied to <build>/bindings/python/mica, libmica in <build>.
    here = os.path.dirname(os.path.abspath(__file__))
    d = here
    for _ in range(4):
        d = os.path.dirname(d)
        found += [os.path.join(d, n) for n in names if os.path.exists(os.path.join(d, n))]
    # An installed package: cmake --install wrote where it put libmica (mica/_install.py).
    try:
        from ._install import LIBDIR
    except ImportError:
        LIBDIR = None
    if LIBDIR:
        found += [os.path.join(LIBDIR, n) for n in names[:2] if os.path.exists(os.path.join(LIBDIR, n))]
    system = ctypes.util.find_library("mica")
    if system:
        found.append(system)
    return found


def find_library():
    """The path libmica is loaded from: $MICA_LIBRARY, else a libmica up to four folders above
    this package (a build tree), else the library installed with this package (mica/_install.py,
    written by cmake --install), else ctypes.util.find_library("mica")."""
    c = _candidates()
    if not c:
        raise OSError("libmica not found: set MICA_LIBRARY to the path of libmica.so")
    return c[0]


class _Missing:
    """Stands in for a function the loaded library does not export (an older libmica)."""

    def __init__(self, name):
        self.__name__ = name

    def __call__(self, *args):
        raise NotImplementedError("%s is not exported by the loaded libmica (%s)" % (self.__name__, path))


path = find_library()
lib = ctypes.CDLL(path)
missing = []  # names of the PROTOTYPES the library does not export
for _name, (_res, _args) in PROTOTYPES.items():
    try:
        _fn = getattr(lib, _name)
    except AttributeError:
        missing.append(_name)
        globals()[_name] = _Missing(_name)
        continue
    _fn.restype = _res
    _fn.argtypes = _args
    globals()[_name] = _fn
del _name, _res, _args
globals().pop("_fn", None)
