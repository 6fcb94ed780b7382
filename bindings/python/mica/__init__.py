# SPDX-License-Identifier: Apache-2.0
"""libmica from Python: deformable bodies and haptic tools through ctypes (no compiler needed).

    import mica
    with mica.World(gravity=(0, 0, 0), solver=mica.MICA_SOLVER_MICA) as world:
        cube = world.create_box((-0.05, 0, -0.05), (0.05, 0.1, 0.05), (4, 4, 4), youngs_modulus=1e4)
        tool = world.create_tool(radius=0.02, position=(0, 0.125, 0))
        world.step(0.01)
        force, torque, contacts = tool.force()
        p = cube.positions          # (n, 3) view, no copy: valid until the next step (then it raises)

The library is found through $MICA_LIBRARY, else next to a build tree holding this package,
else ctypes.util.find_library("mica") (see mica._native.find_library). The raw C API is in
mica.native: every function of mica.h and mica_device.h with its argtypes, and the structs.

Statuses: an error (status < 0) raises MicaError (.status, .message from
mica_world_last_error). A warning (status > 0: the call did its work) is issued as a
MicaWarning through the warnings module (filter it like any warning) and World.step()
returns False instead of True.

Recording (since 0.6): World.record_start(path) on a new world records the session, and
mica.Replay(path) replays it step by step, checking each step against the recording.

Threads: a World is used by one thread at a time; Device.poll() runs on the servo thread.
"""
from __future__ import annotations

import ctypes
import os
import sys
import warnings
from ctypes import POINTER, byref, c_double, c_int32, c_void_p, sizeof
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native as native
from ._native import MICA_VERSION_MAJOR, MICA_VERSION_MINOR, MICA_VERSION_NUMBER, MICA_VERSION_PATCH

# The binding's version: that of the header it mirrors (mica.version() is the loaded library's).
__version__ = "%d.%d.%d" % (MICA_VERSION_MAJOR, MICA_VERSION_MINOR, MICA_VERSION_PATCH)

_HERE = os.path.dirname(os.path.abspath(__file__))

# Type hints: a 3-vector (any sequence of floats or a numpy array), a quaternion (w, x, y, z),
# an (n, k) array or nested sequences, a file path.
Vec3 = Sequence[float]
Quat = Sequence[float]
ArrayLike = Union[np.ndarray, Sequence[Any]]
PathLike = Union[str, "os.PathLike[str]"]

# Every MICA_* constant at the package level too (mica.MICA_SOLVER_MICA).
globals().update({k: v for k, v in vars(native).items() if k.startswith("MICA_")})

__all__ = ["MicaError", "MicaWarning", "World", "Replay", "Body", "Tool", "Lpc", "Device", "DeviceBackend",
           "Embedding", "PositionsView", "version", "world_def", "body_def", "lpc_def", "tool_def", "device_def",
           "embedding_def", "native"]


class MicaError(Exception):
    """A libmica call failed: .status is the mica_status (< 0), .message the library's detail."""

    def __init__(self, status, message="", function=""):
        self.status = status
        self.message = message
        self.function = function
        name = native.mica_status_string(status).decode()
        # The library's message already names the function; the status name follows it.
        super().__init__("%s (%s)" % (message, name) if message else "%s: %s" % (function or "libmica", name))


class MicaWarning(RuntimeWarning):
    """A libmica call did its work but warns (status > 0), e.g. MICA_WARN_NOT_CONVERGED."""

    def __init__(self, status, message=""):
        self.status = status
        super().__init__(native.mica_status_string(status).decode() + (": " + message if message else ""))


def _check(status, world_handle=None, function=""):
    """Raises MicaError for status < 0, issues a MicaWarning for status > 0, returns the status."""
    if status < 0:
        message = native.mica_world_last_error(world_handle) or b""
        raise MicaError(status, message.decode(errors="replace"), function)
    if status > 0:
        message = ""
        if status in (native.MICA_WARN_BODIES_OVERLAP, native.MICA_WARN_UNBOUND_VERTICES) and world_handle is not None:
            # The library keeps these warnings' messages (the bodies and the depth; the unbound
            # vertices) as the world's.
            message = (native.mica_world_last_error(world_handle) or b"").decode(errors="replace")
        warnings.warn(MicaWarning(status, message), stacklevel=_caller_level())
    return status


def _caller_level():
    # The warning points at the first frame outside this package: the user's call.
    level, frame = 1, sys._getframe(1)
    while frame is not None and frame.f_code.co_filename.startswith(_HERE):
        level, frame = level + 1, frame.f_back
    return level


def version() -> int:
    """The version of the loaded library, as MICA_VERSION_NUMBER (major*10000 + minor*100 + patch)."""
    return native.mica_version()


def _expect_length(values, n, name):
    # A fixed-size array takes exactly n values: ctypes would pad a short sequence with zeros
    # and refuse a long one with an IndexError naming nothing.
    try:
        got = len(values)
    except TypeError:
        raise TypeError("%s: expected %d values, got %s" % (name, n, type(values).__name__)) from None
    if got != n:
        raise ValueError("%s: expected %d values, got %d" % (name, n, got))


def _assign(array, value, name):
    # Copies a (nested) Python sequence into a ctypes array field.
    _expect_length(value, len(array), name)
    for i, v in enumerate(value):
        if isinstance(array[i], ctypes.Array):
            _assign(array[i], v, "%s[%d]" % (name, i))
        else:
            array[i] = v


def _fill(struct, fields):
    names = {f[0] for f in struct._fields_}
    for key, value in fields.items():
        if key not in names or key == "struct_size":
            raise TypeError("%s has no settable field '%s'" % (type(struct).__name__, key))
        current = getattr(struct, key)
        if isinstance(current, ctypes.Array) and not isinstance(value, ctypes.Array):
            _assign(current, value, "%s.%s" % (type(struct).__name__, key))
        else:
            setattr(struct, key, value)
    return struct


