#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# What accuracy costs in time, and what a step costs: builds what is missing, runs the study and
# draws it. Output: out/study/*.csv, out/study/*.png, out/study/*.txt (the benchmarks' own
# output), out/study/tables.md (every table of docs/accuracy-vs-time.md and docs/performance.md,
# between <!-- study:begin NAME --> / <!-- study:end NAME --> markers), out/study/logs/*.log.
# At the end scripts/study_docs.py says which generated tables in docs/ differ from this run's
# (`python3 scripts/study_docs.py out/study --update` copies them in).
#
#   scripts/study.sh            the whole study: a few minutes on a 2-core machine
#   scripts/study.sh perf       the performance part only (docs/performance.md: the nidus scene,
#                               the default world against the other solvers, the factorization,
#                               the servo loop, the scaling curve): about a minute once built
#   scripts/study.sh quick      a smoke test: a few configurations of each part
#
# Environment: MICA_STUDY_BUILD (default ./build-study) is the CMake build folder;
# MICA_STUDY_OUT (default ./out/study) the output folder; MICA_STUDY_JOBS (default 2) the
# build's parallel jobs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mode=${1:-full}
build=${MICA_STUDY_BUILD:-$root/build-study}
out=${MICA_STUDY_OUT:-$root/out/study}
jobs=${MICA_STUDY_JOBS:-2}
case $mode in full | quick | perf) ;; *) echo "usage: scripts/study.sh [full|perf|quick]" >&2; exit 2 ;; esac
mkdir -p "$out/logs"
rm -f "$out/logs/times.txt.new"
: >"$out/commands.txt" # name|command of each stage run, for the tables (study_plots.py)
export OPENBLAS_NUM_THREADS=1 OMP_THREAD_LIMIT=1 # CHOLMOD: BLAS and OpenMP on the calling thread, like the step
start=$SECONDS

# ---- build (libmica, the benchmarks, the study programs) when missing or out of date
echo "study: building in $build (log: $out/logs/build.log)"
{
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMICA_BUILD_DOCS=OFF -DMICA_BUILD_TESTS=OFF \
    -DMICA_BUILD_EXAMPLES=OFF -DMICA_BUILD_BENCH=ON
  cmake --build "$build" -j "$jobs" --target mica bench_nidus bench_servo bench_factor
  [[ $mode == perf ]] || cmake --build "$build" -j "$jobs" --target bench_contact
} >"$out/logs/build.log" 2>&1 || { tail -20 "$out/logs/build.log"; exit 1; }
bin="$build/study-bin"
mkdir -p "$bin"
study_programs=(study_sweep study_anchors study_filter)
[[ $mode == perf ]] && study_programs=()
# bench/CMakeLists.txt builds them (add_subdirectory(study)), with the scene builders of scenes/.
if ((${#study_programs[@]})); then
  cmake --build "$build" -j "$jobs" --target "${study_programs[@]}" >>"$out/logs/build.log" 2>&1 ||
    { tail -20 "$out/logs/build.log"; exit 1; }
fi
for p in "${study_programs[@]}"; do cp "$build/bench/study/$p" "$bin/$p"; done
nidus_bin="$build/bench/bench_nidus"
contact_bin="$build/bench/bench_contact"
servo_bin="$build/bench/bench_servo"
factor_bin="$build/bench/bench_factor"
pin=""
# "One core" for the step (the nidus, the default world, the factorization, the scaling curve);
# the refreshed nidus is not pinned (its factor thread runs beside the step), nor the servo loop
# (its thread and the stepping thread, two cores). The nidus's Gauss-Seidel comparison, hundreds
# of times slower, is bench_nidus's own job (the Gauss-Seidel sweep is in the `defaults` stage).
command -v taskset >/dev/null && pin="taskset -c 1"
echo "study: built in $((SECONDS - start)) s"

# ---- the stages: name, weight (expected CPU seconds, for the bar), command
quick=()
[[ $mode == quick ]] && quick=(quick)
mesh="$root/data/nidus/nidus.msh"
nidus_steps=(200 40) # timed, warm-up
defaults_steps=110
servo_s=20
scaling_max=110000
contact_set="--quick" # force quality: 12 cells, dt 10 ms, every tool, exact and MICA factored (docs/accuracy-vs-time.md)
if [[ $mode == quick ]]; then
  nidus_steps=(10 30)
  defaults_steps=5
  servo_s=2
  scaling_max=20000
  contact_set="--cells 8 --dt 20 --no-nidus"
fi
# The performance part (docs/performance.md); each stage's output is copied to $out/<stage>.txt.
perf_stages=(
  "nidus|4|$pin $nidus_bin $mesh 1e-6 ${nidus_steps[0]} ${nidus_steps[1]} 1e4 0.01 0 0"
  "refresh|6|$nidus_bin $mesh 1e-6 ${nidus_steps[0]} ${nidus_steps[1]} 1e4 0.01 0 6"
  "linear|3|$pin $nidus_bin $mesh 1e-6 ${nidus_steps[0]} ${nidus_steps[1]} 1e4 0.01 0 0 linear"
  "defaults|8|$pin $nidus_bin --defaults $mesh $defaults_steps"
  "factor|2|$pin $factor_bin $mesh"
  "factor_omp|3|env -u OMP_THREAD_LIMIT $pin $factor_bin $mesh"
  "servo_idle|$servo_s|$servo_bin $servo_s idle"
  "servo|$servo_s|$servo_bin $servo_s $mesh 0"
)
stages=(
  "sweep|250|$bin/study_sweep $out ${quick[*]:-}"
  "anchors|90|$bin/study_anchors $out ${quick[*]:-}"
  "filter|35|$bin/study_filter $out"
  "${perf_stages[@]}"
  "scaling|15|$pin $nidus_bin --scaling $out/scaling.csv $scaling_max factored"
  "contact|90|$pin $contact_bin $contact_set --csv $out/contact.csv"
  "plots|6|/usr/bin/python3 $root/scripts/study_plots.py $out"
)
if [[ $mode == perf ]]; then
  stages=(
    "${perf_stages[@]}"
    "scaling|15|$pin $nidus_bin --scaling $out/scaling.csv $scaling_max factored"
    "plots|6|/usr/bin/python3 $root/scripts/study_plots.py $out"
  )
fi
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
  case $name in sweep | anchors | filter | scaling | contact | plots) ;; *) cp "$log" "$out/$name.txt" ;; esac
  # The command as the docs print it: the environment above, build/ for the build folder, paths
  # from the source tree.
  echo "$name|OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 $cmd" | sed "s|$build/bench/|build/bench/|g; s|$root/||g" \
    >>"$out/commands.txt"
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
[[ $mode == perf ]] || cp "$out/logs/contact.log" "$out/contact.txt"
echo "study: done in $((SECONDS - start)) s; stage times in $out/logs/times.txt"
echo "  CSV: $(cd "$out" && ls *.csv | tr '\n' ' ')"
echo "  PNG: $(cd "$out" && ls *.png | tr '\n' ' ')"
echo "  tables for the docs: $out/tables.md; the benchmarks' output: $out/*.txt"
# Which generated tables in docs/ this run would change (a report; the docs are not touched).
/usr/bin/python3 "$root/scripts/study_docs.py" "$out" || true
