#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Turns the CSVs the stress tests write (tests/stress, one line per run) into the markdown tables
of docs/stability.md.

    python3 scripts/stability_table.py BUILD/stress/full-*.csv [BUILD/stress/long-run.csv]
        prints the tables
    python3 scripts/stability_table.py --update docs/stability.md BUILD/stress/full-*.csv ...
        replaces what lies between the markers <!-- stability:begin --> and
        <!-- stability:end --> in that file

Standard library only.
"""
import argparse
import csv
import math
import sys
from collections import OrderedDict, defaultdict

SCENARIOS = OrderedDict([
    ("a", "fall onto a static slab"),
    ("b", "sphere pressed to half depth"),
    ("c", "grasped face twisted 180 deg, released"),
    ("d", "inverted elements at start"),
    ("e", "sliver elements (aspect ~2000)"),
    ("f", "plane on 256 nodes at once"),
    ("g", "projection and contact on the same nodes"),
    ("h", "tool at 10 m/s through a thin slab"),
    ("i", "two deformable bodies pressed together"),
    ("L", "long run: virtual hand, 100000 steps"),
])
BEGIN, END = "<!-- stability:begin -->", "<!-- stability:end -->"


def num(row, key):
    try:
        return float(row[key])
    except (KeyError, ValueError):
        return float("nan")


def fmt(x, digits=2):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if x == 0:
        return "0"
    if abs(x) >= 1e4 or abs(x) < 1e-3:
        return f"{x:.{digits - 1}e}".replace("e-0", "e-").replace("e+0", "e")
    return f"{x:.{digits}g}" if abs(x) < 10 else f"{x:.0f}"


def sci(x):
    return f"{x:.1e}".replace(".0e", "e").replace("e+0", "e").replace("e-0", "e-")


def read(paths):
    rows = []
    for p in paths:
        with open(p, newline="") as f:
            rows.extend(csv.DictReader(f))
    return rows


def issues_of(sel):
    found = set()
    for r in sel:
        note = r.get("notes", "")
        if "known issues:" in note:
            found.update(note.split("known issues:")[1].split(";")[0].split())
    return " ".join(sorted(found)) or "-"


def groups_of(rows):
    groups = OrderedDict()
    for key in SCENARIOS:
        for solver in ("mica", "direct"):
            sel = [r for r in rows if r["scenario"] == key and r["solver"] == solver]
            if sel:
                groups[(key, solver)] = sel
    return groups


def summary(rows):
    """Two tables, one line per scenario and solver: what ran, then the worst values."""
    groups = groups_of(rows)
    out = ["| scenario | solver | runs | E (Pa) | nu | h (s) | steps | non-converged steps (runs) | "
           "hidden non-converged steps (runs) | worst residual of a step reported converged | "
           "ok / known / FAIL | known issues | CPU s |",
           "|" + "---|" * 13]
    for (key, solver), sel in groups.items():
        E = sorted({num(r, "E") for r in sel})
        nu = sorted({num(r, "nu") for r in sel})
        h = sorted({num(r, "h") for r in sel})
        steps = sum(int(r["steps"]) for r in sel)
        nc = sum(int(r["nonconverged"]) for r in sel)
        nc_runs = sum(1 for r in sel if int(r["nonconverged"]) > 0)
        hid = sum(int(r["hidden_nonconverged"]) for r in sel)
        hid_runs = sum(1 for r in sel if int(r["hidden_nonconverged"]) > 0)
        status = {s: sum(1 for r in sel if r["status"] == s) for s in ("ok", "known", "FAIL")}
        E_cell = f"{sci(E[0])}..{sci(E[-1])}" if len(E) > 1 else sci(E[0])
        nu_cell = ", ".join(f"{x:g}" for x in nu)
        h_cell = ", ".join(sci(x) for x in h)
        out.append(
            f"| {key} {SCENARIOS[key]} | {solver} | {len(sel)} | {E_cell} | {nu_cell} | {h_cell} | {steps} | "
            f"{nc} ({nc_runs}) | {hid} ({hid_runs}) | {fmt(max(num(r, 'residual') for r in sel))} | "
            f"{status['ok']} / {status['known']} / {status['FAIL']} | {issues_of(sel)} | "
            f"{sum(num(r, 'cpu_s') for r in sel):.1f} |")
    out += ["", "Worst values over the runs of each line (energy as a fraction of the run's energy scale, "
            "penetration as a fraction of the scene's reference length):", ""]
    out += ["| scenario | solver | energy growth, solved steps | energy growth, all steps | recovery allowance used | "
            "penetration, solved steps (ref) | penetration, unsolved steps | active contacts (rows) | "
            "inverted at start, max | slowest recovery after release | runs never recovered | fastest node (m/s) |",
            "|" + "---|" * 12]
    for (key, solver), sel in groups.items():
        ref = num(sel[0], "penetration_ref")
        pen = max(num(r, "penetration") for r in sel)
        pen_nc = max(num(r, "penetration_nonconverged") for r in sel)
        pen_cell = "-" if not ref else f"{fmt(pen / ref)} ({ref * 1000:g} mm)"
        pen_nc_cell = "-" if not ref else fmt(pen_nc / ref)
        recovered = [(int(r["recovery_steps"]) * num(r, "h"), r) for r in sel if int(r["recovery_steps"]) >= 0
                     and int(r["recovery_budget"]) > 0]
        never = sum(1 for r in sel if int(r["recovery_budget"]) > 0 and int(r["recovery_steps"]) == -2)
        if recovered:
            t, r = max(recovered, key=lambda x: x[0])
            rec_cell = f"{int(r['recovery_steps'])} steps = {t:.3g} s (E {sci(num(r, 'E'))}, h {r['h']})"
        else:
            rec_cell = "-"
        budgets = any(int(r["recovery_budget"]) > 0 for r in sel)
        inv = f"{max(int(r['inverted_start']) for r in sel)}, {max(int(r['max_inverted']) for r in sel)}"
        contacts = f"{max(int(r['max_contacts']) for r in sel)} ({max(int(r['max_rows']) for r in sel)})"
        out.append(
            f"| {key} | {solver} | {fmt(max(num(r, 'energy_ratio') for r in sel))} | "
            f"{fmt(max(num(r, 'energy_ratio_all') for r in sel))} | {fmt(max(num(r, 'recovery_ratio') for r in sel))} | "
            f"{pen_cell} | {pen_nc_cell} | {contacts} | {inv} | {rec_cell} | {never if budgets else '-'} | "
            f"{fmt(max(num(r, 'max_speed') for r in sel))} |")
    return out


def grids(rows):
    """Per scenario (MICA): E down, h across; each cell counts the Poisson ratios that failed."""
    out = []
    for key in SCENARIOS:
        sel = [r for r in rows if r["scenario"] == key and r["solver"] == "mica"]
        Es = sorted({num(r, "E") for r in sel})
        hs = sorted({num(r, "h") for r in sel})
        if len(Es) < 2 or len(hs) < 2:
            continue
        out.append(f"**{key}: {SCENARIOS[key]}** (MICA; cell: runs failed / known / with non-converged steps, "
                   f"of {len({num(r, 'nu') for r in sel})} Poisson ratios)")
        out.append("")
        out.append("| E \\ h | " + " | ".join(sci(h) for h in hs) + " |")
        out.append("|---|" + "---|" * len(hs))
        for E in Es:
            cells = []
            for h in hs:
                cell = [r for r in sel if num(r, "E") == E and num(r, "h") == h]
                f = sum(1 for r in cell if r["status"] == "FAIL")
                k = sum(1 for r in cell if r["status"] == "known")
                n = sum(1 for r in cell if int(r["nonconverged"]) > 0)
                cells.append(f"{f} / {k} / {n}")
            out.append(f"| {sci(E)} | " + " | ".join(cells) + " |")
        out.append("")
    return out


def render(rows):
    lines = ["Worst values per scenario and solver (generated by scripts/stability_table.py from the "
             "stress tests' CSV; do not edit by hand).", ""]
    lines += summary(rows)
    lines += ["", ""]
    lines += grids(rows)
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--update", metavar="MARKDOWN", help="replace the generated block of this file")
    ap.add_argument("csv", nargs="+")
    args = ap.parse_args()
    text = render(read(args.csv))
    if not args.update:
        sys.stdout.write(text)
        return 0
    with open(args.update) as f:
        doc = f.read()
    if BEGIN not in doc or END not in doc:
        sys.exit(f"{args.update}: markers {BEGIN} / {END} not found")
    head, rest = doc.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    with open(args.update, "w") as f:
        f.write(head + BEGIN + "\n" + text + END + tail)
    return 0


if __name__ == "__main__":
    sys.exit(main())