# The defs are filled by the *_init functions with this side's sizeof, so a newer library
# sees exactly the fields this binding knows.
def world_def(**fields: Any) -> native.mica_world_def:
    """A mica_world_def with the library's defaults, then `fields` (gravity=(0, 0, 0), ...)."""
    d = native.mica_world_def()
    _check(native.mica_world_def_init(byref(d), sizeof(d), MICA_VERSION_NUMBER), None, "mica_world_def_init")
    return _fill(d, fields)


def body_def(**fields: Any) -> native.mica_body_def:
    """A mica_body_def with the library's defaults, then `fields`."""
    d = native.mica_body_def()
    _check(native.mica_body_def_init(byref(d), sizeof(d)), None, "mica_body_def_init")
    return _fill(d, fields)


def lpc_def(**fields: Any) -> native.mica_lpc_def:
    """A mica_lpc_def with the library's defaults, then `fields`."""
    d = native.mica_lpc_def()
    _check(native.mica_lpc_def_init(byref(d), sizeof(d)), None, "mica_lpc_def_init")
    return _fill(d, fields)


def tool_def(**fields: Any) -> native.mica_tool_def:
    """A mica_tool_def with the library's defaults, then `fields`."""
    d = native.mica_tool_def()
    _check(native.mica_tool_def_init(byref(d), sizeof(d)), None, "mica_tool_def_init")
    return _fill(d, fields)


def device_def(**fields: Any) -> native.mica_device_def:
    """A mica_device_def with the library's defaults, then `fields`."""
    d = native.mica_device_def()
    _check(native.mica_device_def_init(byref(d), sizeof(d)), None, "mica_device_def_init")
    return _fill(d, fields)


def embedding_def(**fields: Any) -> native.mica_embedding_def:
    """A mica_embedding_def with the library's defaults (radius 1 mm), then `fields`. Since 0.7."""
    d = native.mica_embedding_def()
    _check(native.mica_embedding_def_init(byref(d), sizeof(d)), None, "mica_embedding_def_init")
    return _fill(d, fields)


def _array(ctype, values, n, name):
    """A ctypes array of exactly n values (`name` says what they are when the length is wrong)."""
    _expect_length(values, n, name)
    return (ctype * n)(*values)


def _doubles(values, n, name):
    return _array(c_double, values, n, name)


def _rows(values, width, dtype, name):
    """`values` as a C-contiguous (k, width) array: a flat sequence of k * width values or k rows of width."""
    a = np.ascontiguousarray(values, dtype=dtype)
    if (a.ndim > 1 and a.shape[-1] != width) or a.size % width:
        raise ValueError("%s: expected %d values a row, got an array of shape %s" % (name, width, a.shape))
    return a.reshape(-1, width)


def _id_of(obj):
    return getattr(obj, "id", obj) if obj is not None else native.MICA_NULL_ID


class _RawBuffer:
    """The world's position buffer for numpy, without a copy (used only inside PositionsView)."""

    def __init__(self, address, node_count):
        self.__array_interface__ = {"shape": (node_count, 3), "typestr": "<f8", "data": (address, True),
                                    "version": 3}


class PositionsView:
    """A body's current positions (m), (n, 3), read from the world's own buffer without copying
    it (mica_body_positions_view).

    The buffer belongs to the world: a step, destroying the body or closing the world
    invalidates it. A view therefore checks, on every read, that none of these happened since it
    was taken, and raises MicaError (MICA_ERR_WRONG_STATE) otherwise: it never reads freed
    memory and never changes under you. Take body.positions again after each step.

    Indexing (view[:, 1], view[k]) reads only the selected part, as a new array; numpy
    functions and np.asarray(view) get a copy of the whole (a snapshot that stays valid);
    min(), max(), mean(), sum() and copy() work on the view directly. It keeps its World alive.
    """

    __array_priority__ = 1  # numpy converts it through __array__ in mixed arithmetic

    def __init__(self, world: World, body_id: int, address: int, node_count: int) -> None:
        self.world = world
        self.body_id = body_id
        self._epoch = world._view_epoch
        self._raw = np.asarray(_RawBuffer(address, node_count)) if node_count else np.empty((0, 3))
        self._raw.flags.writeable = False

    @property
    def valid(self) -> bool:
        """False once a step, the body's destruction or the world's closing invalidated it."""
        return not self.world.closed and self.world._view_epoch == self._epoch

    def _array(self):
        if self.world.closed:
            raise MicaError(native.MICA_ERR_WRONG_STATE,
                            "the world of this positions view was closed: the view's memory is gone")
        if self.world._view_epoch != self._epoch:
            raise MicaError(native.MICA_ERR_WRONG_STATE,
                            "the world stepped (or destroyed a body) since this positions view was taken: "
                            "take body.positions again")
        return self._raw

    shape = property(lambda self: self._raw.shape)
    dtype = property(lambda self: self._raw.dtype)
    ndim = property(lambda self: self._raw.ndim)
    size = property(lambda self: self._raw.size)

    def __len__(self) -> int:
        return len(self._raw)

    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> np.ndarray:
        return np.array(self._array(), dtype=dtype, copy=True)

    def __getitem__(self, key: Any) -> Any:
        part = self._array()[key]
        return part.copy() if isinstance(part, np.ndarray) else part

    def __iter__(self):
        return iter(self.copy())

    def copy(self) -> np.ndarray:
        """A copy of the positions (n, 3) that stays valid."""
        return self._array().copy()

    def min(self, *args, **kwargs):
        return self._array().min(*args, **kwargs)

    def max(self, *args, **kwargs):
        return self._array().max(*args, **kwargs)

    def mean(self, *args, **kwargs):
        return self._array().mean(*args, **kwargs)

    def sum(self, *args, **kwargs):
        return self._array().sum(*args, **kwargs)

    def __repr__(self):
        if not self.valid:
            return "PositionsView(invalid: take body.positions again)"
        return "PositionsView(%r)" % (self._raw,)


