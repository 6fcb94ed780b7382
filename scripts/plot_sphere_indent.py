#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plots the sphere-indentation demo: tool force over time, and force against depth
(loading and unloading) with the Hertz half-space estimate for orientation.

usage: plot_sphere_indent.py sphere_indent.csv sphere_indent.png [E_Pa nu R_m]
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PHASE_COLOURS = {"load": "tab:red", "hold": "tab:purple", "unload": "tab:blue", "clear": "tab:gray"}


def main(csv_path: str, png_path: str, E: float = 1e4, nu: float = 0.4, R: float = 0.02) -> None:
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t_s"]) for r in rows]
    depth_mm = [1000 * float(r["depth_m"]) for r in rows]
    force = [float(r["force_y_N"]) for r in rows]
    phase = [r["phase"] for r in rows]

    fig, (ax_t, ax_d) = plt.subplots(1, 2, figsize=(12, 4.5), dpi=110)

    # Left: force and depth over time, the phases shaded.
    ax_t.plot(t, force, color="k", lw=1.5, label="tool force $F_y$ (tissue pushes sphere up)")
    ax_t.set_xlabel("time (s)")
    ax_t.set_ylabel("indentation force $F_y$ (N)")
    ax_t.grid(alpha=0.3)
    start = 0
    for k in range(1, len(rows) + 1):
        if k == len(rows) or phase[k] != phase[start]:
            ax_t.axvspan(t[start], t[k - 1], color=PHASE_COLOURS.get(phase[start], "w"), alpha=0.08, lw=0)
            ax_t.text((t[start] + t[k - 1]) / 2, 1.0, phase[start], transform=ax_t.get_xaxis_transform(),
                      ha="center", va="bottom", fontsize=8, color=PHASE_COLOURS.get(phase[start], "k"))
            start = k
    ax_depth = ax_t.twinx()
    ax_depth.plot(t, depth_mm, color="tab:orange", lw=1, ls="--", label="sphere depth below the top face")
    ax_depth.set_ylabel("sphere depth (mm)", color="tab:orange")
    lines = ax_t.get_lines() + ax_depth.get_lines()
    ax_t.legend(lines, [ln.get_label() for ln in lines], loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2,
                fontsize=8, frameon=False)
    ax_t.set_title("Force over time", pad=14)

    # Right: force against depth, loading and unloading separately.
    for name, colour in (("load", "tab:red"), ("hold", "tab:purple"), ("unload", "tab:blue")):
        d = [depth_mm[k] for k in range(len(rows)) if phase[k] == name]
        f = [force[k] for k in range(len(rows)) if phase[k] == name]
        if d:
            ax_d.plot(d, f, marker="o", ms=2.5, lw=1, color=colour,
                      label={"load": "loading (moving down)", "hold": "hold",
                             "unload": "unloading (moving up)"}[name])
    d_max = max(depth_mm)
    ds = [d_max * i / 100 for i in range(101)]
    E_star = E / (1 - nu * nu)
    hertz = [4.0 / 3.0 * E_star * R ** 0.5 * (d / 1000) ** 1.5 for d in ds]
    ax_d.plot(ds, hertz, color="k", ls=":", lw=1.2,
              label=f"Hertz half-space $\\frac{{4}}{{3}}\\frac{{E}}{{1-\\nu^2}}\\sqrt{{R}}\\,d^{{3/2}}$"
                    f" (E={E:g} Pa, $\\nu$={nu:g}, R={1000 * R:g} mm)")
    ax_d.set_xlabel("sphere depth below the undeformed top face (mm)")
    ax_d.set_ylabel("indentation force $F_y$ (N)")
    ax_d.set_xlim(left=min(0.0, min(depth_mm)))
    ax_d.grid(alpha=0.3)
    ax_d.legend(loc="upper left", fontsize=8)
    ax_d.set_title("Force against depth", pad=14)

    fig.suptitle("A sphere indents a soft cube fixed at its base (libmica, MICA solver)")
    fig.tight_layout()
    fig.savefig(png_path)


if __name__ == "__main__":
    extra = [float(a) for a in sys.argv[3:6]]
    main(sys.argv[1], sys.argv[2], *extra)
