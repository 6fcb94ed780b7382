#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the seed corpus of fuzz_api (fuzz/corpus/api/): small programs of C API calls, each a
scene the fuzzer should start from (a press with every solver, a grab, devices that misbehave, a
failed step, loaders, tiny time steps, stale ids). The byte layout mirrors the reader in
fuzz/fuzz_api.cpp; change both together. Run: python3 fuzz/make_api_seeds.py"""
import os
import struct

TABLE = [0.0, -0.0, 1.0, -1.0, 0.5, 0.01, -0.01, 0.05, 0.1, -0.1, 2.0, 10.0, 1e3, 1e6, 1e300, -1e300,
         1e-300, 5e-324, 1.7976931348623157e308, 'nan', 'inf', '-inf', 1e-9, 1e-10, 0.999, 1.0000001,
         1e-3, 0.02, -0.05, 0.001, 1e200, -2.5]


def d(v):
    """A double: the table's entry, else a small value in thousandths, else raw bits."""
    for i, t in enumerate(TABLE):
        if isinstance(v, str) or isinstance(t, str):
            if v == t:
                return bytes([128 + i])
        elif struct.pack('>d', t) == struct.pack('>d', float(v)):
            return bytes([128 + i])
    k = round(v * 1000)
    if -128 <= k <= 127 and k / 1000 == v:
        return bytes([0, k & 0xff])
    return bytes([240]) + struct.pack('>d', float(v))


def u8(v):
    return bytes([v & 0xff])


OPS = dict(box=0, raw=1, file=2, body_destroy=3, forces=4, lpc=5, lpc_remove=6, lpc_velocity=7,
           targets=8, grab=9, handle=10, tool=11, tool_destroy=12, pose=13, step=14, gravity=17,
           device=18, device_destroy=19, poll=20, read=22, select=23, remove_tets=24)


def world(solver=0, sweep=0, refactor=0, iterations=50, gravity=(0, 0, 0), friction=0.0, tol=1e-3):
    b = u8(0) + u8(0)  # struct_size as is, this header's version
    b += d(gravity[0]) + d(gravity[1]) + d(gravity[2])
    b += u8(solver) + u8(iterations) + d(tol) + u8(1) + d(1.0) + u8(1) + d(0.001) + d(friction)
    b += d(1.0) + d(0.0) + u8(sweep) + u8(1) + d(0.001) + u8(8) + u8(refactor)
    return b


def body_def(density=None, static=False):
    flags = (4 if static else 0) | (32 if density is not None else 0)
    b = u8(0) + u8(flags)
    if static:
        b += u8(1)
    if density is not None:
        b += u8(0) + u8(max(0, min(199, int(density / 10) - 1)))  # 10 * (1 + n) kg/m^3
    return b


def box(lo=(-0.05, -0.1, -0.05), cells=(1, 1, 1), per=5, size=0.1, **kw):
    cell_index = {1: 0, 2: 1}
    b = u8(OPS['box']) + body_def(**kw)
    for k in range(3):
        b += d(lo[k]) + u8(0) + u8(min(19, max(0, round((size - 0.005) / 0.005))))  # hi = lo + size
    b += bytes(cell_index[c] for c in cells)
    b += u8(0) + u8(per - 5)
    return b


def pick(index=0):
    return u8(0) + u8(index)


def identity():
    return u8(0) + u8(0) + d(0.0)  # q[0] += 0


def tool(shape=0, position=(0.0, 0.0, 0.0), radius_code=None, friction=None):
    flags = (1 if radius_code is not None else 0) | (4) | (16 if friction is not None else 0)
    b = u8(OPS['tool']) + u8(0) + u8(shape) + u8(flags)
    if radius_code is not None:
        b += u8(radius_code)  # 0.005 + 0.005 code
    b += d(position[0]) + d(position[1]) + d(position[2])
    b += identity()
    if friction is not None:
        b += u8(0) + u8(friction)  # 0.1 * n
    b += u8(0) * 36  # hull points at their defaults
    return b


def pose(position, tool_index=0):
    return u8(OPS['pose']) + pick(tool_index) + d(position[0]) + d(position[1]) + d(position[2]) + identity()


def step(ms=10):
    return u8(OPS['step']) + u8(0) + u8(ms - 1)


def raw_step(dt):
    return u8(OPS['step']) + u8(250) + d(dt)


def device(mode=0, tool_index=0, fail_after=None, info_mode=0, base=(0.0, 0.0, 0.0)):
    b = u8(OPS['device']) + u8(0) + u8(0) + u8(1) + pick(tool_index) + u8(0)
    b += u8(mode)
    b += u8(0) if fail_after is None else u8(250) + u8(fail_after)
    b += u8(0) + u8(info_mode)
    for k in range(3):  # the stylus goes down 0.5 mm per read
        b += d(base[k]) + (u8(0) if k == 1 else u8(250) + d(0.0))
    b += u8(0) + u8(0) + u8(0)  # read_state on both, a table
    return b


def poll(index=0):
    return u8(OPS['poll']) + pick(index) + u8(1) + u8(1)


def grab(center, body_index=0):
    return u8(OPS['grab']) + pick(body_index) + u8(0) + d(center[0]) + d(center[1]) + d(center[2]) + u8(0)


def handle(position, lpc_index=0):
    return u8(OPS['handle']) + pick(lpc_index) + d(position[0]) + d(position[1]) + d(position[2]) + identity()