class World:
    """A simulation world (mica_world). Use it as a context manager, or call close().

    Keyword arguments set mica_world_def fields over the defaults (gravity, solver, tolerance,
    ...); `log` is an optional callable(level, message) for the library's messages.
    """

    def __init__(self, definition: Optional[native.mica_world_def] = None,
                 log: Optional[Callable[[int, str], None]] = None, **fields: Any) -> None:
        d = definition if definition is not None else world_def()
        _fill(d, fields)
        # Callbacks the library may call while the world exists (log, enqueue_task, finish_task).
        self._keepalive = [v for v in fields.values() if isinstance(v, ctypes._CFuncPtr)]
        if log is not None:
            def on_log(level, message, user):
                log(level, message.decode(errors="replace"))
            d.log = native.mica_log_fn(on_log)
            self._keepalive.append(d.log)
        handle = c_void_p()
        _check(native.mica_world_create(byref(d), byref(handle)), None, "mica_world_create")
        self._handle = handle
        self._owner = None  # a Replay when the world is the replay's (then close() does not destroy it)
        self._view_epoch = 0  # advanced by whatever invalidates positions views (PositionsView)

    @classmethod
    def _borrowed(cls, handle: c_void_p, owner: Any) -> World:
        # A wrapper of a world that `owner` owns (a Replay's): it keeps the owner alive, and its
        # close() only forgets the handle.
        world = cls.__new__(cls)
        world._keepalive = []
        world._handle = handle
        world._owner = owner
        world._view_epoch = 0
        return world

    # --- lifetime
    @property
    def handle(self) -> c_void_p:
        """The mica_world* as a c_void_p; raises if the world was closed."""
        if self._handle is None:
            raise MicaError(native.MICA_ERR_WRONG_STATE, "the world is closed")
        return self._handle

    @property
    def closed(self) -> bool:
        return self._handle is None

    def close(self) -> None:
        """Destroys the world and everything in it. Views and ids from it become invalid.
        A replay's world (Replay.world) belongs to the replay: this does nothing, closing the
        Replay destroys it."""
        if getattr(self, "_owner", None) is None and getattr(self, "_handle", None) is not None:
            self._view_epoch += 1
            native.mica_world_destroy(self._handle)
            self._handle = None
            self._keepalive = []

    def _forget(self) -> None:
        # The owner (a Replay) destroyed the world: the wrapper is closed from now on.
        self._view_epoch += 1
        self._handle = None
        self._owner = None

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: the module may be half torn down
            pass

    def _check(self, status, function=""):
        return _check(status, self.handle, function)

    @property
    def last_error(self) -> str:
        return (native.mica_world_last_error(self.handle) or b"").decode(errors="replace")

    # --- world
    def step(self, dt: float) -> bool:
        """Advances by dt seconds. Returns True, or False (and warns) when the solver stopped
        at its iteration cap. Every positions view taken before is invalid afterwards (reading
        it raises)."""
        handle = self.handle
        self._view_epoch += 1  # even a failed step may have touched the buffers
        return self._check(native.mica_step(handle, dt), "mica_step") == native.MICA_OK

    def set_gravity(self, gravity: Vec3) -> None:
        self._check(native.mica_world_set_gravity(self.handle, _doubles(gravity, 3, "set_gravity gravity")),
                    "mica_world_set_gravity")

    def stats(self) -> native.mica_world_stats:
        """A mica_world_stats of the last step (stages indexed by MICA_STAGE_*)."""
        s = native.mica_world_stats()
        s.struct_size = sizeof(s)
        self._check(native.mica_world_get_stats(self.handle, byref(s)), "mica_world_get_stats")
        return s

    def save_state(self) -> bytes:
        """The world's dynamic state (mica_world_save_state), for restore_state()."""
        size = ctypes.c_size_t()
        self._check(native.mica_world_state_size(self.handle, byref(size)), "mica_world_state_size")
        buffer = ctypes.create_string_buffer(size.value)
        self._check(native.mica_world_save_state(self.handle, buffer, size.value), "mica_world_save_state")
        return buffer.raw

    def restore_state(self, state: bytes) -> None:
        """Puts back a state from save_state() (a world of the same shape); raises MicaError
        with the world unchanged otherwise."""
        state = bytes(state)
        self._view_epoch += 1
        self._check(native.mica_world_restore_state(self.handle, state, len(state)), "mica_world_restore_state")

    def ids(self, kind: int) -> list:
        """The ids (ints) of the live objects of one kind: MICA_OBJECT_BODY, _LPC, _TOOL,
        _DEVICE or (since 0.7) _EMBEDDING, in slot order (creation order until one of the kind is
        destroyed). Since 0.6."""
        n = c_int32()
        self._check(native.mica_world_get_ids(self.handle, kind, None, 0, byref(n)), "mica_world_get_ids")
        out = (ctypes.c_uint64 * max(n.value, 1))()
        self._check(native.mica_world_get_ids(self.handle, kind, out, n.value, byref(n)), "mica_world_get_ids")
        return list(out[:n.value])

    def record_start(self, path: PathLike) -> None:
        """Starts recording the world into `path` (created or truncated), for Replay: call it on
        a new world, before anything is added. Each step is flushed as it ends. Since 0.6."""
        self._check(native.mica_world_record_start(self.handle, str(path).encode()), "mica_world_record_start")

    def record_stop(self) -> None:
        """Stops recording and closes the file; raises MicaError (MICA_ERR_IO) if a write failed
        during the recording. Closing the world also closes the file. Since 0.6."""
        self._check(native.mica_world_record_stop(self.handle), "mica_world_record_stop")

    def contacts(self) -> list:
        """The contacts of the last step, a list of mica_contact."""
        n = c_int32()
        self._check(native.mica_world_get_contacts(self.handle, None, 0, byref(n)), "mica_world_get_contacts")
        if n.value == 0:
            return []
        out = (native.mica_contact * n.value)()
        out[0].struct_size = sizeof(native.mica_contact)
        self._check(native.mica_world_get_contacts(self.handle, out, n.value, byref(n)), "mica_world_get_contacts")
        return list(out)

    def write_vtk(self, path: PathLike) -> None:
        self._check(native.mica_world_write_vtk(self.handle, str(path).encode()), "mica_world_write_vtk")

    # --- creation
    def create_body(self, nodes: ArrayLike, tets: ArrayLike, definition: Optional[native.mica_body_def] = None,
                    **fields: Any) -> Body:
        """A body from nodes (n, 3) in m and tets (m, 4) of 0-based indices."""
        d = _fill(definition if definition is not None else body_def(), fields)
        nodes = _rows(nodes, 3, np.float64, "create_body nodes")
        tets = _rows(tets, 4, np.int32, "create_body tets")
        out = native.mica_body_id()
        self._check(native.mica_body_create(self.handle, byref(d), nodes.ctypes.data_as(POINTER(c_double)),
                                            len(nodes), tets.ctypes.data_as(POINTER(c_int32)), len(tets),
                                            byref(out)), "mica_body_create")
        return Body(self, out.value)

    def create_body_from_file(self, path: PathLike, definition: Optional[native.mica_body_def] = None,
                              **fields: Any) -> Body:
        """A body from a mesh file: Gmsh .msh (2.2 or 4.1 ASCII) or a TetGen .node/.ele pair."""
        d = _fill(definition if definition is not None else body_def(), fields)
        out = native.mica_body_id()
        self._check(native.mica_body_create_from_file(self.handle, byref(d), str(path).encode(), byref(out)),
                    "mica_body_create_from_file")
        return Body(self, out.value)

    def create_box(self, lo: Vec3, hi: Vec3, cells: Sequence[int], tets_per_cell: int = 5,
                   definition: Optional[native.mica_body_def] = None, **fields: Any) -> Body:
        """A box [lo, hi] (m) of cells[0] x cells[1] x cells[2] cubes, 5 or 6 tets each."""
        d = _fill(definition if definition is not None else body_def(), fields)
        out = native.mica_body_id()
        self._check(native.mica_body_create_box(self.handle, byref(d), _doubles(lo, 3, "create_box lo"),
                                                _doubles(hi, 3, "create_box hi"),
                                                _array(c_int32, cells, 3, "create_box cells"), tets_per_cell,
                                                byref(out)), "mica_body_create_box")
        return Body(self, out.value)

    def create_tool(self, definition: Optional[native.mica_tool_def] = None, hull_points: Optional[ArrayLike] = None,
                    **fields: Any) -> Tool:
        """A kinematic tool; fields of mica_tool_def (shape, radius, position, ...)."""
        d = _fill(definition if definition is not None else tool_def(), fields)
        if hull_points is not None:
            pts = _rows(hull_points, 3, np.float64, "create_tool hull_points")
            d.hull_points = pts.ctypes.data_as(POINTER(c_double))  # copied by the library
            d.hull_point_count = len(pts)
        out = native.mica_tool_id()
        self._check(native.mica_tool_create(self.handle, byref(d), byref(out)), "mica_tool_create")
        return Tool(self, out.value)

    def create_device(self, backend: Optional[DeviceBackend] = None, tool: Optional[Tool] = None,
                      trajectory: Optional[Callable[[float], Vec3]] = None,
                      definition: Optional[native.mica_device_def] = None, grasp: Optional["Lpc"] = None,
                      **fields: Any) -> Device:
        """A haptic device driving `tool`, or (since 0.6) `grasp`, a grab's Lpc whose handle follows
        the device (mica_device_def.lpc: it renders the grasp's reaction, the force on the hand).
        `backend` is a DeviceBackend (its methods become the callback table) or None for the def's
        backend (MICA_DEVICE_NULL by default); `trajectory` is a callable t -> (x, y, z) for a
        simulated device."""
        d = _fill(definition if definition is not None else device_def(), fields)
        d.tool = _id_of(tool)
        if grasp is not None:
            d.lpc = _id_of(grasp)
        table = None
        if backend is not None:
            table = backend._table()
            d.backend = native.MICA_DEVICE_CALLBACKS
            d.callbacks = ctypes.pointer(table)
            self._keepalive.append(table)
        if trajectory is not None:
            def on_trajectory(t, position, user):
                p = trajectory(t)
                _expect_length(p, 3, "trajectory(%g)" % t)  # an error here is reported, not raised (a callback)
                position[0], position[1], position[2] = p
            d.trajectory = native.mica_trajectory_fn(on_trajectory)
            self._keepalive.append(d.trajectory)
        out = native.mica_device_id()
        self._check(native.mica_device_create(self.handle, byref(d), byref(out)), "mica_device_create")
        return Device(self, out.value, backend)


