#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# What accuracy costs in time: builds what is missing, runs the whole study and draws it.
# Output: out/study/*.csv, out/study/*.png, out/study/tables.md, out/study/logs/*.log.
# See docs/accuracy-vs-time.md and docs/performance.md.
#
#   scripts/study.sh            the full study: 4 minutes on a quiet 2-core machine (11 when
#                               it shared the machine with other work, in libmica 0.2), and
#                               about 1.5 more for the force-quality stage (bench_contact --quick)
#   scripts/study.sh quick      a smoke test: a few configurations of each part
#
# Environment: MICA_STUDY_BUILD (default ./build-study) is the CMake build folder;
# MICA_STUDY_OUT (default ./out/study) the output folder.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=${1:-full}
build=${MICA_STUDY_BUILD:-$root/build-study}
out=${MICA_STUDY_OUT:-$root/out/study}
mkdir -p "$out/logs"
rm -f "$out/logs/times.txt.new"
export OPENBLAS_NUM_THREADS=1 OMP_THREAD_LIMIT=1 # CHOLMOD: BLAS and OpenMP on the calling thread, like the step
start=$SECONDS

# ---- build (libmica, bench_nidus, the study programs) when missing or out of date
echo "study: building in $build (log: $out/logs/build.log)"
{
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMICA_BUILD_DOCS=OFF -DMICA_BUILD_TESTS=OFF \
    -DMICA_BUILD_EXAMPLES=OFF -DMICA_BUILD_BENCH=ON
  cmake --build "$build" -j 2 --target mica bench_nidus bench_contact
} >"$out/logs/build.log" 2>&1 || { tail -20 "$out/logs/build.log"; exit 1; }
bin="$build/study-bin"
mkdir -p "$bin"
study_programs=(study_sweep study_anchors study_filter)
# bench/CMakeLists.txt builds them (add_subdirectory(study)), with the scene builders of scenes/.
cmake --build "$build" -j 2 --target "${study_programs[@]}" >>"$out/logs/build.log" 2>&1 ||
  { tail -20 "$out/logs/build.log"; exit 1; }
for p in "${study_programs[@]}"; do cp "$build/bench/study/$p" "$bin/$p"; done
nidus_bin="$build/bench/bench_nidus"
contact_bin="$build/bench/bench_contact"
pin=""
# The scaling benchmark's "one core"; the nidus one is not pinned: its refreshed variant factors on
# a second thread (its Gauss-Seidel comparison, hundreds of times slower, is bench_nidus's own job).
command -v taskset >/dev/null && pin="taskset -c 1"
echo "study: built in $((SECONDS - start)) s"

# ---- the stages: name, weight (expected CPU seconds, for the bar), command
quick=()
[[ $mode == quick ]] && quick=(quick)
nidus_steps=(30 30)
scaling_max=110000
contact_set="--quick" # force quality: 12 cells, dt 10 ms, every tool, exact and MICA factored (docs/accuracy-vs-time.md)
if [[ $mode == quick ]]; then
  nidus_steps=(5 30)
  scaling_max=20000
  contact_set="--cells 8 --dt 20 --no-nidus"
fi
stages=(
  "sweep|250|$bin/study_sweep $out ${quick[*]:-}"
  "anchors|90|$bin/study_anchors $out ${quick[*]:-}"
  "filter|35|$bin/study_filter $out"
  "nidus|45|$nidus_bin $root/data/nidus/nidus.msh 1e-6 ${nidus_steps[0]} ${nidus_steps[1]} 1e4 0.01 0 6"
  "scaling|215|$pin $nidus_bin --scaling $out/scaling.csv $scaling_max factored"
  "contact|90|$pin $contact_bin $contact_set --csv $out/contact.csv"
  "plots|6|/usr/bin/python3 $root/scripts/study_plots.py $out"
)
total=0
for s in "${stages[@]}"; do total=$((total + $(cut -d'|' -f2 <<<"$s"))); done
cols=40
draw() { # draw <fraction 0..1> <label>
  awk -v f="$1" -v label="$2" -v cols=$cols -v el=$((SECONDS - start)) 'BEGIN {
    if (f < 0) f = 0; if (f > 1) f = 1
    n = int(f * cols + 0.5); bar = ""
    for (i = 0; i < cols; ++i) bar = bar (i < n ? "#" : ".")
    printf "\r[%s] %3d%%  %-8s %4d s ", bar, int(100 * f + 0.5), label, el
  }' >&2
}
has_tty=0
[[ -t 2 ]] && has_tty=1 # the bar on a terminal; one line per stage in a log
done_weight=0
for s in "${stages[@]}"; do
  name=$(cut -d'|' -f1 <<<"$s")
  weight=$(cut -d'|' -f2 <<<"$s")
  cmd=$(cut -d'|' -f3- <<<"$s")
  log="$out/logs/$name.log"
  t0=$SECONDS
  if [[ $has_tty == 1 ]]; then
    draw "$(awk -v a=$done_weight -v t=$total 'BEGIN{print a/t}')" "$name"
  else
    echo "study: $name ..."
  fi
  # stdout to the log; stderr's "progress d t" lines move the bar, anything else goes to the log.
  set +e
  $cmd 2>&1 >"$log" | while IFS= read -r line; do
    if [[ $line == progress\ * ]]; then
      read -r _ d t <<<"$line"
      [[ $has_tty == 1 ]] && draw "$(awk -v a=$done_weight -v w=$weight -v d="$d" -v t="$t" -v T=$total \
        'BEGIN{print (a + w * d / t) / T}')" "$name"
    else
      echo "$line" >>"$log"
    fi
  done
  status=${PIPESTATUS[0]}
  set -e
  if [[ $status != 0 ]]; then
    echo
    echo "study: $name failed (exit $status); the end of $log:"
    tail -20 "$log"
    exit 1
  fi
  done_weight=$((done_weight + weight))
  if [[ $has_tty == 1 ]]; then
    draw "$(awk -v a=$done_weight -v t=$total 'BEGIN{print a/t}')" "$name"
  else
    echo "study: $name done in $((SECONDS - t0)) s ($((100 * done_weight / total))%)"
  fi
  echo "$name $((SECONDS - t0)) s" >>"$out/logs/times.txt.new"
done
[[ $has_tty == 1 ]] && echo
mv "$out/logs/times.txt.new" "$out/logs/times.txt"
cp "$out/logs/nidus.log" "$out/nidus.txt"
cp "$out/logs/contact.log" "$out/contact.txt"
echo "study: done in $((SECONDS - start)) s; stage times in $out/logs/times.txt"
echo "  CSV: $(cd "$out" && ls *.csv | tr '\n' ' ')"
echo "  PNG: $(cd "$out" && ls *.png | tr '\n' ' ')"
echo "  tables for the docs: $out/tables.md; the nidus benchmark: $out/nidus.txt; force quality: $out/contact.txt"
