#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The study's tables in the docs: which ones a study run would change, and copying them in.

scripts/study_plots.py writes out/study/tables.md with the tables the docs include between
markers:

    <!-- study:begin NAME -->
    ...
    <!-- study:end NAME -->

A page under docs/ holds the same markers around its copy. This script compares each copy with
the run's block of the same name and reports, per block, whether it is the same, and otherwise
the largest relative change among its numbers (milliseconds move from run to run; iteration
counts and bytes should not).

usage: study_docs.py <study-folder> [--docs DIR] [--update [--only NAME,...]]
  (no option)  report; exit 1 when a block in the docs differs from the run's
  --update     copy the run's blocks into the docs (the blocks only: the prose around them is
               the author's to check against the new figures)
  --only       with --update: copy only these blocks (comma-separated names), when a run is to
               update some tables and the prose of the others still quotes an earlier run
scripts/study.sh runs the report at its end.
"""
import argparse
import glob
import os
import re
import sys

BLOCK = re.compile(r"<!-- study:begin (\S+) -->\n(.*?)<!-- study:end \1 -->", re.S)
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def blocks(text):
    return {m.group(1): m.group(2) for m in BLOCK.finditer(text)}


def drift(old, new):
    """The largest relative change between the numbers of two blocks, and where, or None when the
    words around the numbers differ (a changed layout)."""
    # The line saying when and on which commit a run was made is not a figure.
    old, new = (("\n".join(l for l in t.split("\n") if not l.startswith("Measured "))) for t in (old, new))
    if NUMBER.sub("#", old) != NUMBER.sub("#", new):
        return None
    worst, where = 0.0, ""
    for a, b in zip(NUMBER.findall(old), NUMBER.findall(new)):
        x, y = float(a), float(b)
        if x == y:
            continue
        rel = abs(y - x) / max(abs(x), abs(y))
        if rel > worst:
            worst, where = rel, f"{a} -> {b}"
    return worst, where


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", help="the study's output folder (out/study)")
    ap.add_argument("--docs", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "docs"))
    ap.add_argument("--update", action="store_true", help="copy the run's blocks into the docs")
    ap.add_argument("--only", default="", help="with --update: copy only these blocks (comma-separated names)")
    args = ap.parse_args()
    only = {n for n in args.only.split(",") if n}
    if only and not args.update:
        sys.exit("--only goes with --update")
    tables = os.path.join(args.folder, "tables.md")
    if not os.path.exists(tables):
        sys.exit(f"{tables}: not found (run scripts/study.sh first)")
    with open(tables) as f:
        run = blocks(f.read())
    for n in sorted(only - set(run)):
        print(f"--only {n}: no such block in this run")
    differ = 0
    for page in sorted(glob.glob(os.path.join(args.docs, "*.md"))):
        with open(page) as f:
            text = f.read()
        found = blocks(text)
        if not found:
            continue
        name = os.path.relpath(page, os.path.join(args.docs, ".."))
        for key, old in found.items():
            if key not in run:
                print(f"{name}: {key}: not in this run (a part the run left out)")
                continue
            new = run[key]
            if old == new:
                print(f"{name}: {key}: the same")
                continue
            differ += 1
            d = drift(old, new)
            if d is None:
                print(f"{name}: {key}: differs (its rows or words changed)")
            else:
                print(f"{name}: {key}: differs, the largest change {100 * d[0]:.0f} % ({d[1]})")
        if args.update:
            def copy(m):
                keep = only and m.group(1) not in only
                body = m.group(2) if keep else run.get(m.group(1), m.group(2))
                return f"<!-- study:begin {m.group(1)} -->\n{body}<!-- study:end {m.group(1)} -->"

            new_text = BLOCK.sub(copy, text)
            if new_text != text:
                with open(page, "w") as f:
                    f.write(new_text)
                print(f"{name}: updated")
    if differ and not args.update:
        print(f"{differ} block(s) differ: `python3 scripts/study_docs.py {args.folder} --update` copies this run's in")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