class Replay:
    """A recording (World.record_start) replayed into a world of its own (mica_replay). Use it as
    a context manager, or call close().

        with mica.Replay("session.micarec") as replay:
            tool = mica.Tool(replay.world, replay.world.ids(mica.MICA_OBJECT_TOOL)[0])
            while replay.step():
                force, torque, contacts = tool.force()

    .world is the replay's world (ids are the recorded ones): read it between steps; changing it
    makes the rest of the replay diverge. It belongs to the replay: its close() does nothing,
    closing the replay closes it. A step that does not reproduce the recording raises MicaError
    with status MICA_ERR_DIVERGED (the message names the step). Since 0.6.
    """

    def __init__(self, path: PathLike) -> None:
        handle = c_void_p()
        _check(native.mica_replay_open(str(path).encode(), byref(handle)), None, "mica_replay_open")
        self._handle = handle
        self.world = World._borrowed(c_void_p(native.mica_replay_world(handle)), self)

    @property
    def handle(self) -> c_void_p:
        """The mica_replay* as a c_void_p; raises if the replay was closed."""
        if self._handle is None:
            raise MicaError(native.MICA_ERR_WRONG_STATE, "the replay is closed")
        return self._handle

    @property
    def closed(self) -> bool:
        return self._handle is None

    def step(self) -> bool:
        """Makes the recorded calls up to the next step, then that step, and checks its results
        against the recording. Returns True when a step was replayed, False at the end of the
        recording. Raises MicaError (MICA_ERR_DIVERGED, MICA_ERR_TRUNCATED for a recording cut
        short, MICA_ERR_PARSE, or the error the step had when recorded); a step that did not
        converge when recorded warns, as World.step()."""
        handle = self.handle
        self.world._view_epoch += 1
        stepped = c_int32()
        _check(native.mica_replay_step(handle, byref(stepped)), self.world.handle, "mica_replay_step")
        return stepped.value != 0

    def close(self) -> None:
        """Closes the replay and destroys its world (views and ids from it become invalid)."""
        if getattr(self, "_handle", None) is not None:
            self.world._forget()
            native.mica_replay_close(self._handle)
            self._handle = None

    def __enter__(self) -> Replay:
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: the module may be half torn down
            pass