def lpc_fixed(nodes, body_index=0):
    b = u8(OPS['lpc']) + pick(body_index) + u8(0) + u8(0)
    b += d(1.0) + d(0.0) + d(0.0) + d(0.0) + d(1.0) + d(0.0)
    b += u8(0) * 3 + u8(len(nodes))
    for k in range(6):
        b += u8(0) + u8(nodes[k] if k < len(nodes) else 0)
    return b


def forces(node, f, body_index=0):
    b = u8(OPS['forces']) + pick(body_index) + u8(1)
    b += (u8(0) + u8(node)) * 4
    for k in range(12):
        b += d(f[k % 3] if k < 3 else 0.0)
    return b


def from_file(which):
    return u8(OPS['file']) + body_def() + u8(which)


def raw_duplicate():
    b = u8(OPS['raw']) + body_def() + u8(5) + u8(3)
    b += u8(0) * 36  # the corners of a 5 cm cube
    tets = [0, 1, 2, 4, 1, 3, 2, 4, 0, 1, 2, 4] + [0] * 20  # the first tet twice
    for t in tets:
        b += u8(0) + u8(t)
    b += u8(0) + u8(0)
    return b


def remove_tets(tets, body_index=0, count=None):
    b = u8(OPS['remove_tets']) + pick(body_index) + u8(len(tets) if count is None else count)
    for k in range(6):
        b += u8(0) + u8(tets[k] if k < len(tets) else 0)
    return b + u8(0) + u8(0)  # the tets given, the mass asked for


def destroy_body(index=0):
    return u8(OPS['body_destroy']) + pick(index)


def read(kind, index=0):
    return u8(OPS['read']) + u8(kind) + pick(index) + u8(3) + u8(0) + u8(0)


SEEDS = {
    'press_direct': world(0) + box(cells=(2, 2, 2)) + tool(position=(0.003, 0.008, 0.002)) +
        step() * 2 + pose((0.003, 0.005, 0.002)) + step() * 2,
    'press_pcg_friction': world(1) + box(cells=(2, 2, 2)) + tool(position=(0.003, 0.008, 0.002), friction=5) +
        step() + pose((0.01, 0.006, 0.002)) + step() * 2,
    'press_mica': world(2) + box(cells=(2, 2, 2)) + tool(position=(0.003, 0.008, 0.002)) + step() * 3,
    'factored_failed_step': world(2, sweep=1, refactor=2) + box(cells=(2, 2, 2), density=10) +
        tool(position=(0.003, 0.008, 0.002)) + step() * 2 + forces(13, (1e300, -1e300, 1e300)) + step() +
        forces(13, (0.0, 0.0, 0.0)) + step() * 3,
    'grab_and_drag': world(2) + box(cells=(2, 2, 2)) + grab((0.0, 0.0, 0.0)) + handle((0.0, 0.02, 0.0)) + step() * 3,
    'fixed_and_gravity': world(0, gravity=(0.0, -2.5, 0.0)) + box() + lpc_fixed([0, 1, 2, 3]) + step() * 2 +
        read(0) + read(1) + read(2),
    'device_press': world(2) + box(cells=(2, 2, 2)) + tool(position=(0.003, 0.01, 0.002)) + device(0) +
        (poll() + step()) * 4,
    'device_non_unit': world(0) + box() + tool(position=(0.0, 0.01, 0.0)) + device(2) + (poll() + step()) * 2,
    'device_nan_and_failing': world(2) + box() + tool(position=(0.0, 0.01, 0.0)) + device(1, fail_after=6) +
        (poll() + poll() + step()) * 3,
    'device_absurd_figures': world(2) + box() + tool(position=(0.0, 0.01, 0.0)) + device(0, info_mode=2) +
        device(6, info_mode=1) + poll() + step(),
    'duplicate_tets': world(0) + raw_duplicate() + box() + step(),
    'loaders': world(0) + from_file(0) + from_file(1) + from_file(2) + from_file(3) + from_file(4) +
        from_file(5) + step(),
    'tiny_steps': world(0) + box() + tool(position=(0.0, 0.008, 0.0)) + step() + raw_step(1e-10) +
        raw_step(5e-324) + raw_step(1e-9) + step(),
    'two_bodies': world(0) + box(cells=(1, 1, 1)) + box(lo=(-0.04, -0.005, -0.04), size=0.05) + step() * 3,
    'remove_tets': world(2, gravity=(0.0, -9.81, 0.0)) + box(cells=(2, 2, 2)) + lpc_fixed([0, 1, 2, 3]) +
        grab((0.0, 0.0, 0.0)) + step() + remove_tets([39, 38, 37]) + step() + remove_tets([5, 5]) +
        remove_tets([43]) + remove_tets([0, 1, 2, 3, 4, 6]) + step() * 2 + read(0),
    'stale_ids': world(2) + box() + tool() + destroy_body() + destroy_body() + step() + read(0) +
        u8(OPS['tool_destroy']) + pick(0) + pose((0.0, 0.0, 0.0)),
}


def main():
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'corpus', 'api')
    os.makedirs(out, exist_ok=True)
    for name, data in SEEDS.items():
        with open(os.path.join(out, name), 'wb') as f:
            f.write(data)
    print(f'{len(SEEDS)} seeds in {out}')


if __name__ == '__main__':
    main()
