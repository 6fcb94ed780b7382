# SPDX-License-Identifier: Apache-2.0
"""Tests of the Python binding (bindings/python/mica): its declarations against the header
manifest (the drift guard), the sphere-indent scene against the C reference, errors, warnings,
view lifetime, devices implemented in Python, and recording and replay.

Environment (set by tests/bindings/CMakeLists.txt): MICA_LIBRARY, MICA_MANIFEST,
MICA_REFERENCE, MICA_BINDINGS_BUILD_DIR; PYTHONPATH holds bindings/python.
"""
import ctypes
import gc
import json
import os
import subprocess
import sys
import tempfile
import unittest
import warnings

import numpy as np

import mica
from mica import native

MANIFEST = json.load(open(os.environ["MICA_MANIFEST"]))


def ctype_class(t):
    """(class, size) of a ctypes type as the manifest names them."""
    if t is None:
        return "void", 0
    if issubclass(t, (ctypes._Pointer, ctypes.c_char_p, ctypes.c_void_p, ctypes._CFuncPtr)):
        return "ptr", ctypes.sizeof(t)
    if issubclass(t, ctypes.Array):
        return ctype_class(t._type_)[0], ctypes.sizeof(t)
    if issubclass(t, ctypes.Structure):
        return "struct", ctypes.sizeof(t)
    if t in (ctypes.c_double, ctypes.c_float):
        return "float", ctypes.sizeof(t)
    if t is ctypes.c_char:
        return "char", 1
    signed = t(-1).value < 0
    return ("int" if signed else "uint"), ctypes.sizeof(t)


