#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Makes data/nidus/nidus.msh: a lesion-like irregular blob (the scale of an AVM nidus, about
3.5 cm across) meshed with linear tetrahedra, in the size of the nidus scene of Arikatla et al.
2016 (9667 tets, 2734 nodes, 8202 DOF).

The blob is star-shaped about the origin: a point p is inside when |p / axes| < rho(u), u the
direction of p / axes, with rho a unit sphere pushed out into six lobes (max(0, u.d)^3 bumps)
and rippled by two low-order trigonometric terms. The mesh is a regular grid of cubes of side
SPACING, each cut into 5 tetrahedra (the cut alternates with the cell parity, so faces match);
a tetrahedron is kept when at least 3 of its 4 corners are inside, only the largest
face-connected piece is kept, and then every surface node is moved along its ray from the
origin onto the blob's surface (rho), by less where a full move would flatten one of its
tetrahedra below a quarter of its grid volume. No random numbers, no external tools: the same
Python gives the same file, byte for byte (the coordinates are written rounded to 1 nm).

usage: make_nidus.py [output.msh]          (default: nidus.msh beside this script)
       make_nidus.py --search              (prints the counts for nearby scales: how SCALE was chosen)
"""
import math
import os
import sys

SPACING = 0.0015  # m, grid cube side
SCALE = 9.07      # blob size in grid cells (semi-axis along x before lobes): 9668 tets, 2736 nodes
AXES = (1.0, 0.6, 0.45)
LOBES = [  # (amplitude, direction): bumps max(0, u.d)^3
    (0.60, (0.8, 0.5, 0.3)), (0.44, (-0.6, 0.7, -0.2)), (0.50, (-0.3, -0.8, 0.5)),
    (0.36, (0.2, -0.3, -0.9)), (0.40, (-0.9, -0.1, 0.4)), (0.30, (0.4, 0.9, -0.6)),
]
RIPPLE = (0.25, 0.35)
MIN_VOLUME_FRACTION = 0.25  # of the grid tet's volume, after the surface nodes move


def _unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


LOBES = [(a, _unit(d)) for a, d in LOBES]

# The 5-tet cuts of a cube (corner index = x + 2 y + 4 z), for even and odd cells.
CUT_EVEN = [(0, 3, 5, 6), (1, 0, 3, 5), (2, 0, 6, 3), (4, 0, 5, 6), (7, 3, 6, 5)]
CUT_ODD = [(1, 2, 4, 7), (0, 1, 4, 2), (3, 1, 2, 7), (5, 1, 7, 4), (6, 2, 4, 7)]


def radius(u):
    """The blob's radius (in scaled units) in unit direction u."""
    rho = 1.0
    for a, d in LOBES:
        c = u[0] * d[0] + u[1] * d[1] + u[2] * d[2]
        if c > 0:
            rho += a * c * c * c
    rho += RIPPLE[0] * math.sin(5 * u[0] + 1.0) * math.cos(4 * u[1] - 0.5) * math.sin(3 * u[2] + 0.7)
    rho += RIPPLE[1] * math.sin(9 * u[0] - 0.3) * math.sin(8 * u[1] + 1.1) * math.cos(7 * u[2] + 0.4)
    return rho


def scaled(p, scale):
    return tuple(p[i] / (scale * SPACING * AXES[i]) for i in range(3))


def inside(p, scale):
    q = scaled(p, scale)
    r = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
    return r == 0 or r < radius((q[0] / r, q[1] / r, q[2] / r))


def on_surface(p, scale):
    """p moved along its ray from the origin onto the blob's surface."""
    q = scaled(p, scale)
    r = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2])
    f = radius((q[0] / r, q[1] / r, q[2] / r)) / r
    return tuple(c * f for c in p)


def volume(a, b, c, d):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    w = [d[i] - a[i] for i in range(3)]
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0