class _Object:
    """An object of a world, named by its 64-bit id; it holds a reference to the World."""

    def __init__(self, world: World, id_: int) -> None:
        self.world = world
        self.id = id_

    def __repr__(self):
        return "%s(0x%016x)" % (type(self).__name__, self.id)

    def __eq__(self, other):
        return type(self) is type(other) and self.world is other.world and self.id == other.id

    def __hash__(self):
        return hash((id(self.world), self.id))


def _read_items(call, width, dtype):
    # The size-query protocol: ask for the count, then fill a buffer of that size.
    count = c_int32()
    call(None, 0, byref(count))
    ctype = c_double if dtype == np.float64 else c_int32
    out = np.empty((count.value, width), dtype=dtype)
    call(out.ctypes.data_as(POINTER(ctype)), count.value, byref(count))
    return out


class Body(_Object):
    """A deformable (or static) body."""

    def counts(self) -> Tuple[int, int, int]:
        """(node_count, tet_count, triangle_count)."""
        n, t, tri = c_int32(), c_int32(), c_int32()
        self.world._check(native.mica_body_get_counts(self.world.handle, self.id, byref(n), byref(t), byref(tri)),
                          "mica_body_get_counts")
        return n.value, t.value, tri.value

    @property
    def positions(self) -> PositionsView:
        """A PositionsView of the current positions (m), (n, 3): read from the world's buffer
        without copying it, valid until the next step, the body's destruction or the world's
        closing, after which reading it raises MicaError. Take it again after every step, or
        keep a copy (get_positions(), view.copy())."""
        ptr, n = POINTER(c_double)(), c_int32()
        self.world._check(native.mica_body_positions_view(self.world.handle, self.id, byref(ptr), byref(n)),
                          "mica_body_positions_view")
        return PositionsView(self.world, self.id, ctypes.cast(ptr, c_void_p).value, n.value)

    def _get(self, fn, width, dtype, name):
        w = self.world
        return _read_items(lambda out, cap, cnt: w._check(fn(w.handle, self.id, out, cap, cnt), name), width, dtype)

    def get_positions(self) -> np.ndarray:
        """A copy of the current positions (m), (n, 3)."""
        return self._get(native.mica_body_get_positions, 3, np.float64, "mica_body_get_positions")

    def velocities(self) -> np.ndarray:
        return self._get(native.mica_body_get_velocities, 3, np.float64, "mica_body_get_velocities")

    def rest_positions(self) -> np.ndarray:
        return self._get(native.mica_body_get_rest_positions, 3, np.float64, "mica_body_get_rest_positions")

    def surface(self) -> np.ndarray:
        """Surface triangles (k, 3), counter-clockwise seen from outside."""
        return self._get(native.mica_body_get_surface, 3, np.int32, "mica_body_get_surface")

    def select_nodes_in_box(self, lo: Vec3, hi: Vec3, use_rest: bool = True) -> np.ndarray:
        w, lo, hi = self.world, _doubles(lo, 3, "select_nodes_in_box lo"), _doubles(hi, 3, "select_nodes_in_box hi")
        return _read_items(lambda out, cap, cnt: w._check(native.mica_body_select_nodes_in_box(
            w.handle, self.id, lo, hi, int(use_rest), out, cap, cnt), "mica_body_select_nodes_in_box"),
            1, np.int32).ravel()

    def select_nodes_by_plane(self, point: Vec3, normal: Vec3, tolerance: float = 1e-9,
                              use_rest: bool = True) -> np.ndarray:
        """Nodes with (p - point) . normal <= tolerance."""
        w = self.world
        p, nrm = _doubles(point, 3, "select_nodes_by_plane point"), _doubles(normal, 3, "select_nodes_by_plane normal")
        return _read_items(lambda out, cap, cnt: w._check(native.mica_body_select_nodes_by_plane(
            w.handle, self.id, p, nrm, tolerance, int(use_rest), out, cap, cnt), "mica_body_select_nodes_by_plane"),
            1, np.int32).ravel()

    def set_node_forces(self, nodes: ArrayLike, forces: ArrayLike) -> None:
        nodes = np.ascontiguousarray(nodes, dtype=np.int32).ravel()
        forces = _rows(forces, 3, np.float64, "set_node_forces forces")
        if len(forces) != len(nodes):
            raise ValueError("one force per node")
        self.world._check(native.mica_body_set_node_forces(
            self.world.handle, self.id, nodes.ctypes.data_as(POINTER(c_int32)),
            forces.ctypes.data_as(POINTER(c_double)), len(nodes)), "mica_body_set_node_forces")

    def _set_nodes(self, fn, values, name):
        values = _rows(values, 3, np.float64, name)
        self.world._check(fn(self.world.handle, self.id, values.ctypes.data_as(POINTER(c_double)), len(values)), name)

    def set_positions(self, positions: ArrayLike) -> None:
        """Sets every node's position (m), (n, 3); drops what was derived from the old ones."""
        self._set_nodes(native.mica_body_set_positions, positions, "mica_body_set_positions")

    def set_velocities(self, velocities: ArrayLike) -> None:
        """Sets every node's velocity (m/s), (n, 3)."""
        self._set_nodes(native.mica_body_set_velocities, velocities, "mica_body_set_velocities")

    def energy(self) -> Tuple[float, float, float]:
        """(kinetic, elastic, potential) in J."""
        k, e, p = c_double(), c_double(), c_double()
        self.world._check(native.mica_body_get_energy(self.world.handle, self.id, byref(k), byref(e), byref(p)),
                          "mica_body_get_energy")
        return k.value, e.value, p.value

    def tets(self) -> np.ndarray:
        """The tets (t, 4), 0-based node indices."""
        return self._get(native.mica_body_get_tets, 4, np.int32, "mica_body_get_tets")

    def tet_regions(self) -> np.ndarray:
        """Region of each tet (t,): the Gmsh physical tag or TetGen region attribute, else 0."""
        return self._get(native.mica_body_get_tet_regions, 1, np.int32, "mica_body_get_tet_regions").ravel()

    def set_materials(self, youngs_modulus: Optional[ArrayLike] = None, poisson_ratio: Optional[ArrayLike] = None,
                      density: Optional[ArrayLike] = None) -> None:
        """Per tet: Young's modulus (Pa), Poisson ratio, density (kg/m^3); None keeps that property.
        Rebuilds the body's stiffness, mass and damping."""
        tets = self.counts()[1]
        arrays = []
        for name, values in (("youngs_modulus", youngs_modulus), ("poisson_ratio", poisson_ratio),
                             ("density", density)):
            if values is None:
                arrays.append(None)
                continue
            a = np.ascontiguousarray(values, dtype=np.float64).ravel()
            if len(a) != tets:
                raise ValueError(f"{name}: one value per tet ({tets}), got {len(a)}")
            arrays.append(a)
        pointers = [None if a is None else a.ctypes.data_as(POINTER(c_double)) for a in arrays]
        self.world._check(native.mica_body_set_materials(self.world.handle, self.id, *pointers, tets),
                          "mica_body_set_materials")

    def remove_tets(self, tets: ArrayLike) -> float:
        """Removes these tets (resection); returns their mass, kg. Node and tet indices change:
        nodes no kept tet holds go, the rest are renumbered in order (see topology_version)."""
        tets = np.ascontiguousarray(tets, dtype=np.int32).ravel()
        removed = c_double(0)
        self.world._check(native.mica_body_remove_tets(self.world.handle, self.id,
                                                       tets.ctypes.data_as(POINTER(c_int32)), len(tets),
                                                       byref(removed)), "mica_body_remove_tets")
        return removed.value

    def cut(self, triangles: ArrayLike) -> Tuple[int, int]:
        """Incision (since 0.8): separates the body along a cut surface, triangles in world space
        (m) where the body is now: (k, 3, 3) corners, (k, 9) rows or a flat multiple of 9 values.
        Returns (faces_cut, nodes_added); a cut frees no piece of fewer than 8 tets (such a sliver
        stays joined); node copies are numbered after the body's nodes, tet indices stay (see
        topology_version, which a cut that separates no node leaves alone)."""
        t = np.ascontiguousarray(triangles, dtype=np.float64)
        if not ((t.ndim == 3 and t.shape[1:] == (3, 3)) or (t.ndim == 2 and t.shape[1] == 9)
                or (t.ndim == 1 and t.size % 9 == 0)):
            raise ValueError("cut triangles: expected rows of 3 corners (k, 3, 3) or of 9 values, got an array "
                             "of shape %s" % (t.shape,))
        t = t.reshape(-1, 9)
        faces, added = c_int32(0), c_int32(0)
        self.world._check(native.mica_body_cut(self.world.handle, self.id,
                                               t.ctypes.data_as(POINTER(c_double)) if len(t) else None, len(t),
                                               byref(faces), byref(added)), "mica_body_cut")
        return faces.value, added.value

    def set_cutting_resistance(self, per_tet: ArrayLike) -> None:
        """Each tet's cutting resistance (since 0.8): the force per metre of blade edge (N/m, >= 0)
        the tissue bears before a blade (tool_def blade=1) parts it; one value per tet."""
        tets = self.counts()[1]
        a = np.ascontiguousarray(per_tet, dtype=np.float64).ravel()
        if len(a) != tets:
            raise ValueError(f"cutting_resistance: one value per tet ({tets}), got {len(a)}")
        self.world._check(native.mica_body_set_cutting_resistance(self.world.handle, self.id,
                                                                  a.ctypes.data_as(POINTER(c_double)), tets),
                          "mica_body_set_cutting_resistance")

    def topology_version(self) -> int:
        """How many times the body's tets have changed (0 at creation)."""
        out = ctypes.c_uint64(0)
        self.world._check(native.mica_body_get_topology_version(self.world.handle, self.id, byref(out)),
                          "mica_body_get_topology_version")
        return out.value

    def node_masses(self) -> np.ndarray:
        """Mass of each node (n,), kg: the row sums of the mass matrix."""
        return self._get(native.mica_body_get_node_masses, 1, np.float64, "mica_body_get_node_masses").ravel()

    def strains(self) -> np.ndarray:
        """Strain of each tet (t, 6): xx, yy, zz, yz, xz, xy (tensor shears), co-rotated."""
        return self._get(native.mica_body_get_strains, 6, np.float64, "mica_body_get_strains")

    def von_mises(self) -> np.ndarray:
        """Von Mises stress of each tet (t,), Pa."""
        return self._get(native.mica_body_get_von_mises, 1, np.float64, "mica_body_get_von_mises").ravel()

    def add_lpc(self, nodes: ArrayLike, definition: Optional[native.mica_lpc_def] = None, **fields: Any) -> Lpc:
        """A projection constraint on `nodes` (kind=MICA_LPC_FIXED by default)."""
        d = _fill(definition if definition is not None else lpc_def(), fields)
        nodes = np.ascontiguousarray(nodes, dtype=np.int32).ravel()
        out = native.mica_lpc_id()
        self.world._check(native.mica_add_lpc(self.world.handle, self.id, nodes.ctypes.data_as(POINTER(c_int32)),
                                              len(nodes), byref(d), byref(out)), "mica_add_lpc")
        return Lpc(self.world, out.value)

    def grab(self, center: Vec3, radius: float, tool: Optional[Tool] = None) -> Lpc:
        """Holds the nodes within `radius` of `center` on a handle (following `tool` if given)."""
        out = native.mica_lpc_id()
        self.world._check(native.mica_lpc_grab(self.world.handle, self.id, _doubles(center, 3, "grab center"), radius,
                                               _id_of(tool), byref(out)), "mica_lpc_grab")
        return Lpc(self.world, out.value)

    def write_vtk(self, path: PathLike) -> None:
        self.world._check(native.mica_body_write_vtk(self.world.handle, self.id, str(path).encode()),
                          "mica_body_write_vtk")

    def embed(self, xyz: ArrayLike, triangles: Optional[ArrayLike] = None,
              definition: Optional[native.mica_embedding_def] = None, **fields: Any) -> Embedding:
        """Binds a render mesh to this body (mica_embedding_create, since 0.7): vertices (n, 3) in m
        in the frame of the rest positions, triangles (k, 3) of vertex indices for the normals
        (None: no normals); fields of mica_embedding_def (radius=...). Vertices farther than the
        radius from the body are unbound: a MicaWarning (MICA_WARN_UNBOUND_VERTICES) names them."""
        d = _fill(definition if definition is not None else embedding_def(), fields)
        xyz = _rows(xyz, 3, np.float64, "embed xyz")
        tris = _rows(triangles if triangles is not None else np.empty((0, 3)), 3, np.int32, "embed triangles")
        out = native.mica_embedding_id()
        status = native.mica_embedding_create(
            self.world.handle, self.id, byref(d), xyz.ctypes.data_as(POINTER(c_double)), len(xyz),
            tris.ctypes.data_as(POINTER(c_int32)) if len(tris) else None, len(tris), byref(out))
        embedding = Embedding(self.world, out.value, xyz, len(tris) > 0) if status >= 0 else None
        self.world._check(status, "mica_embedding_create")  # raises for an error, warns for unbound vertices
        return embedding

    def destroy(self) -> None:
        self.world._view_epoch += 1  # positions views of this body lose their buffer
        self.world._check(native.mica_body_destroy(self.world.handle, self.id), "mica_body_destroy")


