#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plots the cantilever demo's tip deflection over time against the static beam estimate."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path: str, png_path: str) -> None:
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t_s"]) for r in rows]
    w = [1000 * float(r["tip_deflection_m"]) for r in rows]
    w_eb = 1000 * float(rows[0]["euler_bernoulli_m"])
    fig, ax = plt.subplots(figsize=(7, 4), dpi=120)
    ax.plot(t, w, label="libmica, co-rotational FEM (tip, mean over the end face)")
    ax.axhline(w_eb, color="k", ls="--", lw=1, label="static Euler-Bernoulli estimate $qL^4/8EI$")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("tip deflection (mm)")
    ax.set_title("A block clamped at one end sags under its own weight")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(png_path)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
