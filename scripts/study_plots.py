#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Draws the accuracy-against-time study (scripts/study.sh) from the CSVs in its folder, and
writes tables.md (the tables of docs/accuracy-vs-time.md and docs/performance.md). The tables the
docs include are wrapped in <!-- study:begin NAME --> / <!-- study:end NAME --> markers;
scripts/study_docs.py compares them with (or copies them into) the docs.

  error_vs_time.png          position and tool-force error against ms per step, one front per
                             solver and mode (fixed tolerance, fixed iterations), exact as a line
  iterations_vs_tolerance.png iterations and ms per step against the tolerance
  figure2_stiffness.png      MICA iterations per step for E = 1e3 ... 1e7 Pa (nu = 0.3, tol 1e-8),
                             and iterations and ms against E for all three solvers
  figure1_force.png          force during compression and release at the device (1 kHz): raw,
                             filtered with N = 20 and the post-contact correction, and without it;
                             delay and ripple against N
  knobs.png                  the other knobs: time step, mesh, model, mass, PGS sweeps, warm start,
                             stopping norm: error against ms per step
  anchors.png                Hertz and Euler-Bernoulli: error against element size (log-log), and
                             the Hertz force against depth
  material.png               the material axis: uniaxial compression of a cube against the
                             neo-Hookean closed form (stress and error against strain, each
                             model's CPU ms per step), and the press scene's CPU ms per step and
                             difference from the co-rotational body per model and solver
  scaling.png                ms per step, iterations and ms per iteration against tets
and, in tables.md only, the force quality of a held tool and of loading (contact.csv, from
bench/bench_contact.c), and the performance tables (perf-*) from the benchmarks' output the study
keeps as <stage>.txt (nidus, refresh, linear, defaults, factor, factor_omp, servo_idle, servo) with
the commands in commands.txt.

usage: study_plots.py <study-folder>
"""
import csv
import math
import os
import re
import sys
from collections import OrderedDict, defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    if not os.path.exists(path):
        return [], ""
    with open(path, newline="") as f:
        lines = f.readlines()
    comment = "".join(l[1:].strip() for l in lines if l.startswith("#"))
    rows = list(csv.DictReader(l for l in lines if not l.startswith("#")))
    return rows, comment


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def fin(v):
    return not math.isnan(v) and not math.isinf(v)


COLOURS = {"MICA": "tab:blue", "MICA-F": "tab:green", "PCG": "tab:orange", "exact": "k"}


def label_points(ax, labels, fontsize=6):
    """Annotates (x, y, text, colour) points of `ax`, each label moved down (then up) by a line
    until it overlaps no label placed before it: points close together stay readable. Call it
    after the axes' scales and data are final (it reads their limits)."""
    ax.figure.canvas.draw()  # the final limits, so data maps to display coordinates
    pt = ax.figure.dpi / 72  # display pixels per point
    line, placed = fontsize + 1.5, []
    for x, y, text, colour in sorted(labels, key=lambda l: (l[0], -l[1])):
        px, py = ax.transData.transform((x, y)) / pt  # in points
        width = 0.55 * fontsize * len(text)
        for shift in [0] + [s * k * line for k in range(1, 8) for s in (-1, 1)]:
            box = (px + 3, py + 2 + shift, width, line)
            if not any(abs(box[0] - b[0]) < max(box[2], b[2]) and abs(box[1] - b[1]) < line for b in placed):
                break
        placed.append(box)
        ax.annotate(text, (x, y), fontsize=fontsize, color=colour, xytext=(3, 2 + shift), textcoords="offset points",
                    arrowprops=dict(arrowstyle="-", lw=0.3, color="0.6") if shift else None)


def error_vs_time(rows, out):
    fig, axes = plt.subplots(1, 2, figsize=(13, 6), dpi=110)
    floor = {"disp_rms_err_m": 1e-15, "force_err_N": 1e-13}
    for ax, key, label in ((axes[0], "disp_rms_err_m", "position error, RMS over nodes, worst step (m)"),
                           (axes[1], "force_err_N", "tool force error, worst step (N)")):
        labels = []
        for solver in ("MICA", "MICA-F", "PCG"):
            for group, ls, marker, mode in (("tolerance", "-", "o", "fixed tolerance"),
                                            ("iterations", "--", "s", "fixed iterations")):
                pts = [(num(r["ms_median"]), num(r[key]), r) for r in rows
                       if r["group"] == group and r["solver"] == solver and r["status"] in ("ok", "capped")]
                pts = [(x, max(y, floor[key]), r) for x, y, r in pts if fin(x) and fin(y)]
                if not pts:
                    continue
                pts.sort(key=lambda p: p[0])
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], ls=ls, marker=marker, ms=4,
                          color=COLOURS[solver], label=f"{solver}, {mode}")
                for x, y, r in pts:
                    tag = f"{num(r['tol']):.0e}" if group == "tolerance" else r["cap"]
                    labels.append((x, y, tag, COLOURS[solver]))
        exact = [num(r["ms_median"]) for r in rows if r["group"] == "tolerance" and r["solver"] == "exact"]
        if exact:
            ax.axvline(exact[0], color="k", ls=":", lw=1.2, label=f"exact (DIRECT): {exact[0]:.1f} ms")
        ax.set_xlabel("median ms per step (in-process, after warm-up)")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3)  # below: no point hidden
        label_points(ax, labels)
    axes[0].set_title("Position error against cost (labels: tolerance or iteration cap)")
    axes[1].set_title("Tool force error against cost")
    fig.suptitle("Error against the exact solver on the same scene: 3072-tet cube, sphere press + grasp drag, "
                 "dt = 10 ms, 100 steps")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "error_vs_time.png"))
    plt.close(fig)


def iterations_vs_tolerance(rows, out):
    fig, (ax_i, ax_t) = plt.subplots(1, 2, figsize=(12, 4.5), dpi=110)
    for solver in ("MICA", "MICA-F", "PCG"):
        pts = sorted((num(r["tol"]), num(r["iters_mean"]), num(r["iters_max"]), num(r["ms_median"]),
                      num(r["ms_p95"])) for r in rows if r["group"] == "tolerance" and r["solver"] == solver)
        if not pts:
            continue
        ax_i.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", color=COLOURS[solver],
                    label=f"{solver}: mean per step")
        ax_i.loglog([p[0] for p in pts], [p[2] for p in pts], "^:", color=COLOURS[solver], ms=4,
                    label=f"{solver}: worst step")
        ax_t.loglog([p[0] for p in pts], [p[3] for p in pts], "o-", color=COLOURS[solver], label=f"{solver}: median")
        ax_t.loglog([p[0] for p in pts], [p[4] for p in pts], "^:", color=COLOURS[solver], ms=4,
                    label=f"{solver}: p95")
    exact = [num(r["ms_median"]) for r in rows if r["group"] == "tolerance" and r["solver"] == "exact"]
    if exact:
        ax_t.axhline(exact[0], color="k", ls=":", label="exact (DIRECT) median")
    for ax in (ax_i, ax_t):
        ax.invert_xaxis()
        ax.set_xlabel("tolerance (relative change of v and lambda)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    ax_i.set_ylabel("iterations per step\n(PCG: summed over its solves, one per contact row + 1)")
    ax_t.set_ylabel("ms per step")
    ax_i.set_title("Iterations against tolerance")
    ax_t.set_title("Time against tolerance")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "iterations_vs_tolerance.png"))
    plt.close(fig)