class Embedding(_Object):
    """A render mesh bound to a body's tets (Body.embed; mica_embedding_*, since 0.7).

    update() places it on the body as it is now: it writes the positions (n, 3) and, when the
    mesh has triangles, the area-weighted unit normals (n, 3) into float64 numpy arrays, in place:
    by default its own .positions and .normals (made once, reused by every update: views you
    may hand to a renderer), or arrays you pass (C-contiguous float64 of shape (n, 3)). An
    unbound vertex (kinds() == MICA_EMBED_UNBOUND) is never written: .positions starts as the
    bound vertices, so such a vertex stays where it was given.
    """

    def __init__(self, world: World, id_: int, xyz: np.ndarray, has_triangles: bool) -> None:
        super().__init__(world, id_)
        self.positions = np.array(xyz, dtype=np.float64, order="C")  # updated in place
        self.normals = np.zeros_like(self.positions) if has_triangles else None

    @property
    def vertex_count(self) -> int:
        return len(self.positions)

    def counts(self) -> Tuple[int, int, int, int]:
        """(vertices, inside, projected, unbound)."""
        n, i, p, u = c_int32(), c_int32(), c_int32(), c_int32()
        self.world._check(native.mica_embedding_get_counts(self.world.handle, self.id, byref(n), byref(i), byref(p),
                                                           byref(u)), "mica_embedding_get_counts")
        return n.value, i.value, p.value, u.value

    def kinds(self) -> np.ndarray:
        """The kind of each vertex (n,): MICA_EMBED_INSIDE, _PROJECTED or _UNBOUND."""
        w = self.world
        return _read_items(lambda out, cap, cnt: w._check(native.mica_embedding_get_kinds(
            w.handle, self.id, out, cap, cnt), "mica_embedding_get_kinds"), 1, np.int32).ravel()

    def _target(self, array, name):
        if not (isinstance(array, np.ndarray) and array.dtype == np.float64 and array.flags.c_contiguous
                and array.flags.writeable and array.shape == (self.vertex_count, 3)):
            raise ValueError("%s: expected a writeable C-contiguous float64 array of shape (%d, 3)"
                             % (name, self.vertex_count))
        return array.ctypes.data_as(POINTER(c_double))

    def update(self, out_xyz: Optional[np.ndarray] = None,
               out_normals: Optional[np.ndarray] = None) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """Writes the positions (m) and normals after the last step into out_xyz and out_normals
        (default: .positions and .normals) and returns the two arrays (normals None without
        triangles). Allocates nothing."""
        xyz = self.positions if out_xyz is None else out_xyz
        normals = self.normals if out_normals is None else out_normals
        self.world._check(native.mica_embedding_update(
            self.world.handle, self.id, self._target(xyz, "out_xyz"),
            None if normals is None else self._target(normals, "out_normals")), "mica_embedding_update")
        return xyz, normals

    def destroy(self) -> None:
        self.world._check(native.mica_embedding_destroy(self.world.handle, self.id), "mica_embedding_destroy")


