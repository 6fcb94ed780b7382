#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plots MICA iterations against stiffness from convergence_vs_stiffness.csv: iterations per
step for each Young's modulus (log y), and the first-step and median counts against E (log-log).

usage: plot_convergence.py convergence_vs_stiffness.csv convergence_vs_stiffness.png
"""
import csv
import statistics
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path: str, png_path: str) -> None:
    runs = OrderedDict()
    with open(csv_path, newline="") as f:
        for r in csv.DictReader(f):
            runs.setdefault(float(r["E_Pa"]), []).append(
                (int(r["step"]), int(r["iterations"]), int(r["converged"])))

    fig, (ax_s, ax_e) = plt.subplots(1, 2, figsize=(12, 4.5), dpi=110)
    colours = plt.cm.viridis([i / max(1, len(runs) - 1) for i in range(len(runs))])
    for (E, rows), colour in zip(runs.items(), colours):
        steps = [s for s, _, _ in rows]
        its = [i for _, i, _ in rows]
        ax_s.plot(steps, its, marker="o", ms=3, lw=1.2, color=colour, label=f"E = {E:.0e} Pa")
        capped = [(s, i) for s, i, c in rows if not c]
        if capped:
            ax_s.plot([s for s, _ in capped], [i for _, i in capped], "x", color="r", ms=7)
    ax_s.set_yscale("log")
    ax_s.set_xlabel("time step (dt = 0.01 s)")
    ax_s.set_ylabel("MICA iterations to tolerance 1e-8")
    ax_s.set_title("Iterations per step (red x: stopped at the cap)")
    ax_s.grid(alpha=0.3, which="both")
    ax_s.legend(fontsize=8)

    Es = list(runs.keys())
    first = [rows[0][1] for rows in runs.values()]
    median = [statistics.median(i for _, i, _ in rows) for rows in runs.values()]
    ax_e.loglog(Es, first, marker="s", lw=1.5, label="first step (cold start: v = 0, $\\lambda$ = 0)")
    ax_e.loglog(Es, median, marker="o", lw=1.5, label="median over the run (warm starts)")
    # Reference slope: iterations proportional to E, through the first point.
    ax_e.loglog(Es, [first[0] * E / Es[0] for E in Es], color="k", ls=":", lw=1,
                label="$\\propto E$ (i.e. $\\propto E h^2 / \\rho\\, dx^2$)")
    ax_e.set_ylim(min(first + median) / 2, max(first + median) * 4)
    ax_e.set_xlabel("Young's modulus E (Pa)")
    ax_e.set_ylabel("MICA iterations per step")
    ax_e.set_title("Iterations against stiffness")
    ax_e.grid(alpha=0.3, which="both")
    ax_e.legend(fontsize=8)

    fig.suptitle("MICA convergence against stiffness: sphere pressing a cube fixed at its base (nu = 0.3)")
    fig.tight_layout()
    fig.savefig(png_path)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
