#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Raw against filtered device force over a press and release (the paper's Figure 1 b and c)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(csv_path: str, png_path: str) -> None:
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    t = [float(r["t_s"]) for r in rows]
    raw = [float(r["raw_force_y_N"]) for r in rows]
    filtered = [float(r["filtered_force_y_N"]) for r in rows]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), dpi=120)
    for ax, (lo, hi), title in ((axes[0], (t[0], t[-1]), "press and release"),
                                (axes[1], (0.0, 0.25), "contact onset (zoom)")):
        ax.plot(t, raw, lw=0.8, color="0.6", label="raw: the step's local model at servo rate")
        ax.plot(t, filtered, lw=1.2, color="C0", label="rendered: moving average N = 20 + onset correction, limits")
        ax.set_xlim(lo, hi)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("force on the stylus, y (N)")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    # Below the panels: inside, it hid the peak of the press.
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8)
    fig.suptitle("1 kHz servo loop against a 60 Hz simulation (libmica haptic_loop)")
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    fig.savefig(png_path)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
