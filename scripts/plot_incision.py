#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Draws an incision (examples_c/incision.c): the force the tissue puts against the blade's cut
along the incision, each cut marked, next to a close-up of the cut body at the end, its surface
coloured by von Mises stress and the faces the cut opened in blue.

usage: plot_incision.py incision.csv incision.vtk out.png [--title text]
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from plot_tissue import read_vtk, surface, to_plot, unit  # noqa: E402


def cut_nodes(vtk, nodes):
    """Which nodes the cut made or split: those with a twin at the same rest position (the VTK's
    positions less its displacements)."""
    with open(vtk) as f:
        tokens = f.read().split()
    at = tokens.index("displacement") + 2
    rest = nodes - np.array(tokens[at:at + 3 * len(nodes)], dtype=float).reshape(-1, 3)
    _, inverse, count = np.unique(np.round(rest, 12), axis=0, return_inverse=True, return_counts=True)
    return count[inverse.ravel()] > 1


def draw_cut(ax, cax, nodes, tets, von_mises, window, elev, azim, split):
    """The body's surface within `window` (lo, hi corners, m), lit, coloured by its tets' stress;
    a face whose three nodes are all `split` (a cut face) in blue."""
    centroid = nodes[tets].mean(axis=1)
    kept = np.flatnonzero(np.all((centroid > window[0]) & (centroid < window[1]), axis=1))
    faces, owner = surface(nodes, tets[kept])
    owner = kept[owner]
    tri = to_plot(nodes[faces])
    normal = unit(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]))
    eye = np.array([np.cos(np.radians(elev)) * np.cos(np.radians(azim)),
                    np.cos(np.radians(elev)) * np.sin(np.radians(azim)), np.sin(np.radians(elev))])
    light = unit(eye + np.array([0, 0, 0.8]))
    front = normal @ eye > 0
    tri, normal, stress = tri[front], normal[front], 1e-3 * von_mises[owner[front]]
    opened = split[faces[front]].all(axis=1)
    norm = matplotlib.colors.Normalize(0, float(np.percentile(stress, 99)))
    cmap = matplotlib.colormaps["YlOrRd"]
    colours = cmap(norm(stress))
    colours[opened] = matplotlib.colors.to_rgba("#3b6fb6")
    colours[:, :3] *= (0.5 + 0.5 * np.clip(normal @ light, 0, 1))[:, None]
    ax.add_collection3d(Poly3DCollection(tri, facecolors=colours, edgecolors=colours, linewidths=0.3))
    lo, hi = to_plot(np.array(window[0])), to_plot(np.array(window[1]))
    lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(hi - lo, zoom=1.2)
    ax.set_proj_type("ortho")
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    bar = plt.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax, extend="max")
    bar.set_label("von Mises stress (kPa), per tet")
    span = hi - lo
    ax.text2D(0.02, 0.02, f"close-up {span[0]:.0f} x {span[1]:.0f} x {span[2]:.0f} mm around the cut; "
              "the faces it opened in blue",
              transform=ax.transAxes, fontsize=8)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv")
    parser.add_argument("vtk")
    parser.add_argument("png")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    with open(args.csv) as f:
        rows = list(csv.DictReader(f))
    tip = np.array([[float(r["tip_x_m"]), float(r["tip_y_m"]), float(r["tip_z_m"])] for r in rows])
    along = np.array([float(r["force_along_N"]) for r in rows])
    version = np.array([int(r["topology_version"]) for r in rows])
    travel = 1e3 * np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(tip, axis=0), axis=1))])
    entry = np.array([r["phase"] == "entry" for r in rows])

    fig = plt.figure(figsize=(13, 5.2))
    grid = fig.add_gridspec(1, 3, width_ratios=[1, 1.25, 0.04], wspace=0.12)
    ax = fig.add_subplot(grid[0])
    ax.plot(travel, along, color="C3", lw=1.2, label="force against the blade's cut")
    cuts = np.flatnonzero(np.diff(version) > 0) + 1
    ax.plot(travel[cuts], along[cuts - 1], "v", color="k", ms=4, label=f"the tissue parts ({len(cuts)} cuts)")
    if entry.any():
        ax.axvspan(0, travel[entry].max(), color="0.92", label="the blade goes in")
    ax.set_xlabel("blade tip travel (mm)")
    ax.set_ylabel("force (N)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)

    nodes, tets, von_mises = read_vtk(args.vtk)
    middle = tip[entry.sum():].mean(axis=0) if (~entry).any() else tip.mean(axis=0)
    half = np.array([0.5 * np.ptp(tip[:, 0]) + 0.01, 0.012, 0.015])
    window = (middle - half, middle + np.array([half[0], 0.01, half[2]]))
    ax3 = fig.add_subplot(grid[1], projection="3d")
    draw_cut(ax3, fig.add_subplot(grid[2]), nodes, tets, von_mises, window, elev=62, azim=-75,
             split=cut_nodes(args.vtk, nodes))
    if args.title:
        fig.suptitle(args.title)
    fig.savefig(args.png, dpi=110, bbox_inches="tight")
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
