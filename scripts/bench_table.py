#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""A benchmark's table for the docs: the benchmark run three times, pinned to one core, its figures
side by side with their goals.

    python3 scripts/bench_table.py incision [folder] [--runs N]   # docs/cutting.md, "What a cut costs"
    python3 scripts/bench_table.py embedding [folder] [--runs N]  # docs/embedding.md, "How fast"

Writes <folder>/tables.md (default out/<bench>) with the block (`cutting-cost`, `embedding-cost`)
between the markers scripts/study_docs.py copies into the docs, and prints it:

    python3 scripts/study_docs.py out/incision --update --only cutting-cost
    python3 scripts/study_docs.py out/embedding --update --only embedding-cost

Run from the repository root after a build (build/bench/bench_<bench>).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

BENCHES = {
    "incision": {
        "block": "cutting-cost",
        "figures": [  # (row, pattern, goal)
            ("cut median (ms)", r"cut median ([\d.]+)", ""),
            ("uncut median (ms)", r"uncut median ([\d.]+)", ""),
            ("cut/uncut median ratio", r"cut/uncut median ratio ([\d.]+)", "<= 1.5"),
            ("cut p99 (ms)", r"cut median [\d.]+ p99 ([\d.]+)", ""),
            ("uncut p99 (ms)", r"uncut median [\d.]+ p99 ([\d.]+)", ""),
            ("cut/uncut p99 ratio", r"cut/uncut p99 ratio ([\d.]+)", "<= 2.0"),
            ("steps that waited for a factorization", r"waited for a factorization (\d+)", "== 0"),
            ("blade force's largest step-to-step jump (N)", r"step-to-step jump ([\d.]+)", ""),
        ],
        "scene": (r"cuts made (\d+), node copies (\d+)", "{} cuts, {} node copies"),
    },
    "embedding": {
        "block": "embedding-cost",
        "figures": [
            ("update median (ms)", r"update median ms ([\d.]+)", "<= 1"),
            ("update median, CPU time (ms)", r"thread: update median ms ([\d.]+)", ""),
            ("memory bandwidth, memcpy (GB/s)", r"at ([\d.]+) GB/s", ""),
            ("bandwidth ratio", r"bandwidth ratio ([\d.]+)", "<= 3"),
            ("bind (ms)", r"bind ms ([\d.]+)", "<= 100"),
        ],
        "scene": (r"mesh: (\d+) vertices, (\d+) triangles", "{} vertices, {} triangles"),
    },
}


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
    parser.add_argument("bench", choices=sorted(BENCHES))
    parser.add_argument("folder", nargs="?")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    bench = BENCHES[args.bench]
    folder = args.folder or os.path.join("out", args.bench)
    command = [f"build/bench/bench_{args.bench}"]
    if shutil.which("taskset"):
        command = ["taskset", "-c", "1"] + command
    env = dict(os.environ, OMP_THREAD_LIMIT="1", OPENBLAS_NUM_THREADS="1")
    outputs = []
    for k in range(args.runs):
        run = subprocess.run(command, env=env, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"bench_{args.bench} failed:\n{run.stderr}")
        outputs.append(run.stdout)
        print(run.stdout, end="", file=sys.stderr)
    load = re.search(r"load average ([\d.]+)", outputs[0])
    rows = ["| figure | " + " | ".join(f"run {k + 1}" for k in range(args.runs)) + " | goal |",
            "|---|" + "---|" * args.runs + "---|"]
    for name, pattern, goal in bench["figures"]:
        values = [re.search(pattern, out).group(1) for out in outputs]
        rows.append(f"| {name} | " + " | ".join(values) + f" | {verdict(goal, values)} |")
    pattern, form = bench["scene"]
    scene = form.format(*re.search(pattern, outputs[0]).groups())
    block = bench["block"]
    text = (f"<!-- study:begin {block} -->\n"
            f"`OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_{args.bench}`, {args.runs} runs "
            f"(load average {load.group(1) if load else '?'} at the first; {scene}):\n\n"
            + "\n".join(rows) + f"\n<!-- study:end {block} -->\n")
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, "tables.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
