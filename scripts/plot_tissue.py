#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Draws a pressed body as it is: its deformed surface coloured by von Mises stress, lit, with the
sphere that presses it, next to the force the sphere feels against its depth (the moment drawn
marked on the curve).

The body comes from a VTK file of libmica (mica_body_write_vtk / mica_world_write_vtk: nodes, tets,
each tet's "von_mises"); each surface triangle takes the stress of its tet. The CSV is the press's
per-step table (depth_m, force_y_N, the sphere's centre tool_y_m and, if there, tool_x_m, tool_z_m,
tool_radius_m). Either one file (--vtk: the body at the CSV's last row) or numbered frames
(--frames with --every: the frame where the sphere is deepest).

usage: plot_tissue.py steps.csv out.png (--vtk body.vtk | --frames 'dir/name_{:04d}.vtk' --every N)
                      [--cut] [--radius R_m] [--elev deg] [--azim deg] [--title text]
--cut keeps the half of the body behind the vertical plane through the sphere's centre (z below
it), so the dent shows in section.
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

# Each tet face (three corners) with the corner opposite it.
TET_FACES = ((1, 2, 3, 0), (0, 3, 2, 1), (0, 1, 3, 2), (0, 2, 1, 3))


def read_vtk(path):
    """Nodes (n x 3, m), tets (m x 4) and each tet's von Mises stress (Pa) of a legacy ASCII VTK file."""
    with open(path) as f:
        tokens = f.read().split()
    at = tokens.index("POINTS")
    n = int(tokens[at + 1])
    nodes = np.array(tokens[at + 3:at + 3 + 3 * n], dtype=float).reshape(n, 3)
    at = tokens.index("CELLS")
    m = int(tokens[at + 1])
    tets = np.array(tokens[at + 3:at + 3 + 5 * m], dtype=np.int64).reshape(m, 5)[:, 1:]
    at = tokens.index("von_mises")
    at = tokens.index("default", at) + 1
    return nodes, tets, np.array(tokens[at:at + m], dtype=float)


def surface(nodes, tets):
    """The faces of `tets` that no other of them shares, turned outwards, with the tet of each."""
    faces = np.concatenate([tets[:, list(f[:3])] for f in TET_FACES])
    opposite = np.concatenate([tets[:, f[3]] for f in TET_FACES])
    owner = np.tile(np.arange(len(tets)), len(TET_FACES))
    _, first, count = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    once = first[count == 1]
    faces, opposite, owner = faces[once], opposite[once], owner[once]
    a, b, c = (nodes[faces[:, k]] for k in range(3))
    inward = np.einsum("ij,ij->i", np.cross(b - a, c - a), nodes[opposite] - a) > 0
    faces[inward] = faces[inward][:, ::-1]
    return faces, owner


def sphere_mesh(centre, radius, rings=24, segments=48):
    """Triangles (k x 3 x 3) of a sphere, counter-clockwise seen from outside."""
    theta = np.linspace(0, np.pi, rings + 1)
    phi = np.linspace(0, 2 * np.pi, segments + 1)
    p = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.cos(theta)[:, None] * np.ones_like(phi),
                  np.sin(theta)[:, None] * np.sin(phi)], axis=-1) * radius + centre
    quads = []
    for i in range(rings):
        for j in range(segments):
            a, b, c, d = p[i, j], p[i + 1, j], p[i + 1, j + 1], p[i, j + 1]
            quads += [(a, d, c), (a, c, b)]
    return np.array(quads)


def to_plot(v):
    """Simulation frame (y up) to the plot's (z up), turned so that handedness is kept: (x, -z, y), in mm."""
    return 1e3 * np.stack([v[..., 0], -v[..., 2], v[..., 1]], axis=-1)


def unit(v):
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-30)