def figure2(rows, steps, out):
    fig, (ax_s, ax_e, ax_t) = plt.subplots(1, 3, figsize=(16, 5.2), dpi=110)
    runs = OrderedDict()
    for r in steps:
        if r["solver"] == "MICA":
            runs.setdefault(num(r["E_Pa"]), []).append((int(r["step"]), int(r["iterations"]), int(r["converged"])))
    colours = plt.cm.viridis([i / max(1, len(runs) - 1) for i in range(len(runs))])
    for (E, rs), c in zip(runs.items(), colours):
        ax_s.plot([s for s, _, _ in rs], [i for _, i, _ in rs], marker="o", ms=2.5, lw=1, color=c,
                  label=f"E = {E:.0e} Pa")
        capped = [(s, i) for s, i, ok in rs if not ok]
        if capped:
            ax_s.plot(*zip(*capped), "x", color="r")
    ax_s.set_yscale("log")
    ax_s.set_xlabel("step (dt = 10 ms)")
    ax_s.set_ylabel("MICA iterations to tolerance 1e-8")
    ax_s.set_title("Figure 2: iterations per step (nu = 0.3)")
    ax_s.grid(alpha=0.3, which="both")
    ax_s.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.15), ncol=3)  # below: no curve hidden
    for solver in ("MICA", "MICA-F", "PCG", "exact"):
        pts = sorted((num(r["E_Pa"]), num(r["iters_mean"]), num(r["ms_median"])) for r in rows
                     if r["group"] == "stiffness" and r["solver"] == solver)
        if not pts:
            continue
        if solver != "exact":
            ax_e.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", color=COLOURS[solver], label=solver)
        ax_t.loglog([p[0] for p in pts], [p[2] for p in pts], "o-", color=COLOURS[solver], label=solver)
    Es = sorted({num(r["E_Pa"]) for r in rows if r["group"] == "stiffness"})
    if Es:
        dx = 0.1 / 8
        ax_e.set_title("Mean iterations per step against E\n(top axis: E h^2 / (rho dx^2))")
        sec = ax_e.secondary_xaxis("top", functions=(lambda E: E * 1e-4 / (1000 * dx * dx),
                                                     lambda r: r * 1000 * dx * dx / 1e-4))
        sec.tick_params(labelsize=7)
    ax_e.set_xlabel("Young's modulus E (Pa)")
    ax_e.set_ylabel("iterations per step (mean after warm-up)")
    ax_t.set_xlabel("Young's modulus E (Pa)")
    ax_t.set_ylabel("median ms per step")
    ax_t.set_title("Time against E (tol 1e-8; exact for reference)")
    for ax in (ax_e, ax_t):
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.suptitle("Stiffness: 3072-tet cube, sphere press + grasp drag, 50 steps of 10 ms")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figure2_stiffness.png"))
    plt.close(fig)


def moving_average_uncorrected(raw, n):
    out, acc = [], 0.0
    for k, v in enumerate(raw):
        acc += v
        if k >= n:
            acc -= raw[k - n]
        out.append(acc / min(n, k + 1))
    return out


def figure1(samples, filt, out):
    if not samples:
        return
    fig = plt.figure(figsize=(15, 8), dpi=110)
    gs = fig.add_gridspec(2, 3)
    ax = fig.add_subplot(gs[0, :2])
    ax_z = fig.add_subplot(gs[0, 2])
    ax_d = fig.add_subplot(gs[1, 0])
    ax_r = fig.add_subplot(gs[1, 1])
    ax_h = fig.add_subplot(gs[1, 2])
    by = defaultdict(list)
    for r in samples:
        by[(r["mode"], int(r["N"]))].append(r)
    local1 = by.get(("local", 1), [])
    local20 = by.get(("local", 20), [])
    if local1 and local20:
        t = [num(r["t_s"]) for r in local20]
        raw = [num(r["raw_force_y_N"]) for r in local20]
        ax.plot(t, [num(r["step_force_y_N"]) for r in local20], color="0.6", lw=1, drawstyle="steps-post",
                label="simulation step force (62.5 Hz)")
        ax.plot(t, raw, color="tab:orange", lw=0.8, label="raw: local model at 1 kHz")
        ax.plot(t, [num(r["filtered_force_y_N"]) for r in local20], color="tab:blue", lw=1.5,
                label="rendered: moving average N = 20 with the post-contact correction")
        ax.plot(t, moving_average_uncorrected(raw, 20), color="tab:green", lw=1, ls="--",
                label="N = 20 without the correction (computed from the raw samples)")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("force on the stylus, y (N)")
        ax.set_title("Figure 1: compression and release, simulated stylus, lockstep 16 polls per 16 ms step")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        # zoom on the contact onset
        onset = next((i for i, v in enumerate(raw) if v > 0), 0)
        lo, hi = max(0, onset - 15), min(len(t), onset + 80)
        ax_z.plot(t[lo:hi], raw[lo:hi], color="tab:orange", lw=1, marker=".", ms=3, label="raw")
        ax_z.plot(t[lo:hi], [num(r["filtered_force_y_N"]) for r in local20][lo:hi], color="tab:blue", lw=1.5,
                  label="N = 20, corrected")
        ax_z.plot(t[lo:hi], moving_average_uncorrected(raw, 20)[lo:hi], color="tab:green", ls="--",
                  label="N = 20, uncorrected")
        ax_z.set_title("Contact onset (zoom)")
        ax_z.set_xlabel("time (s)")
        ax_z.grid(alpha=0.3)
        ax_z.legend(fontsize=7)
    for mode, colour in (("local", "tab:blue"), ("hold", "tab:red")):
        pts = sorted((int(r["N"]), num(r["delay_ms"]), num(r["ripple_rms_N_per_ms"]), num(r["max_jump_N"]))
                     for r in filt if r["mode"] == mode)
        if not pts:
            continue
        name = "local model" if mode == "local" else "zero-order hold"
        ax_d.plot([p[0] for p in pts], [p[1] for p in pts], "o-", color=colour, label=f"{name}: measured")
        ax_r.loglog([p[0] for p in pts], [p[2] for p in pts], "o-", color=colour, label=f"{name}: RMS change per ms")
        ax_r.loglog([p[0] for p in pts], [p[3] for p in pts], "s:", color=colour, ms=4,
                    label=f"{name}: largest jump per ms")
    Ns = sorted({int(r["N"]) for r in filt})
    ax_d.plot(Ns, [(n - 1) / 2 for n in Ns], "k:", label="(N - 1) / 2")
    ax_d.set_xlabel("filter window N (servo samples of 1 ms)")
    ax_d.set_ylabel("delay of the rendered force (ms)")
    ax_d.set_title("Delay against N")
    ax_r.set_xlabel("filter window N")
    ax_r.set_ylabel("N per servo sample while in contact")
    ax_r.set_title("Smoothness against N")
    for a in (ax_d, ax_r):
        a.grid(alpha=0.3, which="both")
        a.legend(fontsize=7)
    hold20 = by.get(("hold", 20), [])
    hold1 = by.get(("hold", 1), [])
    if hold1 and hold20:
        t = [num(r["t_s"]) for r in hold20]
        ax_h.plot(t, [num(r["filtered_force_y_N"]) for r in hold1], color="tab:red", lw=0.8, label="hold, N = 1")
        ax_h.plot(t, [num(r["filtered_force_y_N"]) for r in hold20], color="tab:blue", lw=1.5, label="hold, N = 20")
        ax_h.set_xlim(0.3, 0.5)
        ys = [num(r["filtered_force_y_N"]) for r in hold1 if 0.3 <= num(r["t_s"]) <= 0.5]
        if ys:
            ax_h.set_ylim(min(ys) * 0.95, max(ys) * 1.05)
        ax_h.set_title("Zero-order hold, loading (zoom)")
        ax_h.set_xlabel("time (s)")
        ax_h.grid(alpha=0.3)
        ax_h.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "figure1_force.png"))
    plt.close(fig)