class Lpc(_Object):
    """A linear projection constraint group (fixed nodes, a plane, a grab)."""

    def set_velocity(self, velocity: Vec3) -> None:
        self.world._check(native.mica_lpc_set_velocity(self.world.handle, self.id,
                                                       _doubles(velocity, 3, "set_velocity velocity")),
                          "mica_lpc_set_velocity")

    def set_targets(self, targets: ArrayLike) -> None:
        t = _rows(targets, 3, np.float64, "set_targets targets")
        self.world._check(native.mica_lpc_set_targets(self.world.handle, self.id,
                                                      t.ctypes.data_as(POINTER(c_double)), len(t)),
                          "mica_lpc_set_targets")

    def set_handle_pose(self, position: Vec3, orientation: Quat = (1, 0, 0, 0)) -> None:
        self.world._check(native.mica_lpc_set_handle_pose(
            self.world.handle, self.id, _doubles(position, 3, "set_handle_pose position"),
            _doubles(orientation, 4, "set_handle_pose orientation")), "mica_lpc_set_handle_pose")

    def nodes(self) -> np.ndarray:
        w = self.world
        return _read_items(lambda out, cap, cnt: w._check(native.mica_lpc_get_nodes(w.handle, self.id, out, cap, cnt),
                                                          "mica_lpc_get_nodes"), 1, np.int32).ravel()

    def reaction(self) -> np.ndarray:
        """Reaction force (N) of the last step, as a numpy 3-vector."""
        f = (c_double * 3)()
        self.world._check(native.mica_lpc_get_reaction(self.world.handle, self.id, f), "mica_lpc_get_reaction")
        return np.array(f[:])

    def remove(self) -> None:
        self.world._check(native.mica_lpc_remove(self.world.handle, self.id), "mica_lpc_remove")


