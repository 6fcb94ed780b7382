#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The table of docs/cutting.md "What a cut costs": bench_incision run three times, pinned to one
core, its figures side by side.

Writes <folder>/tables.md (default out/incision) with the block `cutting-cost` between the
markers scripts/study_docs.py copies into the docs, and prints it:

    python3 scripts/incision_table.py [folder] [--runs N]
    python3 scripts/study_docs.py out/incision --update --only cutting-cost

Run from the repository root after a build (build/bench/bench_incision).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

FIGURES = [  # (row, pattern, goal)
    ("cut median (ms)", r"cut median ([\d.]+)", ""),
    ("uncut median (ms)", r"uncut median ([\d.]+)", ""),
    ("cut/uncut median ratio", r"cut/uncut median ratio ([\d.]+)", "<= 1.5"),
    ("cut p99 (ms)", r"cut median [\d.]+ p99 ([\d.]+)", ""),
    ("uncut p99 (ms)", r"uncut median [\d.]+ p99 ([\d.]+)", ""),
    ("cut/uncut p99 ratio", r"cut/uncut p99 ratio ([\d.]+)", "<= 2.0"),
    ("steps that waited for a factorization", r"waited for a factorization (\d+)", "== 0"),
    ("blade force's largest step-to-step jump (N)", r"step-to-step jump ([\d.]+)", ""),
]


def verdict(goal, values):
    if not goal:
        return ""
    op, limit = goal.split()
    met = [float(v) <= float(limit) if op == "<=" else float(v) == float(limit) for v in values]
    goal = goal if op == "<=" else limit
    if all(met):
        return goal + ": met"
    if not any(met):
        return goal + ": not met"
    return f"{goal}: met in {sum(met)} runs of {len(met)}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", default="out/incision")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    command = ["build/bench/bench_incision"]
    if shutil.which("taskset"):
        command = ["taskset", "-c", "1"] + command
    env = dict(os.environ, OMP_THREAD_LIMIT="1", OPENBLAS_NUM_THREADS="1")
    outputs = []
    for k in range(args.runs):
        run = subprocess.run(command, env=env, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"bench_incision failed:\n{run.stderr}")
        outputs.append(run.stdout)
        print(run.stdout, end="", file=sys.stderr)
    load = re.search(r"load average ([\d.]+)", outputs[0])
    rows = ["| figure | " + " | ".join(f"run {k + 1}" for k in range(args.runs)) + " | goal |",
            "|---|" + "---|" * args.runs + "---|"]
    for name, pattern, goal in FIGURES:
        values = [re.search(pattern, out).group(1) for out in outputs]
        rows.append(f"| {name} | " + " | ".join(values) + f" | {verdict(goal, values)} |")
    cuts = re.search(r"cuts made (\d+), node copies (\d+)", outputs[0])
    text = ("<!-- study:begin cutting-cost -->\n"
            f"`OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_incision`, {args.runs} runs "
            f"(load average {load.group(1) if load else '?'} at the first; {cuts.group(1)} cuts, {cuts.group(2)} node copies):\n\n"
            + "\n".join(rows) + "\n<!-- study:end cutting-cost -->\n")
    os.makedirs(args.folder, exist_ok=True)
    with open(os.path.join(args.folder, "tables.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