def knobs(rows, out):
    panels = [("dt", "time step", lambda r: f"{1e3 * num(r['dt_s']):g} ms"),
              ("mesh", "mesh (cells per side)", lambda r: f"{r['cells']}^3"),
              ("model", "model", lambda r: r["model"]),
              ("mass", "mass", lambda r: r["mass"]),
              ("pgs", "PGS sweeps (tol 1e-6)", lambda r: f"{r['pgs_sweeps']} sweeps"),
              ("warmstart", "warm start", lambda r: f"{'on' if r['warm_start'] == '1' else 'off'} {num(r['tol']):.0e}"),
              ("norm", "paper's 2-norm stop", lambda r: f"{num(r['tol']):.0e}")]
    fig, axes = plt.subplots(2, 4, figsize=(18, 8), dpi=100)
    axes = axes.ravel()
    base = [r for r in rows if r["group"] == "tolerance" and r["solver"] == "MICA"]
    for ax, (group, title, tag) in zip(axes, panels):
        rs = [r for r in rows if r["group"] == group]
        if not rs:
            ax.set_title(f"{title}: not in this run")
            ax.axis("off")
            continue
        labels = []
        for r in rs:
            x = num(r["ms_median"])
            y = num(r["model_disp_rms_err_m"]) if group in ("dt", "model", "mass") else num(r["disp_rms_err_m"])
            if group == "mesh":
                y = num(r["model_force_err_N"])
            if not fin(x) or not fin(y):
                continue
            y = max(y, 1e-12)
            ax.loglog(x, y, "o" if r["solver"] == "MICA" else "s" if r["solver"] == "PCG" else "D",
                      color=COLOURS[r["solver"]], ms=6)
            labels.append((x, y, f"{r['solver']} {tag(r)}", "k"))
        if group in ("pgs", "norm", "warmstart") and base:
            pts = sorted((num(r["ms_median"]), num(r["disp_rms_err_m"])) for r in base)
            ax.loglog([p[0] for p in pts], [max(p[1], 1e-12) for p in pts], "-", color="0.7", lw=1,
                      label="MICA tolerance front")
            ax.legend(fontsize=6)
        what = {"dt": "position error vs exact at dt = 5 ms (m)", "mesh": "tool force error vs exact 10^3 (N)",
                "model": "position error vs exact co-rotational (m)",
                "mass": "position error vs exact consistent (m)"}.get(group, "position error vs exact (m)")
        ax.set_ylabel(what, fontsize=8)
        ax.set_xlabel("median ms per step", fontsize=8)
        ax.set_title(title)
        ax.grid(alpha=0.3, which="both")
        label_points(ax, labels)
    drift = [r for r in rows if r["group"] == "drift"]
    ax = axes[7]
    if drift:
        labels = [f"{r['solver']} {num(r['tol']):.0e}" if r["solver"] != "exact" else "exact" for r in drift]
        vals = [num(r["energy_ratio_end"]) for r in drift]
        ax.bar(range(len(vals)), vals, color=[COLOURS[r["solver"]] for r in drift])
        ax.set_xticks(range(len(vals)))
        ax.set_xticklabels(labels, rotation=45, fontsize=7, ha="right")
        ax.set_ylabel("energy after 1 s / energy after the push")
        ax.set_title("Energy drift: undamped free vibration")
        # Log scale: the ratios span decades (backward Euler damps the vibration), and a linear axis
        # cut just below the smallest made bars of similar height look empty.
        ax.set_yscale("log")
        ax.set_ylim(min(v for v in vals if fin(v) and v > 0) / 10, max(vals) * 2)
        ax.grid(alpha=0.3, axis="y", which="both")
    fig.suptitle("The other knobs (MICA tol 1e-6 unless marked): error against cost")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "knobs.png"))
    plt.close(fig)


def anchors(rows, curve, out):
    if not rows:
        return
    fig, (ax_c, ax_f) = plt.subplots(1, 2, figsize=(13, 5), dpi=110)
    labels = []
    for test, model, colour, marker in (("hertz", "linear", "tab:red", "o"),
                                        ("hertz", "corotational", "tab:orange", "D"),
                                        ("hertz", "neo-hookean", "tab:brown", "P"),
                                        ("cantilever", "linear", "tab:blue", "s"),
                                        ("cantilever", "corotational", "tab:cyan", "^"),
                                        ("cantilever", "neo-hookean", "tab:purple", "v")):
        pts = sorted((num(r["h_m"]), abs(num(r["rel_error"])), num(r["rel_error"])) for r in rows
                     if r["test"] == test and r["model"] == model)
        pts = [p for p in pts if fin(p[1])]
        if not pts:
            continue
        label = (f"Hertz force ({model}), h = cell size at the contact edge" if test == "hertz"
                 else f"cantilever tip ({model}), h = H / n")
        ax_c.loglog([p[0] for p in pts], [p[1] for p in pts], marker=marker, color=colour, label=label)
        for h, e, s in pts:
            labels.append((h, e, f"{s:+.1%}", colour))
        if len(pts) >= 2:
            (h1, e1, _), (h2, e2, _) = pts[0], pts[1]
            if e1 > 0 and e2 > 0 and h2 != h1:
                rate = math.log(e2 / e1) / math.log(h2 / h1)
                labels.append((h1, e1, f"slope {rate:.2f} (finest two)", colour))
    label_points(ax_c, labels)
    ax_c.set_xlabel("element size h (m)")
    ax_c.set_ylabel("|FEM - theory| / theory")
    ax_c.set_title("Mesh convergence toward Hertz and Euler-Bernoulli (exact solver, static)")
    ax_c.grid(alpha=0.3, which="both")
    ax_c.legend(fontsize=7)
    by = OrderedDict()
    for r in curve:
        by.setdefault(num(r["h0_m"]), []).append((num(r["depth_m"]), num(r["force_N"]), num(r["hertz_N"])))
    colours = plt.cm.plasma([i / max(1, len(by)) for i in range(len(by))])
    for (h, pts), c in zip(by.items(), colours):
        ax_f.loglog([1e3 * p[0] for p in pts], [p[1] for p in pts], "o-", color=c, ms=4,
                    label=f"FEM, h0 = {1e3 * h:.2f} mm")
    if by:
        pts = list(by.values())[0]
        ax_f.loglog([1e3 * p[0] for p in pts], [p[2] for p in pts], "k--", lw=2,
                    label="Hertz 4/3 E/(1-nu^2) sqrt(R) d^1.5")
    ax_f.set_xlabel("indentation d (mm)")
    ax_f.set_ylabel("force (N)")
    ax_f.set_title("Sphere R = 1 cm on a deep block (E = 10 kPa, nu = 0.3)")
    ax_f.grid(alpha=0.3, which="both")
    ax_f.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "anchors.png"))
    plt.close(fig)


MODELS = (("linear", "tab:gray", "s", "linear"), ("corotational", "tab:blue", "o", "co-rotational"),
          ("neo-hookean", "tab:red", "^", "neo-Hookean"))