class Tool(_Object):
    """A kinematic rigid tool: the host sets its pose, the bodies push back on it."""

    def set_pose(self, position: Vec3, orientation: Quat = (1, 0, 0, 0)) -> None:
        """The pose for the next step, which sweeps the tool there from its last pose."""
        self.world._check(native.mica_tool_set_pose(
            self.world.handle, self.id, _doubles(position, 3, "set_pose position"),
            _doubles(orientation, 4, "set_pose orientation")), "mica_tool_set_pose")

    def teleport(self, position: Vec3, orientation: Quat = (1, 0, 0, 0)) -> None:
        """Puts the tool at a pose without a sweep (nothing on the way is pushed)."""
        self.world._check(native.mica_tool_teleport(
            self.world.handle, self.id, _doubles(position, 3, "teleport position"),
            _doubles(orientation, 4, "teleport orientation")), "mica_tool_teleport")

    def pose(self) -> Tuple[np.ndarray, np.ndarray]:
        """(position m, orientation quaternion w, x, y, z) as numpy vectors; a tool driven by a
        device takes the device's pose at each step."""
        p, q = (c_double * 3)(), (c_double * 4)()
        self.world._check(native.mica_tool_get_pose(self.world.handle, self.id, p, q), "mica_tool_get_pose")
        return np.array(p[:]), np.array(q[:])

    def force(self) -> Tuple[np.ndarray, np.ndarray, int]:
        """(force N, torque N m, contacts) of the last step; force and torque as numpy 3-vectors."""
        f, t, n = (c_double * 3)(), (c_double * 3)(), c_int32()
        self.world._check(native.mica_tool_get_force(self.world.handle, self.id, f, t, byref(n)),
                          "mica_tool_get_force")
        return np.array(f[:]), np.array(t[:]), n.value

    def destroy(self) -> None:
        self.world._check(native.mica_tool_destroy(self.world.handle, self.id), "mica_tool_destroy")


class DeviceBackend:
    """A haptic device implemented in Python: override read_state and write_force (and open,
    close, info if needed), pass it to World.create_device(backend=...).

    read_state and write_force run on the servo thread (the caller of Device.poll(), or libmica's
    own 1 kHz thread after Device.start()); they take the GIL, so a Python backend suits tests and
    simulations, not a real 1 kHz device. An exception inside a callback becomes MICA_ERR_DEVICE
    and is kept in .error.
    """

    error = None

    def open(self) -> None:
        pass

    def close(self) -> None:
        pass

    def info(self, out: native.mica_device_info) -> None:
        """Fill `out` (a mica_device_info); leave this method alone to use libmica's defaults."""

    def read_state(self, state: native.mica_device_state) -> None:
        """Fill `state` (a mica_device_state: position, orientation, velocity, buttons, timestamp)."""
        raise NotImplementedError

    def write_force(self, force: Tuple[float, float, float], torque: Tuple[float, float, float]) -> None:
        """Render `force` (N) and `torque` (N m), both 3-tuples in the device frame."""
        raise NotImplementedError

    def _guard(self, f):
        # No Python exception may unwind into C: report it as a device failure.
        def call(*args):
            try:
                f(*args)
                return native.MICA_OK
            except Exception as e:  # noqa: BLE001 - every failure is the device's
                self.error = e
                return native.MICA_ERR_DEVICE
        return call

    def _table(self):
        t = native.mica_device_callbacks()
        t.struct_size = sizeof(t)
        t.open = native.mica_device_open_fn(self._guard(lambda user: self.open()))
        close = self._guard(lambda user: self.close())
        t.close = native.mica_device_close_fn(lambda user: close(user) and None)
        if type(self).info is not DeviceBackend.info:
            t.info = native.mica_device_info_fn(self._guard(lambda user, out: self.info(out.contents)))
        t.read_state = native.mica_device_read_state_fn(self._guard(lambda user, out: self.read_state(out.contents)))
        t.write_force = native.mica_device_write_force_fn(
            self._guard(lambda user, f, tq: self.write_force((f[0], f[1], f[2]), (tq[0], tq[1], tq[2]))))
        return t


class Device(_Object):
    """A haptic device driving a tool. poll() is the servo cycle: call it on the servo thread
    (or start() libmica's own 1 kHz loop)."""

    def __init__(self, world: World, id_: int, backend: Optional[DeviceBackend] = None) -> None:
        super().__init__(world, id_)
        self.backend = backend

    def poll(self) -> Tuple[native.mica_device_state, np.ndarray]:
        """One servo cycle: returns (mica_device_state read, force sent as a numpy 3-vector).
        A failing device (zero force sent) raises MicaError without a message: the world's
        last error belongs to the simulation thread. Warnings (MICA_WARN_DEVICE) are not
        issued here, at servo rate; stats().last_status has them."""
        s = native.mica_device_state()
        s.struct_size = sizeof(s)
        f = (c_double * 3)()
        status = native.mica_device_poll(self.world.handle, self.id, byref(s), f)
        if status < 0:
            raise MicaError(status, "", "mica_device_poll")
        return s, np.array(f[:])

    def start(self) -> None:
        self.world._check(native.mica_device_start(self.world.handle, self.id), "mica_device_start")

    def stop(self) -> None:
        self.world._check(native.mica_device_stop(self.world.handle, self.id), "mica_device_stop")

    def info(self) -> native.mica_device_info:
        i = native.mica_device_info()
        i.struct_size = sizeof(i)
        self.world._check(native.mica_device_get_info(self.world.handle, self.id, byref(i)), "mica_device_get_info")
        return i

    def stats(self) -> native.mica_device_stats:
        s = native.mica_device_stats()
        s.struct_size = sizeof(s)
        self.world._check(native.mica_device_get_stats(self.world.handle, self.id, byref(s)), "mica_device_get_stats")
        return s

    def destroy(self) -> None:
        self.world._check(native.mica_device_destroy(self.world.handle, self.id), "mica_device_destroy")