def draw_body(ax, cax, nodes, tets, von_mises, centre, radius, surface_y, cut, elev, azim):
    kept = np.arange(len(tets))
    if cut:
        kept = kept[nodes[tets].mean(axis=1)[:, 2] < centre[2]]
    faces, owner = surface(nodes, tets[kept])
    owner = kept[owner]
    tri = to_plot(nodes[faces])  # k x 3 corners x 3
    normal = unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    eye = np.array([np.cos(np.radians(elev)) * np.cos(np.radians(azim)),
                    np.cos(np.radians(elev)) * np.sin(np.radians(azim)), np.sin(np.radians(elev))])
    # The light comes from over the viewer's left shoulder, so slopes facing up-left are bright.
    light = unit(eye + np.array([-np.sin(np.radians(azim)), np.cos(np.radians(azim)), 0.0]) * -0.6 +
                 np.array([0, 0, 0.8]))
    front = normal @ eye > 0  # orthographic view: a closed surface's back faces are hidden anyway
    tri, normal, stress = tri[front], normal[front], 1e-3 * von_mises[owner[front]]

    vmax = float(np.percentile(1e-3 * von_mises, 99.5))
    norm = matplotlib.colors.Normalize(0, vmax)
    cmap = matplotlib.colormaps["YlOrRd"]
    shade = 0.55 + 0.45 * np.clip(normal @ light, 0, 1)
    colours = cmap(norm(stress))
    colours[:, :3] *= shade[:, None]

    ball = sphere_mesh(to_plot(np.asarray(centre)), 1e3 * radius)
    if cut:
        ball = ball[ball.mean(axis=1)[:, 1] > -1e3 * centre[2]]
    ball_normal = unit(np.cross(ball[:, 1] - ball[:, 0], ball[:, 2] - ball[:, 0]))
    ball_colours = np.tile([0.45, 0.55, 0.75, 0.2 if cut else 0.3], (len(ball), 1))
    ball_colours[:, :3] *= (0.5 + 0.5 * np.abs(ball_normal @ light))[:, None]

    # Edges in the faces' own colours hide the seams antialiasing leaves between them.
    # (Not the translucent sphere's: they would add up to a wire mesh.)
    face_colours = np.concatenate([colours, ball_colours])
    edge_colours = np.concatenate([colours, np.zeros((len(ball), 4))])
    polys = Poly3DCollection(np.concatenate([tri, ball]), facecolors=face_colours, edgecolors=edge_colours,
                             linewidths=0.3)
    ax.add_collection3d(polys)
    if cut:
        # In the cut plane: the sphere's section, and the level of the undeformed surface above it.
        angle = np.linspace(0, 2 * np.pi, 97)
        c = to_plot(np.asarray(centre))
        ax.plot(c[0] + 1e3 * radius * np.cos(angle), np.full_like(angle, c[1]), c[2] + 1e3 * radius * np.sin(angle),
                color="k", lw=1, zorder=3)
        x = to_plot(nodes)[:, 0]
        ax.plot([x.min(), x.max()], [c[1], c[1]], [1e3 * surface_y] * 2, color="k", ls="--", lw=1, zorder=3)
    lo, hi = to_plot(nodes).min(axis=0), to_plot(nodes).max(axis=0)
    span = hi - lo
    hi[2] = max(hi[2], 1e3 * (centre[1] + radius))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo, zoom=1.25)
    ax.computed_zorder = False  # the lines in the cut plane are drawn over the faces
    ax.set_proj_type("ortho")
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    mappable = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
    bar = plt.colorbar(mappable, cax=cax, extend="max")
    bar.set_label("von Mises stress (kPa), per tet")
    note = f"body {span[0]:.0f} x {span[1]:.0f} x {span[2]:.0f} mm; the sphere (radius {1e3 * radius:.0f} mm) in grey"
    if cut:
        note += ",\nits section in black; dashed: the undeformed top surface"
    ax.text2D(0.04, 0.02, note, transform=ax.transAxes, fontsize=8)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv")
    parser.add_argument("png")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--vtk", help="the body at the CSV's last row")
    source.add_argument("--frames", help="numbered frames, a Python format such as dir/name_{:04d}.vtk")
    parser.add_argument("--every", type=int, default=1, help="CSV rows per frame (frame j is row j * every)")
    parser.add_argument("--cut", action="store_true", help="show the body cut through the sphere's centre")
    parser.add_argument("--radius", type=float, default=0.02, help="sphere radius (m) if the CSV has none")
    parser.add_argument("--elev", type=float, default=25)
    parser.add_argument("--azim", type=float, default=-60)
    parser.add_argument("--title", default="")
    args = parser.parse_args()

    with open(args.csv, newline="") as f:
        rows = list(csv.DictReader(f))
    depth = np.array([1e3 * float(r["depth_m"]) for r in rows])
    force = np.array([float(r["force_y_N"]) for r in rows])
    if args.vtk:
        row, vtk = len(rows) - 1, args.vtk
    else:
        frames = [j for j in range(len(rows) // args.every + 1)
                  if j * args.every < len(rows) and os.path.exists(args.frames.format(j))]
        if not frames:
            parser.error(f"no frame {args.frames} found")
        j = max(frames, key=lambda j: (round(depth[j * args.every], 6), force[j * args.every]))
        row, vtk = j * args.every, args.frames.format(j)
    r = rows[row]
    centre = [float(r.get("tool_x_m", 0)), float(r["tool_y_m"]), float(r.get("tool_z_m", 0))]
    radius = float(r.get("tool_radius_m", args.radius))
    nodes, tets, von_mises = read_vtk(vtk)

    fig = plt.figure(figsize=(12, 5.6), dpi=110)
    ax = fig.add_axes([0.0, 0.03, 0.5, 0.86], projection="3d")
    cax = fig.add_axes([0.5, 0.2, 0.012, 0.6])
    # The undeformed surface under the sphere: its lowest point is `depth` below it.
    surface_y = centre[1] - radius + 1e-3 * depth[row]
    draw_body(ax, cax, nodes, tets, von_mises, centre, radius, surface_y, args.cut, args.elev, args.azim)
    ax.set_title(f"{'Cut through the sphere: ' if args.cut else ''}sphere {depth[row]:.1f} mm deep, "
                 f"force {force[row]:.3g} N")
    ax_f = fig.add_axes([0.63, 0.12, 0.35, 0.74])
    ax_f.plot(depth, force, color="k", lw=1.2, marker="o", ms=2, label="the force on the sphere, each step")
    ax_f.plot([depth[row]], [force[row]], "o", color="tab:red", ms=9, label="the moment drawn on the left")
    ax_f.set_xlabel("sphere depth below the undeformed surface (mm)")
    ax_f.set_ylabel("force on the sphere $F_y$ (N)")
    ax_f.grid(alpha=0.3)
    ax_f.legend(loc="upper left", fontsize=8)
    ax_f.set_title("Force against depth")
    fig.suptitle(args.title)
    fig.savefig(args.png)


if __name__ == "__main__":
    main()