def material(rows, uni, out):
    """The material axis: uniaxial compression (uniaxial.csv) and the press scene's model group
    (sweep.csv)."""
    press = [r for r in rows if r["group"] == "model"]
    if not uni and not press:
        return
    fig, axes = plt.subplots(2, 2, figsize=(13, 9), dpi=100)
    (ax_p, ax_e), (ax_u, ax_c) = axes
    if uni:
        # The closed forms at the measured strains (uniaxial.csv has them per row), from the origin.
        ref = sorted({(num(r["strain"]), -num(r["nominal_neo_hookean_Pa"]), -num(r["nominal_hooke_Pa"]))
                      for r in uni if r["model"] == "neo-hookean"})
        if ref:
            ax_p.plot([0] + [100 * p[0] for p in ref], [0] + [p[1] for p in ref], "k-", lw=1.5,
                      label="neo-Hookean closed form (at the measured stretch)")
            ax_p.plot([0] + [100 * p[0] for p in ref], [0] + [p[2] for p in ref], "k--", lw=1,
                      label="Hooke: E (1 - s)")
        for model, colour, marker, name in MODELS:
            pts = sorted((100 * num(r["strain"]), -num(r["nominal_fem_Pa"]), 100 * num(r["rel_error"]),
                          num(r["load_cpu_ms"]), num(r["cpu_ms_median"]), num(r["load_solves"]))
                         for r in uni if r["model"] == model)
            if not pts:
                continue
            ms = 9 if model == "linear" else 6  # linear and co-rotational coincide here: linear drawn larger
            ax_p.plot([p[0] for p in pts], [p[1] for p in pts], marker, color=colour, ms=ms, mfc="none", label=name)
            ax_e.plot([p[0] for p in pts], [p[2] for p in pts], marker + "-", color=colour, ms=ms, mfc="none",
                      label=name)
            ax_u.plot([p[0] for p in pts], [p[3] for p in pts], marker + "-", color=colour, ms=ms, mfc="none",
                      label=f"{name}: the loading step")
            ax_u.plot([p[0] for p in pts], [p[4] for p in pts], marker + ":", color=colour, ms=ms - 2, mfc="none",
                      label=f"{name}: median of the increment's 7 steps")
            for x, _, _, y, _, n in pts:
                ax_u.annotate(f"{n:.0f}", (x, y), fontsize=6, color=colour, xytext=(2, 3), textcoords="offset points")
        cells = uni[0]["cells"]
        ax_p.set_title(f"Uniaxial compression, frictionless ends ({cells}^3 cells x 6 tets, E = 10 kPa, nu = 0.45)",
                       fontsize=9)
        ax_p.set_xlabel("compression (%)")
        ax_p.set_ylabel("nominal stress -P_zz (Pa)")
        ax_e.set_title("Error against the neo-Hookean closed form", fontsize=9)
        ax_e.set_xlabel("compression (%)")
        ax_e.set_ylabel("(FEM - closed form) / closed form (%)")
        ax_e.axhline(0, color="k", lw=0.8)
        ax_u.set_title("Uniaxial: CPU ms per step (exact solver; labels: solves of the loading step;\n"
                       "the first step also analyses the matrix)", fontsize=9)
        ax_u.set_xlabel("compression (%)")
        ax_u.set_ylabel("stepping thread's CPU ms")
        for ax in (ax_p, ax_e, ax_u):
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    if press:
        solvers = [s for s in ("exact", "MICA", "MICA-F", "PCG") if any(r["solver"] == s for r in press)]
        width, labelled = 0.8 / len(MODELS), set()
        for i, solver in enumerate(solvers):
            here = [(m, next(r for r in press if r["model"] == m[0] and r["solver"] == solver)) for m in MODELS
                    if any(r["model"] == m[0] and r["solver"] == solver for r in press)]
            for k, ((_, colour, _, name), r) in enumerate(here):
                x, y = i + (k - (len(here) - 1) / 2) * width, num(r["cpu_ms_median"])  # centred on the solver
                ax_c.bar(x, y, width, color=colour, label=None if name in labelled else name)
                labelled.add(name)
                ax_c.annotate(f"{y:.2f}", (x, y), fontsize=7, ha="center", xytext=(0, 2), textcoords="offset points")
        ax_c.set_xticks(range(len(solvers)))
        ax_c.set_xticklabels([s if s == "exact" else f"{s}, tol 1e-6" for s in solvers])
        ax_c.set_ylabel("median CPU ms per step (stepping thread)")
        ax_c.set_yscale("log")
        ax_c.set_title("Press scene (3072 tets, 10 ms steps): median CPU ms per step\n"
                       "(the models' differences in position and force: the accuracy-material table)", fontsize=9)
        ax_c.grid(alpha=0.3, axis="y", which="both")
        ax_c.legend(fontsize=7)
    else:
        ax_c.axis("off")
    fig.suptitle("Material axis: linear, co-rotational and neo-Hookean bodies")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "material.png"))
    plt.close(fig)