def build(scale):
    n = int(math.ceil(2.2 * scale)) + 2  # cells from the origin to the grid's edge
    flags = {}

    def node_inside(key):
        if key not in flags:
            flags[key] = inside(tuple((key[a] - n) * SPACING for a in range(3)), scale)
        return flags[key]

    tets = []
    for i in range(2 * n):
        for j in range(2 * n):
            for k in range(2 * n):
                corner = [(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)) for c in range(8)]
                for t in (CUT_EVEN if (i + j + k) % 2 == 0 else CUT_ODD):
                    keys = [corner[c] for c in t]
                    if sum(node_inside(key) for key in keys) >= 3:
                        tets.append(keys)
    # The largest face-connected piece.
    faces = {}
    for e, t in enumerate(tets):
        for skip in range(4):
            faces.setdefault(tuple(sorted(t[:skip] + t[skip + 1:])), []).append(e)
    neighbours = [[] for _ in tets]
    for owners in faces.values():
        if len(owners) == 2:
            neighbours[owners[0]].append(owners[1])
            neighbours[owners[1]].append(owners[0])
    piece = [-1] * len(tets)
    sizes = []
    for start in range(len(tets)):
        if piece[start] >= 0:
            continue
        piece[start] = len(sizes)
        stack, size = [start], 0
        while stack:
            e = stack.pop()
            size += 1
            for o in neighbours[e]:
                if piece[o] < 0:
                    piece[o] = len(sizes)
                    stack.append(o)
        sizes.append(size)
    biggest = sizes.index(max(sizes))
    tets = [t for e, t in enumerate(tets) if piece[e] == biggest]
    # Number the nodes in grid order (x fastest), as they first appear in that order.
    keys = sorted({key for t in tets for key in t}, key=lambda key: (key[2], key[1], key[0]))
    index = {key: a for a, key in enumerate(keys)}
    nodes = [tuple((key[a] - n) * SPACING for a in range(3)) for key in keys]
    tets = [[index[key] for key in t] for t in tets]
    for t in tets:  # positive volume
        if volume(*(nodes[a] for a in t)) < 0:
            t[2], t[3] = t[3], t[2]
    # Surface nodes onto the blob's surface, backing off where a tet would get too flat.
    counts = {}
    for t in tets:
        for skip in range(4):
            f = tuple(sorted(t[:skip] + t[skip + 1:]))
            counts[f] = counts.get(f, 0) + 1
    surface = sorted({a for f, c in counts.items() if c == 1 for a in f})
    node_tets = [[] for _ in nodes]
    for e, t in enumerate(tets):
        for a in t:
            node_tets[a].append(e)
    v0 = SPACING ** 3 / 6.0  # the smallest grid tet (the corner tets of the 5-tet cut)
    for a in surface:
        target = on_surface(nodes[a], scale)
        old = nodes[a]
        for fraction in (1.0, 0.75, 0.5, 0.25, 0.0):
            nodes[a] = tuple(old[c] + fraction * (target[c] - old[c]) for c in range(3))
            if all(volume(*(nodes[b] for b in tets[e])) > MIN_VOLUME_FRACTION * v0 for e in node_tets[a]):
                break
    nodes = [tuple(round(c, 9) for c in p) for p in nodes]
    return nodes, tets, len(surface)


def write_msh(path, nodes, tets):
    with open(path, "w", newline="\n") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n")
        f.write("$Comment\nnidus: made by data/nidus/make_nidus.py (a lesion-like blob, metres)\n$EndComment\n")
        f.write(f"$Nodes\n{len(nodes)}\n")
        for a, p in enumerate(nodes):
            f.write(f"{a + 1} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f}\n")
        f.write("$EndNodes\n")
        f.write(f"$Elements\n{len(tets)}\n")
        for e, t in enumerate(tets):
            f.write(f"{e + 1} 4 2 1 1 {t[0] + 1} {t[1] + 1} {t[2] + 1} {t[3] + 1}\n")
        f.write("$EndElements\n")


def main(argv):
    if len(argv) > 1 and argv[1] == "--search":
        for s in [SCALE + 0.01 * k for k in range(-8, 9)]:
            nodes, tets, _ = build(s)
            print(f"scale {s:.2f}: {len(tets)} tets, {len(nodes)} nodes "
                  f"(off by {len(tets) - 9667:+d} tets, {len(nodes) - 2734:+d} nodes)")
        return
    path = argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "nidus.msh")
    nodes, tets, surface = build(SCALE)
    write_msh(path, nodes, tets)
    lo = [min(p[c] for p in nodes) for c in range(3)]
    hi = [max(p[c] for p in nodes) for c in range(3)]
    vols = [volume(*(nodes[a] for a in t)) for t in tets]
    print(f"{path}: {len(tets)} tets, {len(nodes)} nodes ({3 * len(nodes)} DOF), {surface} on the surface; "
          f"extent {1e3 * (hi[0] - lo[0]):.1f} x {1e3 * (hi[1] - lo[1]):.1f} x {1e3 * (hi[2] - lo[2]):.1f} mm, "
          f"volume {1e6 * sum(vols):.2f} cm^3, smallest tet {min(vols) / (SPACING ** 3 / 6):.2f} of a grid corner tet")


if __name__ == "__main__":
    main(sys.argv)