class DriftGuard(unittest.TestCase):
    """The binding's declarations are the header's: functions, structs, typedefs, constants."""

    def test_functions(self):
        header = {f["name"]: f for f in MANIFEST["functions"]}
        self.assertEqual(sorted(set(header) - set(native.PROTOTYPES)), [], "in the header, not in the binding")
        self.assertEqual(sorted(set(native.PROTOTYPES) - set(header)), [], "in the binding, not in the header")
        for name, f in header.items():
            restype, argtypes = native.PROTOTYPES[name]
            self.assertEqual(len(argtypes), len(f["params"]), name + ": argument count")
            self.assertEqual(ctype_class(restype), (f["return"]["class"], f["return"]["size"]), name + ": return")
            for i, (t, p) in enumerate(zip(argtypes, f["params"])):
                self.assertEqual(ctype_class(t), (p["class"], p["size"]), "%s: parameter %d (%s)" % (name, i, p["name"]))
            if name not in native.missing:
                fn = getattr(native, name)
                self.assertEqual(fn.argtypes, argtypes, name)

    def test_structs(self):
        header = {s["name"] for s in MANIFEST["structs"]}
        mirrors = {k for k, v in vars(native).items() if isinstance(v, type) and issubclass(v, ctypes.Structure)
                   and k.startswith("mica_")}
        self.assertEqual(sorted(header - mirrors), [], "structs in the header without a mirror")
        self.assertEqual(sorted(mirrors - header), [], "mirrors of structs not in the header")
        for s in MANIFEST["structs"]:
            py = getattr(native, s["name"])
            self.assertEqual(ctypes.sizeof(py), s["size"], s["name"] + ": size")
            self.assertEqual(ctypes.alignment(py), s["align"], s["name"] + ": alignment")
            self.assertEqual([f[0] for f in py._fields_], [f["name"] for f in s["fields"]], s["name"] + ": fields")
            for (fname, ftype), f in zip(py._fields_, s["fields"]):
                where = "%s.%s" % (s["name"], fname)
                self.assertEqual(getattr(py, fname).offset, f["offset"], where + ": offset")
                self.assertEqual(getattr(py, fname).size, f["size"], where + ": size")
                self.assertEqual(ctype_class(ftype)[0], f["class"], where + ": type")

    def test_typedefs_and_callbacks(self):
        for t in MANIFEST["typedefs"]:
            self.assertEqual(ctype_class(getattr(native, t["name"])), (t["class"], t["size"]), t["name"])
        for c in MANIFEST["callbacks"]:
            self.assertEqual(len(getattr(native, c["name"])._argtypes_), c["param_count"], c["name"])

    def test_constants(self):
        header = {c["name"]: c["value"] for c in MANIFEST["constants"]}
        mine = {k: v for k, v in vars(native).items() if k.startswith("MICA_")}
        self.assertEqual(sorted(set(header) - set(mine)), [], "constants in the header, not in the binding")
        self.assertEqual(sorted(set(mine) - set(header)), [], "constants in the binding, not in the header")
        for name, value in header.items():
            self.assertEqual(mine[name], value, name)
        self.assertEqual(mica.version() // 10000, mica.MICA_VERSION_MAJOR, "the loaded library's major version")


def read_reference():
    rows = []
    with open(os.environ["MICA_REFERENCE"]) as f:
        for line in f:
            k, fx, fy, fz, contacts = line.strip().split(",")
            rows.append((int(k), (float(fx), float(fy), float(fz)), int(contacts)))
    return rows


def sphere_indent(steps):
    """examples_c/sphere_indent.c through the Pythonic layer: the force and contacts per step."""
    L, E, nu, rho, dt = 0.1, 1e4, 0.4, 1000.0, 0.01
    R, margin, start_gap, max_depth = 0.02, 0.0015, 0.005, 0.015
    cells = 12
    out = []
    with mica.World(gravity=(0, 0, 0), solver=mica.MICA_SOLVER_MICA, max_iterations=2000, tolerance=1e-6) as world:
        cube = world.create_box((-L / 2, 0, -L / 2), (L / 2, L, L / 2), (cells, cells, cells), 5,
                                youngs_modulus=E, poisson_ratio=nu, density=rho,
                                rayleigh_alpha=2.0, rayleigh_beta=0.005)
        bottom = cube.select_nodes_by_plane((0, 0, 0), (0, 1, 0), 1e-9, use_rest=True)
        cube.add_lpc(bottom, kind=mica.MICA_LPC_FIXED)
        y_start = L + R + start_gap
        sphere = world.create_tool(shape=mica.MICA_TOOL_SPHERE, radius=R, margin=margin, position=(0, y_start, 0))
        n_load, n_hold, n_unload = steps // 3, steps // 6, steps // 3
        travel = start_gap + max_depth
        speed = travel / (n_load * dt)
        for k in range(1, steps + 1):
            # The same floating-point operations as the C program, in the same order.
            if k <= n_load:
                y = y_start - speed * k * dt
            elif k <= n_load + n_hold:
                y = y_start - travel
            elif k <= n_load + n_hold + n_unload:
                y = y_start - travel + speed * (k - n_load - n_hold) * dt
            else:
                y = y_start
            sphere.set_pose((0, y, 0), (1, 0, 0, 0))
            world.step(dt)
            force, _, contacts = sphere.force()
            out.append((k, tuple(force), contacts))
    return out


class Scene(unittest.TestCase):
    def test_sphere_indent_matches_c(self):
        ref = read_reference()
        got = sphere_indent(len(ref))
        peak = 0.0
        for (k, fr, cr), (_, fp, cp) in zip(ref, got):
            scale = max(np.linalg.norm(fr), np.linalg.norm(fp))
            peak = max(peak, fr[1])
            self.assertEqual(cp, cr, "step %d: contacts" % k)
            for i in range(3):
                # Relative to the force's magnitude: the same operations agree to round-off.
                self.assertLessEqual(abs(fp[i] - fr[i]), 1e-9 * scale, "step %d: force[%d] %r vs C %r" % (k, i, fp[i], fr[i]))
        self.assertGreater(peak, 0.1, "the scene indents at all")
        worst = max((abs(fp[i] - fr[i]) / max(np.linalg.norm(fr), np.linalg.norm(fp))
                     for (_, fr, _), (_, fp, _) in zip(ref, got) if max(np.linalg.norm(fr), np.linalg.norm(fp)) > 0
                     for i in range(3)), default=0.0)
        print("(%d steps, largest deviation from C %.3g of the force) " % (len(ref), worst), end="", file=sys.stderr)


class Behaviour(unittest.TestCase):
    def test_defaults_come_from_the_library(self):
        d = mica.world_def()
        self.assertEqual(d.struct_size, ctypes.sizeof(native.mica_world_def))
        self.assertEqual(d.header_version, mica.MICA_VERSION_NUMBER)
        self.assertEqual(list(d.gravity), [0, -9.81, 0])
        self.assertEqual(mica.body_def().youngs_modulus, 1e4)
        self.assertEqual(mica.tool_def().orientation[:], [1, 0, 0, 0])
        with self.assertRaises(TypeError):
            mica.world_def(no_such_field=1)

    def test_version_and_type_marker(self):
        # mica.__version__ is the header's version, which the loaded library (built with it) reports.
        v = mica.version()
        self.assertEqual(mica.__version__, "%d.%d.%d" % (v // 10000, v // 100 % 100, v % 100))
        self.assertEqual(mica.__version__, "%d.%d.%d" % (mica.MICA_VERSION_MAJOR, mica.MICA_VERSION_MINOR,
                                                         mica.MICA_VERSION_PATCH))
        # PEP 561: without py.typed, type checkers treat the package as untyped.
        self.assertTrue(os.path.isfile(os.path.join(os.path.dirname(mica.__file__), "py.typed")))

    def test_errors_raise_with_the_message(self):
        with mica.World() as world:
            with self.assertRaises(mica.MicaError) as e:
                world.create_box((0, 0, 0), (-1, 1, 1), (1, 1, 1))
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            self.assertIn("hi[0]", e.exception.message)
            body = world.create_box((0, 0, 0), (1, 1, 1), (1, 1, 1))
            body.destroy()
            with self.assertRaises(mica.MicaError) as e:
                body.counts()
            self.assertEqual(e.exception.status, mica.MICA_ERR_STALE_ID)
        with self.assertRaises(mica.MicaError) as e:
            world.step(0.01)  # closed
        self.assertEqual(e.exception.status, mica.MICA_ERR_WRONG_STATE)
        with self.assertRaises(mica.MicaError) as e:
            mica.World(header_version=(mica.MICA_VERSION_MAJOR + 1) * 10000)
        self.assertEqual(e.exception.status, mica.MICA_ERR_VERSION_MISMATCH)

    def test_wrong_length_sequences_are_refused(self):
        # A fixed-size array takes exactly its count of values: never padded, never an IndexError.
        with mica.World(gravity=(0, 0, 0)) as world:
            def refused(message, call, *args, **kwargs):
                with self.assertRaises(ValueError) as e:
                    call(*args, **kwargs)
                self.assertEqual(str(e.exception), message)

            for cells in ((2, 2), (2, 2, 2, 2), ()):
                refused("create_box cells: expected 3 values, got %d" % len(cells),
                        world.create_box, (0, 0, 0), (1, 1, 1), cells)
            refused("create_box lo: expected 3 values, got 2", world.create_box, (0, 0), (1, 1, 1), (1, 1, 1))
            refused("create_box hi: expected 3 values, got 4", world.create_box, (0, 0, 0), (1, 1, 1, 1), (1, 1, 1))
            with self.assertRaises(TypeError) as e:
                world.create_box((0, 0, 0), (1, 1, 1), 2)
            self.assertEqual(str(e.exception), "create_box cells: expected 3 values, got int")
            self.assertEqual(world.ids(mica.MICA_OBJECT_BODY), [], "no body from a refused call")
            body = world.create_box((0, 0, 0), (1, 1, 1), np.array([1, 1, 1]))

            tool = world.create_tool(radius=0.01, position=(0.1, 2, 0.3))
            refused("mica_tool_def.position: expected 3 values, got 1", world.create_tool, position=(0.5,))
            refused("mica_tool_def.orientation: expected 4 values, got 3", world.create_tool, orientation=(1, 0, 0))
            refused("mica_lpc_def.direction[1]: expected 3 values, got 2", mica.lpc_def,
                    direction=((1, 0, 0), (0, 1)))
            refused("mica_world_def.gravity: expected 3 values, got 4", mica.World, gravity=(0, 0, 0, 0))
            for position in ((0.2,), (0.1, 0.2), (0.1, 0.2, 0.3, 0.4)):
                refused("set_pose position: expected 3 values, got %d" % len(position), tool.set_pose, position)
            refused("set_pose orientation: expected 4 values, got 5", tool.set_pose, (0, 2, 0), (1, 0, 0, 0, 0))
            np.testing.assert_array_equal(tool.pose()[0], (0.1, 2, 0.3), "a refused pose leaves the tool alone")

            refused("select_nodes_by_plane normal: expected 3 values, got 2", body.select_nodes_by_plane,
                    (0, 0, 0), (0, 1))
            refused("select_nodes_in_box hi: expected 3 values, got 2", body.select_nodes_in_box, (0, 0, 0), (1, 1))
            refused("grab center: expected 3 values, got 1", body.grab, (0,), 0.1)
            grab = body.grab((0, 1, 0), 0.1)
            refused("set_handle_pose orientation: expected 4 values, got 2", grab.set_handle_pose, (0, 1, 0), (1, 0))
            refused("set_velocity velocity: expected 3 values, got 2", grab.set_velocity, (0, 1))
            refused("set_gravity gravity: expected 3 values, got 2", world.set_gravity, (0, -9.81))

            # Arrays of rows: each row has its width (a flat array, a multiple of it).
            n = body.counts()[0]
            refused("mica_body_set_positions: expected 3 values a row, got an array of shape (%d, 2)" % n,
                    body.set_positions, np.zeros((n, 2)))
            refused("create_body nodes: expected 3 values a row, got an array of shape (6, 2)",
                    world.create_body, np.zeros((6, 2)), [0, 1, 2, 3])
            refused("create_body tets: expected 4 values a row, got an array of shape (3,)",
                    world.create_body, np.eye(4, 3), [0, 1, 2])
            refused("set_targets targets: expected 3 values a row, got an array of shape (2, 4)",
                    grab.set_targets, np.zeros((2, 4)))

    @unittest.skipIf("mica_device_create" in native.missing, "the loaded libmica has no device functions yet")
    def test_teleport_is_no_sweep(self):
        """A sphere made inside a box and teleported above it touches nothing; set_pose would sweep."""
        with mica.World(gravity=(0, 0, 0)) as world:
            world.create_box((0, 0, 0), (0.1, 0.1, 0.1), (2, 2, 2), 5)
            tool = world.create_tool(radius=0.01, position=(0.05, 0.05, 0.05))
            tool.teleport((0.05, 0.2, 0.05))
            world.step(0.01)
            force, _, contacts = tool.force()
            self.assertEqual((tuple(force), contacts), ((0.0, 0.0, 0.0), 0))
            self.assertEqual(tuple(tool.pose()[0]), (0.05, 0.2, 0.05))
            with self.assertRaisesRegex(ValueError, "teleport position: expected 3 values, got 1"):
                tool.teleport((0.2,))

    def test_embedding_fills_numpy_arrays(self):
        """A render mesh on a box: at rest in place, moved with the body into the same arrays (no
        new ones), an unbound vertex warned about and left where it was, NaN refused by index."""
        with mica.World(gravity=(0, 0, 0)) as world:
            box = world.create_box((0, 0, 0), (0.1, 0.1, 0.1), (2, 2, 2), 5)
            xyz = np.array([[0.05, 0.05, 0.05], [0.02, 0.1, 0.03], [0.08, 0.1, 0.07], [0.03, 0.1, 0.09],
                            [0.05, 0.5, 0.05]])
            with self.assertWarns(mica.MicaWarning) as w:
                sheet = box.embed(xyz, [[1, 3, 2]], radius=0.001)
            self.assertEqual(w.warning.status, mica.MICA_WARN_UNBOUND_VERTICES)
            self.assertIn("vertex 4", str(w.warning))
            self.assertEqual(sheet.counts(), (5, 4, 0, 1))
            self.assertEqual(list(sheet.kinds()), [0, 0, 0, 0, 2])
            positions, normals = sheet.update()
            self.assertIs(positions, sheet.positions)
            np.testing.assert_allclose(positions, xyz, atol=1e-12)
            np.testing.assert_allclose(normals[1], (0, 1, 0), atol=1e-12)
            rest = box.rest_positions()
            box.set_positions(rest + (0, 0.01, 0))
            out, out_n = np.zeros((5, 3)), np.zeros((5, 3))
            self.assertIs(sheet.update(out, out_n)[0], out)
            np.testing.assert_allclose(out[:4], xyz[:4] + (0, 0.01, 0), atol=1e-12)
            np.testing.assert_array_equal(out[4], (0, 0, 0))  # unbound: left as it was
            with self.assertRaisesRegex(ValueError, "out_xyz"):
                sheet.update(np.zeros((5, 3), dtype=np.float32))
            bad = xyz.copy()
            bad[2, 0] = np.nan
            with self.assertRaises(mica.MicaError) as e:
                box.embed(bad)
            self.assertIn("vertex 2 is not finite", e.exception.message)
            sheet.destroy()
            with self.assertRaises(mica.MicaError) as e:
                sheet.update()
            self.assertEqual(e.exception.status, mica.MICA_ERR_STALE_ID)

    def test_host_job_system_as_raw_callbacks(self):
        """enqueue_task and finish_task as ctypes callbacks: the same bits as threads = 2."""
        calls = []

        def enqueue(task, item_count, min_range, context, user):
            calls.append(item_count)
            task(0, item_count, context)  # every range here, then NULL: no finish_task
            return None

        def run(**fields):
            with mica.World(gravity=(0, -9.81, 0), **fields) as world:
                body = world.create_box((0, 0, 0), (0.1, 0.1, 0.1), (3, 3, 3), youngs_modulus=2e4)
                body.add_lpc(body.select_nodes_by_plane((0, 0, 0), (0, 1, 0)))
                for _ in range(3):
                    world.step(0.01)
                return body.get_positions()

        own = run(threads=2)
        hosted = run(task_worker_count=2, enqueue_task=native.mica_enqueue_task_fn(enqueue),
                     finish_task=native.mica_finish_task_fn(lambda handle, user: None))
        np.testing.assert_array_equal(hosted, own)
        self.assertTrue(calls and set(calls) == {1}, calls)

    def test_a_trajectory_of_the_wrong_length_is_reported(self):
        # The trajectory runs inside a C callback: its error goes to sys.unraisablehook.
        reported = []
        hook, sys.unraisablehook = sys.unraisablehook, lambda u: reported.append(str(u.exc_value))
        try:
            with mica.World(gravity=(0, 0, 0)) as world:
                device = world.create_device(definition=mica.device_def(backend=mica.MICA_DEVICE_SIMULATED),
                                             tool=world.create_tool(radius=0.01), trajectory=lambda t: (0, 0.1))
                device.poll()
        finally:
            sys.unraisablehook = hook
        self.assertTrue(reported, "the trajectory was called")
        self.assertRegex(reported[0], r"^trajectory\(.*\): expected 3 values, got 2$")

    def test_warning_when_not_converged(self):
        with mica.World(solver=mica.MICA_SOLVER_PCG, max_iterations=1, tolerance=1e-14) as world:
            world.create_box((0, 0, 0), (1, 1, 1), (2, 2, 2), youngs_modulus=1e5)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                converged = world.step(0.01)
            self.assertFalse(converged)
            self.assertEqual([w.message.status for w in caught], [mica.MICA_WARN_NOT_CONVERGED])
            self.assertEqual(world.stats().converged, 0)

    def test_positions_view_is_zero_copy_and_keeps_the_world(self):
        def make():
            world = mica.World()
            body = world.create_box((0, 0, 0), (1, 1, 1), (2, 2, 2))
            return body.positions, body

        view, body = make()
        gc.collect()
        self.assertIsInstance(view, mica.PositionsView)
        self.assertTrue(view.valid)
        self.assertEqual(view.shape, (27, 3))
        self.assertEqual(len(view), 27)
        self.assertIs(view.world, body.world)
        np.testing.assert_array_equal(view, body.get_positions())
        # No copy: the view reads the world's own buffer, the same one each time.
        view2 = body.positions
        self.assertEqual(view._raw.__array_interface__["data"][0], view2._raw.__array_interface__["data"][0])
        self.assertFalse(view._raw.flags.writeable)
        # What leaves the view is a copy: writing to it does not touch the world.
        column = view[:, 1]
        column[:] = 42.0
        self.assertNotEqual(body.get_positions()[0, 1], 42.0)
        snapshot = np.asarray(view)
        body.world.step(0.01)  # the documented rule: take the view again after a step
        np.testing.assert_array_equal(body.positions, body.get_positions())
        self.assertLess(body.positions[:, 1].min(), 0)
        self.assertLess(body.positions.min(axis=0)[1], 0)
        self.assertEqual(snapshot[0, 1], 0.0)  # the snapshot taken before the step did not change
        body.world.close()

    def test_type_hints(self):
        # Every public method of the object layer is annotated, and the annotations resolve.
        import inspect
        import typing
        for cls in (mica.World, mica.Body, mica.Tool, mica.Lpc, mica.Device, mica.PositionsView, mica.DeviceBackend):
            for name, fn in inspect.getmembers(cls, inspect.isfunction):
                if name.startswith("_") and name not in ("__init__", "__getitem__", "__len__", "__array__"):
                    continue
                if name in ("min", "max", "mean", "sum"):  # numpy's signatures, forwarded
                    continue
                hints = typing.get_type_hints(fn, vars(mica))
                self.assertIn("return", hints, "%s.%s has no return annotation" % (cls.__name__, name))
        self.assertIs(typing.get_type_hints(mica.World.create_box, vars(mica))["return"], mica.Body)

    def test_positions_view_raises_once_invalid(self):
        world = mica.World()
        body = world.create_box((0, 0, 0), (1, 1, 1), (2, 2, 2))
        other = world.create_box((2, 0, 0), (3, 1, 1), (2, 2, 2))
        view = body.positions
        world.step(0.01)
        self.assertFalse(view.valid)
        for read in (lambda: view[0], lambda: np.asarray(view), lambda: view.max(), lambda: view.copy()):
            with self.assertRaises(mica.MicaError) as caught:
                read()
            self.assertEqual(caught.exception.status, mica.MICA_ERR_WRONG_STATE)
            self.assertIn("take body.positions again", str(caught.exception))
        view = other.positions
        body.destroy()
        with self.assertRaises(mica.MicaError):
            view[0]
        view = other.positions
        self.assertTrue(view.valid)
        world.close()  # the world's memory is freed: the view must not read it
        self.assertFalse(view.valid)
        with self.assertRaises(mica.MicaError) as caught:
            view[:, 1].max()
        self.assertEqual(caught.exception.status, mica.MICA_ERR_WRONG_STATE)
        self.assertIn("closed", str(caught.exception))
        self.assertIn("invalid", repr(view))

    def test_constraints_and_grab(self):
        with mica.World(gravity=(0, 0, 0)) as world:
            body = world.create_box((0, 0, 0), (1, 1, 1), (2, 2, 2))
            bottom = body.select_nodes_by_plane((0, 0, 0), (0, 1, 0))
            lpc = body.add_lpc(bottom)
            np.testing.assert_array_equal(np.sort(lpc.nodes()), np.sort(bottom))
            grab = body.grab((0.5, 1, 0.5), 0.3)
            grab.set_handle_pose((0.5, 1.1, 0.5))
            world.step(0.01)
            self.assertLess(grab.reaction()[1], 0, "pulling up: the hand feels a downward force")
            grab.remove()
            self.assertEqual(len(body.surface()), body.counts()[2])
            tool = world.create_tool(position=(1, 2, 3))
            position, orientation = tool.pose()
            self.assertEqual(list(position), [1, 2, 3])
            self.assertEqual(list(orientation), [1, 0, 0, 0])

    def test_node_state_save_restore_and_contacts(self):
        def scene():
            world = mica.World(gravity=(0, -9.81, 0))
            body = world.create_box((0, 0, 0), (0.1, 0.1, 0.1), (3, 3, 3), youngs_modulus=2e4)
            body.add_lpc(body.select_nodes_by_plane((0, 0, 0), (0, 1, 0)))
            tool = world.create_tool(radius=0.02, position=(0.05, 0.1205, 0.05), friction=0.3)
            return world, body, tool

        def run(world, body, tool, first, steps):
            xs, fs = [], []
            for k in range(first, first + steps):
                tool.set_pose((0.05 + 0.0002 * k, 0.1205 - 0.0002 * min(k, 20), 0.05), (1, 0, 0, 0))
                world.step(0.01)
                xs.append(body.get_positions())
                fs.append(np.array(tool.force()[0]))
            return np.array(xs), np.array(fs)

        world, body, tool = scene()
        with world:
            # Set and read back.
            x = body.rest_positions() + 1e-4
            body.set_positions(x)
            np.testing.assert_array_equal(body.get_positions(), x)
            v = np.full_like(x, 0.001)
            body.set_velocities(v)
            np.testing.assert_array_equal(body.velocities(), v)
            body.set_positions(body.rest_positions())
            body.set_velocities(np.zeros_like(x))
            with self.assertRaises(mica.MicaError) as caught:
                body.set_positions(x[:-1])
            self.assertEqual(caught.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            # Save, run, restore, run again: the same bits.
            run(world, body, tool, 0, 15)
            state = world.save_state()
            xa, fa = run(world, body, tool, 15, 15)
            world.restore_state(state)
            xb, fb = run(world, body, tool, 15, 15)
            self.assertEqual(xa.tobytes(), xb.tobytes())
            self.assertEqual(fa.tobytes(), fb.tobytes())
            self.assertGreater(fa[-1][1], 0, "the tool is pressing")
            # The contacts add up to the tool force.
            impulse = np.zeros(3)
            for c in world.contacts():
                self.assertEqual(c.other_kind, mica.MICA_CONTACT_OTHER_TOOL)
                impulse += (np.array(c.normal) * c.normal_impulse + np.array(c.tangent_impulse)
                            + np.array(c.curvature_impulse))
            np.testing.assert_allclose(impulse / 0.01, -fb[-1], rtol=1e-12, atol=1e-12 * np.abs(fb[-1]).sum())
            # A truncated state is refused.
            with self.assertRaises(mica.MicaError) as caught:
                world.restore_state(state[:-1])
            self.assertEqual(caught.exception.status, mica.MICA_ERR_PARSE)

    def test_regions_materials_and_fields(self):
        # A box held on a uniform stretch eps along x, nu = 0: strain (eps, 0...) and von Mises
        # E eps in every tet; node masses sum to density x volume; doubling E doubles the stress.
        eps, E, rho = 1e-3, 2e4, 1100
        with mica.World(gravity=(0, 0, 0)) as world:
            body = world.create_box((0, 0, 0), (0.1, 0.05, 0.05), (2, 1, 1), 5, youngs_modulus=E,
                                    poisson_ratio=0, density=rho)
            nodes, tets, _ = body.counts()
            self.assertEqual(body.tets().shape, (tets, 4))
            self.assertTrue(np.all(body.tet_regions() == 0))
            self.assertAlmostEqual(body.node_masses().sum(), rho * 0.1 * 0.05 * 0.05, delta=1e-15)
            rest = body.rest_positions()
            lpc = body.add_lpc(np.arange(nodes))
            lpc.set_targets(rest * (1 + eps, 1, 1))
            world.step(0.01)
            strains = body.strains()
            self.assertEqual(strains.shape, (tets, 6))
            np.testing.assert_allclose(strains, np.tile([eps, 0, 0, 0, 0, 0], (tets, 1)), atol=1e-12)
            np.testing.assert_allclose(body.von_mises(), E * eps, rtol=1e-9)
            body.set_materials(youngs_modulus=np.full(tets, 2 * E))
            np.testing.assert_allclose(body.von_mises(), 2 * E * eps, rtol=1e-9)
            with self.assertRaises(ValueError):
                body.set_materials(density=[rho])
            bad = np.full(tets, rho)
            bad[3] = -1
            with self.assertRaises(mica.MicaError) as e:
                body.set_materials(density=bad)
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            self.assertIn("tet 3", e.exception.message)
            data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
            cube = world.create_body_from_file(os.path.join(data, "two_regions_v41.msh"), translation=(2, 0, 0))
            self.assertEqual(list(cube.tet_regions()), [7, 7, 7, 9, 9, 0])

    def test_remove_tets(self):
        # Resection: the second cell of a bar goes; its mass is returned and the version bumped.
        rho = 1000
        with mica.World(gravity=(0, 0, 0)) as world:
            body = world.create_box((0, 0, 0), (0.2, 0.1, 0.1), (2, 1, 1), 5, density=rho)
            nodes, tets, _ = body.counts()
            self.assertEqual(body.topology_version(), 0)
            removed = body.remove_tets(np.arange(5, 10))
            self.assertAlmostEqual(removed, rho * 0.1 * 0.1 * 0.1, delta=1e-12)
            self.assertEqual(body.counts()[:2], (nodes - 4, tets - 5))
            self.assertEqual(body.topology_version(), 1)
            with self.assertRaises(mica.MicaError) as e:
                body.remove_tets([0, 0])
            self.assertIn("listed twice", e.exception.message)

    def test_cut(self):
        # Incision: a 4 x 2 x 2 cell box cut through x = 0.02 (two triangles covering the section)
        # gets a copy of each of the section's 3 x 3 nodes; the mass stays, the version is bumped.
        with mica.World(gravity=(0, 0, 0)) as world:
            body = world.create_box((0, 0, 0), (0.04, 0.02, 0.02), (4, 2, 2), 5)
            nodes, tets, _ = body.counts()
            mass = body.node_masses().sum()
            x, y0, y1, z0, z1 = 0.02, -0.01, 0.03, -0.01, 0.03
            section = [[(x, y0, z0), (x, y1, z0), (x, y1, z1)], [(x, y0, z0), (x, y1, z1), (x, y0, z1)]]
            self.assertEqual(body.cut([]), (0, 0), "no triangles: nothing cut")
            self.assertEqual(body.topology_version(), 0)
            faces, added = body.cut(section)
            self.assertEqual((faces, added), (2 * 2 * 2, 3 * 3))
            self.assertEqual(body.counts()[:2], (nodes + 9, tets))
            self.assertEqual(body.topology_version(), 1)
            self.assertLessEqual(abs(body.node_masses().sum() - mass), 1e-12 * mass)
            # A cut along the same faces again separates nothing more (flat rows of 9 this time).
            self.assertEqual(body.cut(np.reshape(section, (2, 9)))[1], 0)
            self.assertEqual(body.topology_version(), 1)
            with self.assertRaises(ValueError) as e:
                body.cut(np.zeros((2, 3, 2)))
            self.assertEqual(str(e.exception), "cut triangles: expected rows of 3 corners (k, 3, 3) or of 9 values, "
                                               "got an array of shape (2, 3, 2)")
            with self.assertRaises(ValueError):
                body.cut(np.zeros(10))
            bad = np.array(section, dtype=np.float64)
            bad[1, 2, 0] = np.nan
            with self.assertRaises(mica.MicaError) as e:
                body.cut(bad)
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            self.assertIn("triangle 1", e.exception.message)
            self.assertEqual(body.topology_version(), 1, "a refused cut changes nothing")

    def test_cutting_resistance_and_blades(self):
        self.assertEqual(mica.body_def().cutting_resistance, 200.0)
        self.assertEqual(mica.tool_def().blade, 0)
        with mica.World(gravity=(0, 0, 0)) as world:
            body = world.create_box((0, 0, 0), (0.04, 0.02, 0.02), (4, 2, 2), 5, cutting_resistance=350)
            tets = body.counts()[1]
            body.set_cutting_resistance(np.full(tets, 500.0))
            with self.assertRaises(ValueError) as e:
                body.set_cutting_resistance([500.0])
            self.assertEqual(str(e.exception), "cutting_resistance: one value per tet (%d), got 1" % tets)
            bad = np.full(tets, 500.0)
            bad[7] = -1
            with self.assertRaises(mica.MicaError) as e:
                body.set_cutting_resistance(bad)
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            self.assertIn("tet 7", e.exception.message)
            with self.assertRaises(mica.MicaError) as e:
                world.create_box((1, 0, 0), (1.04, 0.02, 0.02), (4, 2, 2), 5, cutting_resistance=-1)
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            self.assertIn("cutting_resistance", e.exception.message)
            # A blade is a capsule: accepted as one, refused as a sphere (no tool made).
            blade = world.create_tool(shape=mica.MICA_TOOL_CAPSULE, radius=0.0005, half_length=0.02, blade=1,
                                      position=(0.02, 0.05, 0.01))
            self.assertEqual(world.ids(mica.MICA_OBJECT_TOOL), [blade.id])
            with self.assertRaises(mica.MicaError) as e:
                world.create_tool(shape=mica.MICA_TOOL_SPHERE, radius=0.01, blade=1)
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)
            self.assertIn("blade", e.exception.message)
            self.assertEqual(world.ids(mica.MICA_OBJECT_TOOL), [blade.id])
            world.step(0.01)  # the blade above the body: nothing to cut
            self.assertEqual(body.topology_version(), 0)

    def test_library_found_next_to_the_build_tree(self):
        # The package copied into <build>/bindings/python finds <build>/libmica without help.
        pkg = os.path.join(os.environ["MICA_BINDINGS_BUILD_DIR"], "python")
        env = {k: v for k, v in os.environ.items() if k not in ("MICA_LIBRARY", "LD_LIBRARY_PATH")}
        env["PYTHONPATH"] = pkg
        r = subprocess.run([sys.executable, "-c", "import mica; print(mica.native.path)"], env=env,
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        build = os.path.dirname(os.environ["MICA_BINDINGS_BUILD_DIR"])
        self.assertEqual(os.path.realpath(r.stdout.strip()), os.path.realpath(os.path.join(build, "libmica.so.0")))


class Recording(unittest.TestCase):
    """World.record_start/record_stop, World.ids and Replay: a recorded session replays bit for bit."""

    STEPS, DT = 20, 0.01

    def record(self, path):
        """A box on a fixed base pressed by a sphere, recorded: (ids, forces, positions) per step."""
        with mica.World(gravity=(0, -9.81, 0)) as world:
            world.record_start(path)
            with self.assertRaises(mica.MicaError) as caught:
                world.record_start(path)
            self.assertEqual(caught.exception.status, mica.MICA_ERR_WRONG_STATE, "already recording")
            body = world.create_box((0, 0, 0), (0.1, 0.1, 0.1), (3, 3, 3), youngs_modulus=2e4)
            lpc = body.add_lpc(body.select_nodes_by_plane((0, 0, 0), (0, 1, 0)))
            tool = world.create_tool(radius=0.02, position=(0.05, 0.1205, 0.05))
            ids = {mica.MICA_OBJECT_BODY: [body.id], mica.MICA_OBJECT_LPC: [lpc.id],
                   mica.MICA_OBJECT_TOOL: [tool.id], mica.MICA_OBJECT_DEVICE: []}
            for kind, expected in ids.items():
                self.assertEqual(world.ids(kind), expected, "the ids of kind %d are the created ones" % kind)
            forces, positions = [], []
            for k in range(1, self.STEPS + 1):
                tool.set_pose((0.05, 0.1205 - 0.0003 * k, 0.05))  # 6 mm down over the session
                world.step(self.DT)
                forces.append(tool.force()[0])
                positions.append(body.get_positions())
            world.record_stop()
            with self.assertRaises(mica.MicaError) as caught:
                world.record_stop()
            self.assertEqual(caught.exception.status, mica.MICA_ERR_WRONG_STATE, "not recording")
        self.assertGreater(forces[-1][1], 0, "the tool is pressing")
        return ids, np.array(forces), np.array(positions)

    def test_replay_is_bit_for_bit(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "session.micarec")
            ids, forces, positions = self.record(path)
            with mica.Replay(path) as replay:
                world = replay.world
                self.assertEqual(world.ids(mica.MICA_OBJECT_BODY), [], "the recorded calls come with the steps")
                got_forces, got_positions = [], []
                while replay.step():
                    if not got_forces:  # the first step made the recorded creations
                        for kind, expected in ids.items():
                            self.assertEqual(world.ids(kind), expected, "the replay's ids are the recorded ones")
                        body = mica.Body(world, world.ids(mica.MICA_OBJECT_BODY)[0])
                        tool = mica.Tool(world, world.ids(mica.MICA_OBJECT_TOOL)[0])
                    got_forces.append(tool.force()[0])
                    got_positions.append(body.get_positions())
                world.close()  # the replay's world is the replay's: this does not destroy it
                self.assertFalse(world.closed)
                self.assertEqual(len(got_forces), self.STEPS, "the step count")
                self.assertEqual(np.array(got_forces).tobytes(), forces.tobytes(), "tool forces")
                self.assertEqual(np.array(got_positions).tobytes(), positions.tobytes(), "positions")
                self.assertFalse(replay.step(), "the end stays the end")
            self.assertTrue(replay.closed)
            self.assertTrue(world.closed, "closing the replay closes its world")
            with self.assertRaises(mica.MicaError):
                world.ids(mica.MICA_OBJECT_BODY)

    def test_a_changed_fingerprint_diverges_at_its_step(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "session.micarec")
            self.record(path)
            # The file ends with the last step's fingerprint, then the end entry (24 bytes).
            with open(path, "r+b") as f:
                f.seek(-25, os.SEEK_END)
                last = f.read(1)[0]
                f.seek(-25, os.SEEK_END)
                f.write(bytes([last ^ 1]))
            with mica.Replay(path) as replay:
                steps = 0
                with self.assertRaises(mica.MicaError) as caught:
                    while replay.step():
                        steps += 1
                self.assertEqual(caught.exception.status, mica.MICA_ERR_DIVERGED)
                self.assertEqual(steps, self.STEPS - 1, "the steps before the last replay")
                self.assertIn("step %d" % self.STEPS, caught.exception.message)
            with self.assertRaises(mica.MicaError) as caught:
                mica.Replay(os.path.join(tmp, "missing.micarec"))
            self.assertEqual(caught.exception.status, mica.MICA_ERR_IO)


class Recorder(mica.DeviceBackend):
    """A device implemented in Python: a stylus held at `position`, recording the forces."""

    def __init__(self, position):
        self.position = position
        self.opened = self.closed = 0
        self.reads = 0
        self.forces = []

    def open(self):
        self.opened += 1

    def close(self):
        self.closed += 1

    def info(self, out):
        out.name = b"python stylus"
        out.max_force = 5.0

    def read_state(self, state):
        self.reads += 1
        state.position[:] = self.position
        state.orientation[:] = (1, 0, 0, 0)
        state.timestamp = self.reads * 0.001

    def write_force(self, force, torque):
        self.forces.append(force)


@unittest.skipIf("mica_device_create" in native.missing, "the loaded libmica has no device functions yet")
class Devices(unittest.TestCase):
    def test_python_backend(self):
        with mica.World(gravity=(0, 0, 0), solver=mica.MICA_SOLVER_MICA) as world:
            world.create_box((-0.05, 0, -0.05), (0.05, 0.1, 0.05), (4, 4, 4))
            tool = world.create_tool(radius=0.02, position=(0, 0.2, 0))
            backend = Recorder((0, 0.115, 0))
            device = world.create_device(backend=backend, tool=tool)
            self.assertEqual(backend.opened, 1)
            self.assertEqual(device.info().name, b"python stylus")
            state, force = device.poll()
            self.assertEqual(state.position[:], [0, 0.115, 0])
            self.assertEqual(backend.forces[-1], tuple(force))
            world.step(0.01)
            for _ in range(5):
                state, force = device.poll()
            self.assertGreaterEqual(backend.reads, 6, "a read per poll")
            self.assertEqual(backend.forces[-1], tuple(force))
            self.assertTrue(np.all(np.isfinite(force)))
            self.assertEqual(device.stats().polls, 6)
            device.destroy()
            self.assertEqual(backend.closed, 1)
            self.assertIsNone(backend.error)

    def test_device_drives_a_grasp(self):
        # Since 0.6 (mica_device_def.lpc): a stylus held 5 mm above a grab on the top face lifts it;
        # the device renders the grasp's reaction, the force on the hand: down, toward the tissue,
        # against the fixed base's up.
        with mica.World(gravity=(0, 0, 0), solver=mica.MICA_SOLVER_MICA) as world:
            body = world.create_box((-0.05, 0, -0.05), (0.05, 0.1, 0.05), (4, 4, 4))
            base = body.add_lpc(body.select_nodes_by_plane((0, 0, 0), (0, 1, 0)))
            grasp = body.grab((0, 0.1, 0), 0.001)
            backend = Recorder((0, 0.105, 0))
            device = world.create_device(backend=backend, grasp=grasp)
            self.assertEqual(native.mica_device_def().lpc, 0)
            for _ in range(20):
                device.poll()
                world.step(0.01)
            state, force = device.poll()
            reaction = grasp.reaction()
            self.assertLess(reaction[1], 0)
            self.assertLess(force[1], 0)
            self.assertAlmostEqual(base.reaction()[1], -reaction[1], delta=0.05 * abs(reaction[1]))
            with self.assertRaises(mica.MicaError) as e:
                grasp.remove()
            self.assertEqual(e.exception.status, mica.MICA_ERR_WRONG_STATE)
            device.destroy()
            grasp.remove()
            # A device drives a tool or a grasp, not both.
            tool = world.create_tool(radius=0.01, position=(0, 0.3, 0))
            other = body.grab((0.025, 0.1, 0), 0.01)
            with self.assertRaises(mica.MicaError) as e:
                world.create_device(tool=tool, grasp=other)
            self.assertEqual(e.exception.status, mica.MICA_ERR_INVALID_ARGUMENT)

    def test_failing_backend_sends_zero(self):
        class Broken(Recorder):
            def read_state(self, state):
                raise IOError("unplugged")

        with mica.World() as world:
            tool = world.create_tool()
            backend = Broken((0, 0, 0))
            device = world.create_device(backend=backend, tool=tool)
            with self.assertRaises(mica.MicaError) as e:
                device.poll()
            self.assertEqual(e.exception.status, mica.MICA_ERR_DEVICE)
            self.assertIsInstance(backend.error, IOError)


if __name__ == "__main__":
    sys.stdout.reconfigure(line_buffering=True)
    result = unittest.main(verbosity=2, exit=False).result
    sys.exit(0 if result.wasSuccessful() else 1)