def scaling(rows, out):
    if not rows:
        return
    fig, (ax_t, ax_i) = plt.subplots(1, 2, figsize=(12, 4.5), dpi=110)
    tets = [num(r["tets"]) for r in rows]
    ax_t.loglog(tets, [num(r["ms_median"]) for r in rows], "o-", label="median ms per step")
    ax_t.loglog(tets, [num(r["ms_p95"]) for r in rows], "^:", label="p95")
    t0, m0 = tets[0], num(rows[0]["ms_median"])
    ax_t.loglog(tets, [m0 * t / t0 for t in tets], "k:", lw=1, label="proportional to tets")
    ax_t.set_xlabel("tets")
    ax_t.set_ylabel("ms per step (MICA, factored sweep, tol 1e-6, one core)")
    ax_t.set_title("Time per step against mesh size (0.1 m cube refined)")
    ax_i.loglog(tets, [num(r["iterations"]) for r in rows], "o-", color="tab:orange", label="iterations per step")
    ax_i2 = ax_i.twinx()
    ax_i2.loglog(tets, [1e3 * num(r["ms_per_iteration"]) / num(r["tets"]) for r in rows], "s--", color="tab:green",
                 label="microseconds per iteration per tet")
    ax_i.set_xlabel("tets")
    ax_i.set_ylabel("iterations per step", color="tab:orange")
    ax_i2.set_ylabel("us per iteration per tet", color="tab:green")
    ax_i.set_title("Where the time goes: iterations per step, cost per iteration")
    for a in (ax_t, ax_i):
        a.grid(alpha=0.3, which="both")
    ax_t.legend(fontsize=7)
    # One legend for both of the right panel's axes (each curve is on its own y axis).
    lines = ax_i.get_lines() + ax_i2.get_lines()
    ax_i.legend(lines, [l.get_label() for l in lines], fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scaling.png"))
    plt.close(fig)


def g(v, fmt="{:.3g}"):
    x = num(v)
    return "-" if not fin(x) else fmt.format(x)



def sweep_tables(rows, w):
    """The other knobs, stiffness and energy drift tables of the sweep (sweep.csv)."""
    w("\n### Other knobs\n")
    w("<!-- study:begin accuracy-knobs -->")
    w("| group | solver | setting | median ms | p95 ms | iters/step | pos. RMS err vs exact, same scene (m) "
      "| model error (m or N) | force err (N) | penetration (m) | status |")
    w("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        gr = r["group"]
        if gr in ("tolerance", "iterations", "drift", "stiffness"):
            continue
        setting = {"dt": f"dt {1e3 * num(r['dt_s']):g} ms", "mesh": f"{r['cells']}^3 cells, {r['tets']} tets",
                   "model": r["model"], "mass": r["mass"], "pgs": f"{r['pgs_sweeps']} PGS sweeps",
                   "warmstart": f"warm start {'on' if r['warm_start'] == '1' else 'off'}",
                   "norm": "paper's 2-norm"}.get(gr, "")
        if r["solver"] != "exact":
            setting += f", tol {num(r['tol']):.0e}"
        model = (f"{g(r['model_force_err_N'])} N" if gr == "mesh" else
                 f"{g(r['model_disp_rms_err_m'])} m" if gr in ("dt", "model", "mass") else "-")
        w(f"| {gr} | {r['solver']} | {setting} | {g(r['ms_median'])} | {g(r['ms_p95'])} | "
          f"{g(r['iters_mean'], '{:.1f}')} | {g(r['disp_rms_err_m'])} | {model} | {g(r['force_err_N'])} | "
          f"{g(r['penetration_m'])} | {r['status']} |")
    w("<!-- study:end accuracy-knobs -->")
    w("\n### Stiffness (tol 1e-8, 50 steps)\n")
    w("<!-- study:begin accuracy-stiffness -->")
    w("| E (Pa) | solver | median ms | p95 ms | iters/step (max) | pos. RMS err (m) | force err (N) | status |")
    w("|---|---|---|---|---|---|---|---|")
    for r in rows:
        if r["group"] == "stiffness":
            w(f"| {num(r['E_Pa']):.0e} | {r['solver']} | {g(r['ms_median'])} | {g(r['ms_p95'])} | "
              f"{g(r['iters_mean'], '{:.1f}')} ({g(r['iters_max'], '{:.0f}')}) | {g(r['disp_rms_err_m'])} | "
              f"{g(r['force_err_N'])} | {r['status']} |")
    w("<!-- study:end accuracy-stiffness -->")
    w("\n### Energy drift (undamped free vibration, 1 s)\n")
    w("<!-- study:begin accuracy-drift -->")
    w("| solver | tol | median ms | iters/step | energy end / start | pos. RMS err vs exact (m) |")
    w("|---|---|---|---|---|---|")
    for r in rows:
        if r["group"] == "drift":
            tol = "-" if r["solver"] == "exact" else f"{num(r['tol']):.0e}"
            w(f"| {r['solver']} | {tol} | {g(r['ms_median'])} | {g(r['iters_mean'], '{:.1f}')} | "
              f"{g(r['energy_ratio_end'], '{:.3g}')} | {g(r['disp_rms_err_m'])} |")
    w("<!-- study:end accuracy-drift -->")


def pct(v):
    """A relative error in percent, 3 significant digits (round-off shows as such, not as 0.00 %)."""
    x = num(v)
    return "-" if not fin(x) else f"{100 * x:+.3g}%"


def material_tables(rows, uni, w):
    """The material axis: the press scene's model group (sweep.csv) and uniaxial compression
    (uniaxial.csv)."""
    press = [r for r in rows if r["group"] == "model"]
    if press:
        w("\n### Material: the press scene per model\n")
        w("<!-- study:begin accuracy-material -->")
        w("| solver | model | median CPU ms | p95 CPU ms | median wall ms | iters/step | solves/step "
          "| pos. RMS err vs exact, same model (m) | pos. RMS diff. vs exact co-rotational (m) "
          "| force diff. vs exact co-rotational (N) | peak force (N) | status |")
        w("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in press:
            tol = "" if r["solver"] == "exact" else f", tol {num(r['tol']):.0e}"
            w(f"| {r['solver']}{tol} | {r['model']} | {g(r['cpu_ms_median'])} | {g(r['cpu_ms_p95'])} | "
              f"{g(r['ms_median'])} | {g(r['iters_mean'], '{:.1f}')} | {g(r['solves_mean'], '{:.2f}')} | "
              f"{g(r['disp_rms_err_m'])} | {g(r['model_disp_rms_err_m'])} | {g(r['model_force_err_N'])} | "
              f"{g(r['peak_force_N'], '{:.3f}')} | {r['status']} |")
        w("<!-- study:end accuracy-material -->")
    if uni:
        w("\n### Material: uniaxial compression against the neo-Hookean closed form\n")
        w("<!-- study:begin accuracy-uniaxial -->")
        w("| model | compression | P FEM (Pa) | P neo-Hookean (Pa) | error | P Hooke (Pa) | error vs Hooke "
          "| lateral stretch FEM | neo-Hookean | solves, loading step | CPU ms, loading step | CPU ms/step, median |")
        w("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in uni:
            w(f"| {r['model']} | {100 * num(r['strain']):.0f}% | {g(r['nominal_fem_Pa'], '{:.1f}')} | "
              f"{g(r['nominal_neo_hookean_Pa'], '{:.1f}')} | {pct(r['rel_error'])} | "
              f"{g(r['nominal_hooke_Pa'], '{:.1f}')} | {pct(r['rel_error_hooke'])} | "
              f"{g(r['lateral_fem'], '{:.4f}')} | {g(r['lateral_neo_hookean'], '{:.4f}')} | {r['load_solves']} | "
              f"{g(r['load_cpu_ms'], '{:.2f}')} | {g(r['cpu_ms_median'], '{:.2f}')} |")
        w("<!-- study:end accuracy-uniaxial -->")


def tables(rows, anchor_rows, filt, scal, comments, out, contact=(), uni=()):
    lines = []
    w = lines.append
    w("<!-- written by scripts/study_plots.py -->")
    for name, c in comments.items():
        if c:
            w(f"<!-- {name}: {c} -->")
    head = ("| solver | tol | cap | median ms | p95 ms | iters/step (max) | pos. RMS err (m) | pos. max err (m) "
            "| force err (N) | energy err | status |")
    sep = "|---|---|---|---|---|---|---|---|---|---|---|"

    def row(r, extra_tol=True):
        tol = "-" if r["solver"] == "exact" else f"{num(r['tol']):.0e}"
        cap = "-" if r["solver"] == "exact" else r["cap"]
        return (f"| {r['solver']} | {tol} | {cap} | {g(r['ms_median'])} | {g(r['ms_p95'])} | "
                f"{g(r['iters_mean'], '{:.1f}')} ({g(r['iters_max'], '{:.0f}')}) | {g(r['disp_rms_err_m'])} | "
                f"{g(r['disp_max_err_m'])} | {g(r['force_err_N'])} | {g(r['energy_err_rel'])} | {r['status']} |")

    # The sweep's tables only when it ran (the `perf` part of the study leaves it out).
    for group, title in (() if not rows else (("tolerance", "Fixed tolerance (cap 100000)"),
                         ("iterations", "Fixed iterations (tolerance 1e-300, the cap varies)"))):
        w(f"\n### {title}\n")
        w(f"<!-- study:begin accuracy-{group} -->")
        w(head)
        w(sep)
        for r in rows:
            if r["group"] == group or (group == "tolerance" and r["group"] == "tolerance" and r["solver"] == "exact"):
                w(row(r))
        w(f"<!-- study:end accuracy-{group} -->")
    if rows:
        sweep_tables(rows, w)
    if anchor_rows:
        w("\n### Analytic anchors\n")
        w("<!-- study:begin accuracy-anchors -->")
        w("| test | model | h (m) | nodes | tets | FEM | theory | rel. error | vs Timoshenko (beam) | ms |")
        w("|---|---|---|---|---|---|---|---|---|---|")
        for r in anchor_rows:
            extra = (g(r.get("rel_error_timoshenko"), "{:+.2%}") if r["test"] == "cantilever"
                     else f"(last 3 steps spread {g(r.get('spread'), '{:.1%}')})")
            w(f"| {r['test']} | {r['model']} | {g(r['h_m'])} | {r['nodes']} | {r['tets']} | {g(r['fem'], '{:.5g}')} | "
              f"{g(r['theory'], '{:.5g}')} | {g(r['rel_error'], '{:+.2%}')} | {extra} | {g(r['ms'], '{:.0f}')} |")
        w("<!-- study:end accuracy-anchors -->")
    material_tables(rows, uni, w)
    if filt:
        w("\n### Filter window (device side)\n")
        w("<!-- study:begin accuracy-filter -->")
        w("| mode | N | delay (ms) | (N-1)/2 | ripple (N/ms) | raw ripple | largest jump (N) | raw jump (N) "
          "| peak raw (N) | peak rendered (N) |")
        w("|---|---|---|---|---|---|---|---|---|---|")
        for r in filt:
            w(f"| {r['mode']} | {r['N']} | {r['delay_ms']} | {r['delay_theory_ms']} | {g(r['ripple_rms_N_per_ms'])} | "
              f"{g(r['ripple_raw_N_per_ms'])} | {g(r['max_jump_N'])} | {g(r['max_jump_raw_N'])} | "
              f"{g(r['peak_raw_N'], '{:.4f}')} | {g(r['peak_filtered_N'], '{:.4f}')} |")
        w("<!-- study:end accuracy-filter -->")
    if contact:
        w("\n### Force quality (bench_contact: tool pressed 10 mm and held 1 s)\n")
        w("<!-- study:begin accuracy-contact -->")
        w("| body | tool | cells | dt (ms) | solver | F end (N) | alt. run | late change | loading drop "
          "| ms/step | iters/step | verdict |")
        w("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in contact:
            fails = [k for k, c in (("alt", "pass_alt"), ("late", "pass_late"), ("drop", "pass_drop")) if r[c] != "1"]
            verdict = "pass" if not fails else "**FAIL**: " + ", ".join(fails)
            w(f"| {r['body']} | {r['shape']} | {r['cells'] if r['body'] == 'cube' else '-'} | {r['dt_ms']} | "
              f"{r['solver']} | {g(r['force_N'], '{:.4f}')} | {r['alt_run']} | {g(r['late_rel'], '{:.2e}')} | "
              f"{g(r['load_drop_rel'], '{:.3%}')} | {g(r['ms_median'], '{:.1f}')} | {g(r['iters_mean'], '{:.1f}')} | "
              f"{verdict} |")
        w("<!-- study:end accuracy-contact -->")
    with open(os.path.join(out, "tables.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


# ---- the performance tables (docs/performance.md), from the benchmarks' own output

def read_text(folder, name):
    path = os.path.join(folder, name + ".txt")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return f.read()


def commands(folder):
    """Each stage's command as the docs print it (study.sh writes commands.txt: name|command)."""
    out = {}
    path = os.path.join(folder, "commands.txt")
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                if "|" in line:
                    name, cmd = line.rstrip("\n").split("|", 1)
                    # The 4-thread factorization: the study's environment without OMP_THREAD_LIMIT.
                    cmd = cmd.replace("OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 env -u OMP_THREAD_LIMIT ",
                                      "OPENBLAS_NUM_THREADS=1 ")
                    out[name] = cmd
    return out


def nidus_sections(text):
    """bench_nidus's output: {section title: {key: value text}} (keys as printed, e.g. 'median ms/step')."""
    sections, cur = OrderedDict(), None
    for line in (text or "").splitlines():
        if line.startswith("## "):
            cur = sections.setdefault(line[3:].strip(), {})
        elif cur is not None and line.startswith("# bench_nidus:"):
            m = re.search(r"load average ([\d.]+)", line)
            cur["load"] = m.group(1) if m else "?"
        elif cur is not None and line.startswith("# mesh "):
            m = re.search(r"(\d+) tets", line)
            cur["tets"] = m.group(1) if m else "?"
        elif cur is not None and line.startswith("mean ms/step by stage "):
            cur["mean ms/step by stage"] = line[len("mean ms/step by stage "):]
        elif cur is not None and not line.startswith("#"):
            m = re.match(r"^(\S.*?)\s{2,}(.*)$", line)
            if m:
                cur[m.group(1).strip()] = m.group(2).strip()
    return sections


def first_num(v, default=math.nan):
    m = re.search(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?", v or "")
    return float(m.group(0)) if m else default


def held_b_per_tet(sec):
    m = re.search(r"held (\d+) B/tet", sec.get("memory, after 1 step", ""))
    return int(m.group(1)) if m else None


def stages_of(sec):
    return {k: float(v) for k, v in re.findall(r"(\w+) ([\d.]+)", sec.get("mean ms/step by stage", ""))}


def source_of_run(folder):
    """When the run was (its nidus output's time) and the commit of the source it ran."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    stamp = "?"
    path = os.path.join(folder, "nidus.txt")
    if os.path.exists(path):
        import datetime
        stamp = datetime.datetime.utcfromtimestamp(os.path.getmtime(path)).strftime("%Y-%m-%d %H:%M UTC")
    try:
        import subprocess
        commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, universal_newlines=True).stdout.strip() or "?"
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no", "--", "src",
                                "capi", "include", "bench", "scenes", "CMakeLists.txt"], stdout=subprocess.PIPE,
                               stderr=subprocess.DEVNULL, universal_newlines=True).stdout.strip()
        commit += " with local changes to the library or benchmarks" if dirty else ""
    except OSError:
        commit = "?"
    return stamp, commit


def headline(folder, fac, cmds, block):
    """The figures a reader asks first, each from one of the runs below it."""
    rows, used = [], []

    def row(what, figure, run):
        rows.append(f"| {what} | {figure} | {run} |")
        for r in run.split(", "):
            if r not in used:
                used.append(r)

    if fac:
        row("the nidus step (9668 tets, a tool moving in contact), one core: median / p95",
            f"**{first_num(fac['median ms/step']):.2f} / {first_num(fac['p95 ms/step']):.2f} ms**", "nidus")
        row("its conjugate-gradient iterations a step", f"{first_num(fac['iterations/step']):.1f}", "nidus")
        held = held_b_per_tet(fac)
        if held:
            row("memory the world holds, nidus", f"**{held} B per tet**", "nidus")
    d = nidus_sections(read_text(folder, "defaults"))
    if d.get("the default world") and d.get("solver DIRECT"):
        a, b = first_num(d["the default world"]["median ms/step"]), first_num(d["solver DIRECT"]["median ms/step"])
        row("the default world against the exact solver (`MICA_SOLVER_DIRECT`), nidus: median step",
            f"{a:.2f} against {b:.2f} ms: {b / a:.1f}x faster", "defaults")
    scal, _ = read(os.path.join(folder, "scaling.csv"))
    if scal:
        pick = [scal[0]] + [r for r in scal if 30000 <= num(r["tets"]) <= 40000][:1] + [scal[-1]]
        row("the scaling curve (a cube, one core): median step at " + " / ".join(f"{int(num(r['tets'])):,} tets"
                                                                                  for r in pick),
            "**" + " / ".join(f"{g(r['ms_median'])}" for r in pick) + " ms**", "scaling")
        held = [num(r.get("mem_held_B_per_tet")) for r in scal if fin(num(r.get("mem_held_B_per_tet")))]
        if held:
            row("memory the world holds along the curve", f"{min(held):.0f}-{max(held):.0f} B per tet", "scaling")
    servo, idle = read_text(folder, "servo"), read_text(folder, "servo_idle")
    if servo:
        cost = re.search(r"poll cost \(us\):\s+median ([\d.]+)", servo)
        late = re.search(r"late \(ms\):.*?p99.9 ([\d.]+)", servo)
        late_idle = re.search(r"late \(ms\):.*?p99.9 ([\d.]+)", idle or "")
        if cost:
            row("the 1 kHz servo loop beside the stepping nidus: one poll, median", f"{cost.group(1)} us", "servo")
        if late and late_idle:
            row("its cycles' lateness, p99.9, beside the nidus / with nothing stepping",
                f"{late.group(1)} / {late_idle.group(1)} ms", "servo, servo_idle")
    if not rows:
        return
    stamp, commit = source_of_run(folder)
    body = ["| | | run |", "|---|---|---|"] + rows + [""]
    body += [f"- {k}: `{cmds[k]}`" if k in cmds else f"- {k}: (not run)" for k in used]
    body += ["", f"Measured {stamp} by `scripts/study.sh` (its `perf` part), source {commit}."]
    block("perf-headline", body)


def perf_lines(folder):
    cmds = commands(folder)
    lines = []
    w = lines.append

    def cmd(name):
        return f"`{cmds[name]}`" if name in cmds else "(not run)"

    def block(name, body):
        w(f"\n<!-- study:begin {name} -->")
        lines.extend(body)
        w(f"<!-- study:end {name} -->")

    nidus = nidus_sections(read_text(folder, "nidus"))
    fac = nidus.get("factored sweep")
    headline(folder, fac, cmds, block)
    if fac:
        st = stages_of(fac)
        other = sum(v for k, v in st.items() if k not in ("rotations", "elements", "solve"))
        held = held_b_per_tet(fac)
        force = fac.get("tool force", "").split(",")[0]
        body = ["| the nidus step (factored sweep, tol 1e-6, one core) | |", "|---|---|",
                f"| median / p95 ms a step | **{first_num(fac['median ms/step']):.2f}** / "
                f"**{first_num(fac['p95 ms/step']):.2f}** (max {first_num(fac['max ms/step']):.2f}) |",
                f"| the stepping thread's CPU time, median | {first_num(fac['median CPU ms/step']):.2f} ms |",
                f"| where it goes (mean ms a step) | rotations {st.get('rotations', math.nan):.2f}, elements "
                f"{st.get('elements', math.nan):.2f}, solve {st.get('solve', math.nan):.2f}, the rest {other:.2f} |",
                f"| conjugate-gradient iterations / velocity solves a step | {first_num(fac['iterations/step']):.1f} / "
                f"{first_num(fac['solves/step']):.2f} |",
                f"| memory held after the first step | {held} B per tet "
                f"({held * first_num(fac.get('tets')) / 1e6:.1f} MB for {fac.get('tets')} tets) |" if held else "| memory held | - |",
                f"| tool force at the end | {force} |",
                f"| contact nodes whose velocity change reverses from one step to the next | "
                f"{fac.get('velocity reversals', '-').split(' of ')[0]} |",
                "",
                f"Load average at the start: {fac.get('load', '?')}. Command: {cmd('nidus')}"]
        block("perf-nidus", body)

    rows = []
    d = nidus_sections(read_text(folder, "defaults"))
    dw = d.get("the default world")
    if dw:
        base = first_num(dw["median ms/step"])
        for title, label in (("the default world", "the default world: MICA, factored sweep, tol 1e-8, cap 200"),
                             ("solver DIRECT", "`solver = MICA_SOLVER_DIRECT` (exact, the default before 0.5)"),
                             ("MICA, Gauss-Seidel sweep", "`mica_sweep = MICA_SWEEP_GAUSS_SEIDEL` (the paper's sweep)")):
            sec = d.get(title)
            if not sec:
                continue
            med = first_num(sec["median ms/step"])
            capped = re.search(r"(\d+) stopped at the cap", sec.get("iterations/step", ""))
            note = f"{capped.group(1)} of the steps stopped at the cap" if capped and capped.group(1) != "0" else "every step converged"
            rows.append(f"| {label} | {med:.2f} | {first_num(sec['p95 ms/step']):.2f} | "
                        f"{first_num(sec['iterations/step']):.1f} | {note} | "
                        f"{'1' if sec is dw else f'{med / base:.1f}x'} | defaults |")
    r = nidus_sections(read_text(folder, "refresh"))
    rf, rr = r.get("factored sweep"), next((v for k, v in r.items() if "refreshed" in k), None)
    if rf and rr:
        m = re.search(r"every (\d+) steps", next(k for k in r if "refreshed" in k))
        every = m.group(1) if m else "?"
        base = first_num(rf["median ms/step"])
        for sec, label in ((rf, "factored sweep, tol 1e-6, `refactor_interval = 0`, not pinned"),
                           (rr, f"the same, `refactor_interval = {every}` (a second core factors)")):
            med = first_num(sec["median ms/step"])
            rows.append(f"| {label} | {med:.2f} | {first_num(sec['p95 ms/step']):.2f} | "
                        f"{first_num(sec['iterations/step']):.1f} | "
                        f"{first_num(sec.get('factorizations', '0')):.0f} factorizations in the timed steps | "
                        f"{'1' if sec is rf else f'{med / base:.2f}x'} | refresh |")
    lin = nidus_sections(read_text(folder, "linear")).get("factored sweep")
    if lin and fac:
        base = first_num(fac["median ms/step"])
        med = first_num(lin["median ms/step"])
        rows.append(f"| factored sweep, tol 1e-6, co-rotational body (the `nidus` run above) | {base:.2f} | "
                    f"{first_num(fac['p95 ms/step']):.2f} | {first_num(fac['iterations/step']):.1f} | "
                    f"tool force {fac.get('tool force', '').split(',')[0]} | 1 | nidus |")
        rows.append(f"| the same, `mica_body_def.model = MICA_MODEL_LINEAR` | {med:.2f} | "
                    f"{first_num(lin['p95 ms/step']):.2f} | {first_num(lin['iterations/step']):.1f} | "
                    f"tool force {lin.get('tool force', '').split(',')[0]} | {med / base:.2f}x | linear |")
    if rows:
        used = []
        for r_ in rows:
            k = r_.rsplit("|", 2)[-2].strip()
            if k not in used:
                used.append(k)
        body = ["| the nidus scene | median ms | p95 ms | iterations a step | note | time against the first row of its run | run |",
                "|---|---|---|---|---|---|---|"] + rows + [""] + [f"- {k}: {cmd(k)}" for k in used]
        block("perf-knobs", body)

    def factor_parts(text):
        """bench_factor's figures: CHOLMOD's own factorizations, and DirectSolver's free and held."""
        out = {}
        for kind, label in (("simplicial", r"simplicial LDL\^T"), ("supernodal", r"supernodal LL\^T \(AMD\)")):
            m = re.search(label + r"\s+analyse\s+([\d.]+) ms\s+factor\s+([\d.]+) ms\s+solve 1 rhs\s+([\d.]+) ms",
                          text or "")
            if m:
                out[kind] = tuple(float(x) for x in m.groups())
        for key, head in (("free", "no node held"), ("held", "the lowest fifth held")):
            i = (text or "").find("DirectSolver, " + head)
            if i < 0:
                continue
            part = text[i:]
            j = part.find("DirectSolver, ", 10)
            part = part[:j] if j > 0 else part
            f = {}
            for name, pat in (("nnz", r"\(([\d.]+) M nonzeros in L\)"), ("flops", r"([\d.e+]+) flops"),
                              ("analyse", r"analyse ([\d.]+) ms"), ("again", r"ordering known: ([\d.]+) ms"),
                              ("factor", r"\), factor ([\d.]+) ms"), ("cholmod", r"cholmod_solve2 ([\d.]+) ms"),
                              ("hand", r"by hand ([\d.]+) ms"), ("single", r"single precision ([\d.]+) ms"),
                              ("half", r"half precision ([\d.]+) ms"),
                              ("half_diff", r"half precision [\d.]+ ms \([\d.]+x single, difference ([\d.e+-]+)\)"),
                              ("columns", r"(\d+) nodes in ([\d.]+) ms")):
                m = re.search(pat, part)
                if m:
                    f[name] = m.group(1) if name != "columns" else (m.group(1), m.group(2))
            out[key] = f
        return out

    fa, fo = factor_parts(read_text(folder, "factor")), factor_parts(read_text(folder, "factor_omp"))
    if fa.get("held"):
        fr, he = fa.get("free", {}), fa["held"]

        def both(fn):
            return f"{fn(fr) if fr else '-'} | {fn(he)}"

        body = ["| the nidus system (`DirectSolver`: CHOLMOD, supernodal) | no node held | its lowest fifth held "
                "(the benchmark's scene) |", "|---|---|---|",
                "| nonzeros in L; flops a factorization | " + both(lambda f: f"{f.get('nnz')} M; {f.get('flops')}") + " |",
                "| the first analysis (it finds the ordering); again, the ordering known (ms) | "
                + both(lambda f: f"{f.get('analyse')}; {f.get('again')}") + " |",
                "| a factorization, one thread (ms) | " + both(lambda f: f"**{f.get('factor')}**") + " |"]
        f4 = fo.get("held", {}).get("factor")
        if f4:
            f1 = float(he["factor"])
            body.append(f"| the same with CHOLMOD's OpenMP threads (4 in Debian's build) on the same core (ms) | "
                        f"{fo.get('free', {}).get('factor', '-')} | {f4} ({float(f4) / f1:.1f}x) |")
        body += ["| a solve pair with the factor: `cholmod_solve2`; by hand in double; single; half precision (ms) | "
                 + both(lambda f: f"{f.get('cholmod')}; {f.get('hand')}; {f.get('single')}; **{f.get('half')}**") + " |",
                 "| the half-precision pair's relative difference from the double one | "
                 + both(lambda f: f"{f.get('half_diff')}") + " |",
                 "| the half columns of " + (he.get("columns", ("?", ""))[0]) + " contact nodes (ms) | "
                 + both(lambda f: f"{f.get('columns', ('', '-'))[1]}") + " |"]
        sn, sp = fa.get("supernodal"), fa.get("simplicial")
        if sn and sp:
            body.append(f"| CHOLMOD's supernodal LL^T against its simplicial LDL^T (AMD ordering, no node held): "
                        f"factorization (ms) | {sn[1]} against {sp[1]} ({sp[1] / sn[1]:.1f}x) | |")
        body += ["", f"- {cmd('factor')}"] + ([f"- {cmd('factor_omp')}"] if f4 else [])
        block("perf-factor", body)

    srows = []
    for name, label in (("servo_idle", "nothing (`idle`)"), ("servo", "the nidus, factored sweep, `refactor_interval = 0`")):
        t = read_text(folder, name)
        if not t:
            continue
        sps = re.search(r"\(([\d.]+) steps/s\)", t)
        fifo = "SCHED_FIFO 80" if "SCHED_FIFO 80" in t else "fair scheduler"
        cost = re.search(r"poll cost \(us\):\s+median ([\d.]+)\s+p99 ([\d.]+)", t)
        late = re.search(r"late \(ms\):\s+median [\d.]+\s+p99 ([\d.]+)\s+p99.9 ([\d.]+)\s+max ([\d.]+).*?(\d+) of (\d+) cycles",
                         t)
        if not (cost and late):
            continue
        srows.append(f"| {label} | {sps.group(1) if sps and name != 'servo_idle' else '-'} | {cost.group(1)} / "
                     f"{cost.group(2)} | {late.group(1)} / {late.group(2)} / {late.group(3)} | {late.group(4)} of "
                     f"{late.group(5)} | {fifo} |")
    if srows:
        body = ["| stepping alongside | steps/s | one poll, median / p99 (us) | late, p99 / p99.9 / max (ms) "
                "| cycles late by > 0.5 ms | servo thread |", "|---|---|---|---|---|---|"] + srows + [""]
        body += [f"- {cmd(n)}" for n in ("servo_idle", "servo") if n in cmds]
        block("perf-servo", body)

    scal, _ = read(os.path.join(folder, "scaling.csv"))
    if scal:
        body = ["| cells | nodes | tets | median ms | p95 ms | iterations a step | ms per iteration "
                "| memory held (B per tet) | rotations, elements, solve (mean ms) |",
                "|---|---|---|---|---|---|---|---|---|"]
        for r_ in scal:
            body.append(f"| {r_['cells']}^3 | {r_['nodes']} | {r_['tets']} | {g(r_['ms_median'])} | {g(r_['ms_p95'])} | "
                        f"{g(r_['iterations'], '{:.1f}')} | {g(r_['ms_per_iteration'], '{:.3g}')} | "
                        f"{g(r_.get('mem_held_B_per_tet'), '{:.0f}')} | {g(r_.get('ms_rotations'), '{:.2f}')}, "
                        f"{g(r_.get('ms_elements'), '{:.2f}')}, {g(r_.get('ms_solve'), '{:.3g}')} |")
        body += ["", f"Command: {cmd('scaling')}"]
        block("perf-scaling", body)
    return lines


def main(folder):
    rows, c_sweep = read(os.path.join(folder, "sweep.csv"))
    steps, _ = read(os.path.join(folder, "stiffness_steps.csv"))
    anchor_rows, c_anchor = read(os.path.join(folder, "anchors.csv"))
    curve, _ = read(os.path.join(folder, "hertz_curve.csv"))
    filt, c_filter = read(os.path.join(folder, "filter.csv"))
    samples, _ = read(os.path.join(folder, "filter_samples.csv"))
    scal, c_scal = read(os.path.join(folder, "scaling.csv"))
    contact, c_contact = read(os.path.join(folder, "contact.csv"))
    uni, c_uni = read(os.path.join(folder, "uniaxial.csv"))
    if rows:
        error_vs_time(rows, folder)
        iterations_vs_tolerance(rows, folder)
        figure2(rows, steps, folder)
        knobs(rows, folder)
    figure1(samples, filt, folder)
    anchors(anchor_rows, curve, folder)
    material(rows, uni, folder)
    scaling(scal, folder)
    tables(rows, anchor_rows, filt, scal,
           {"sweep": c_sweep, "anchors": c_anchor, "filter": c_filter, "scaling": c_scal, "contact": c_contact,
            "uniaxial": c_uni}, folder, contact, uni)
    extra = perf_lines(folder)
    if extra:
        with open(os.path.join(folder, "tables.md"), "a") as f:
            f.write("\n## Performance (docs/performance.md)\n" + "\n".join(extra) + "\n")
    print(f"plots and tables.md in {folder}")


if __name__ == "__main__":
    main(sys.argv[1])
