#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plots the two-hands example: each hand's rendered force over time (servo thread, after the
filter and the safety limits) against the force of the simulation step it follows (the grasp's
reaction for hand 1, the sphere's tool force for hand 2).

usage: plot_two_hands.py two_hands.csv two_hands.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path: str, png_path: str) -> None:
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{csv_path}: no rows")
    t = [float(r["t_s"]) for r in rows]

    def col(name: str) -> list:
        return [float(r[name]) for r in rows]

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5), dpi=110, sharex=True)
    ax1.plot(t, col("hand1_fy_N"), color="tab:blue", lw=1.5, label="rendered $F_y$ (servo output, sampled each step)")
    ax1.plot(t, col("grasp_fy_N"), color="tab:blue", lw=1, ls="--", label="grasp reaction $F_y$ (simulation step, 100 Hz)")
    ax1.plot(t, col("hand1_fx_N"), color="tab:orange", lw=1.5, label="rendered $F_x$ (servo output, sampled each step)")
    ax1.plot(t, col("grasp_fx_N"), color="tab:orange", lw=1, ls="--", label="grasp reaction $F_x$ (simulation step, 100 Hz)")
    ax1.set_title("Hand 1: grasps the top face, pulls up and toward -x")
    ax2.plot(t, col("hand2_fy_N"), color="tab:green", lw=1.5, label="rendered $F_y$ (servo output, sampled each step)")
    ax2.plot(t, col("tool_fy_N"), color="tab:green", lw=1, ls="--", label="sphere tool force $F_y$ (simulation step, 100 Hz)")
    ax2.set_title("Hand 2: presses a sphere into the top face")
    for ax in (ax1, ax2):
        ax.axhline(0, color="k", lw=0.5)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("force on the hand (N)")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    fig.suptitle("Two hands on one soft block, each device on its own servo thread (libmica)")
    fig.tight_layout()
    fig.savefig(png_path)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
