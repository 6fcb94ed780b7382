#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fuzzes the mesh loaders, the C API and the file formats a user receives from others (saved
# states, recordings) with libFuzzer (clang, ASan + UBSan) for a bounded time:
#   bash scripts/fuzz.sh                      # each target FUZZ_SECONDS (default 60) seconds,
#                                             # fuzz_api FUZZ_API_SECONDS (default the same)
#   FUZZ_SECONDS=300 bash scripts/fuzz.sh     # longer
#   FUZZ_TARGETS="fuzz_gmsh" bash scripts/fuzz.sh
#   FUZZ_SECONDS=0 bash scripts/fuzz.sh       # no fuzzing: only run the seeds and learned corpus
# Targets (fuzz/): fuzz_gmsh, fuzz_tetgen, fuzz_mesh_build, fuzz_api (sequences of C API calls
# on twin worlds; fuzz/README.md), fuzz_state (mica_world_restore_state), fuzz_recording
# (mica_replay_open and _step). Seeds come from fuzz/corpus/<kind>/
# (read only); what the fuzzer learns goes to <build>/corpus/<target>/ and is kept between runs.
# A crashing input is saved as fuzz/crashes/<target>-crash-<sha1> (or -leak-, -timeout-, -oom-),
# printed in base64, and makes the script exit 1 after the other targets have run.
# Reproduce one: <build>/<target> fuzz/crashes/<file>; shrink it:
#   <build>/<target> -minimize_crash=1 -runs=100000 -exact_artifact_path=min fuzz/crashes/<file>
# Then turn it into a case of tests/mesh/test_fuzz_regressions.cpp and delete the file.
#
# Installs nothing. Needs the Debian 12 packages clang-14, libclang-rt-14-dev and
# libeigen3-dev (llvm-14 too for symbolized stack traces); fuzz_api also libsuitesparse-dev and
# libccd-dev (the main build's), and so do fuzz_state and fuzz_recording.
# Environment: FUZZ_SECONDS, FUZZ_API_SECONDS, FUZZ_TARGETS, FUZZ_BUILD_DIR (default build-fuzz/), FUZZ_CXX (the
# clang++ to use), FUZZ_JOBS (build parallelism, default nproc), FUZZ_CRASH_DIR (default
# fuzz/crashes/).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${FUZZ_SECONDS:-60}
targets=${FUZZ_TARGETS:-fuzz_gmsh fuzz_tetgen fuzz_mesh_build fuzz_api fuzz_state fuzz_recording}
api_seconds=${FUZZ_API_SECONDS:-$seconds}
build=${FUZZ_BUILD_DIR:-$root/build-fuzz}
crashes=${FUZZ_CRASH_DIR:-$root/fuzz/crashes}
packages="clang-14 libclang-rt-14-dev libeigen3-dev (and llvm-14 for symbolized traces)"

if [[ -n "${FUZZ_CXX:-}" ]]; then
  cxx=$FUZZ_CXX
elif command -v clang++-14 >/dev/null 2>&1; then
  cxx=clang++-14
elif command -v clang++ >/dev/null 2>&1; then
  cxx=clang++
else
  echo "fuzz.sh: no clang++ found; install the Debian packages: $packages" >&2
  exit 2
fi
# llvm-symbolizer (llvm-14) turns the sanitizers' addresses into file:line; optional.
for s in llvm-symbolizer-14 llvm-symbolizer; do
  if command -v "$s" >/dev/null 2>&1; then
    export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-$(command -v "$s")}
    break
  fi
done

mkdir -p "$build"
if ! cmake -S "$root/fuzz" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" \
  >"$build/configure.log" 2>&1; then
  cat "$build/configure.log" >&2
  echo "fuzz.sh: configuring fuzz/ failed; the Debian packages needed: $packages" >&2
  exit 2
fi
cmake --build "$build" -j "${FUZZ_JOBS:-$(nproc 2>/dev/null || echo 2)}"

# Sanitizer reports abort (UBSan is built with -fno-sanitize-recover); leaks count.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

for s in "$seconds" "$api_seconds"; do
  if [[ ! $s =~ ^[0-9]+$ ]]; then
    echo "fuzz.sh: FUZZ_SECONDS and FUZZ_API_SECONDS must be whole numbers of seconds, got '$s'" >&2
    exit 2
  fi
done

mkdir -p "$crashes"
failed=()
for target in $targets; do
  case "$target" in
    fuzz_gmsh) seeds=("$root/fuzz/corpus/gmsh"); dict=gmsh ;;
    fuzz_tetgen) seeds=("$root/fuzz/corpus/tetgen"); dict=tetgen ;;
    fuzz_mesh_build) seeds=("$root/fuzz/corpus/gmsh" "$root/fuzz/corpus/tetgen"); dict=mesh_build ;;
    fuzz_api) seeds=("$root/fuzz/corpus/api"); dict= ;;
    fuzz_state) seeds=("$root/fuzz/corpus/state"); dict= ;;
    fuzz_recording) seeds=("$root/fuzz/corpus/recording"); dict= ;;
    *) echo "fuzz.sh: unknown target '$target'" >&2; exit 2 ;;
  esac
  if [[ ! -x "$build/$target" ]]; then
    echo "fuzz.sh: $build/$target was not built (see $build/configure.log)" >&2
    failed+=("$target")
    continue
  fi
  s=$seconds
  [[ $target == fuzz_api ]] && s=$api_seconds
  # libFuzzer takes -max_total_time=0 as "no limit": 0 means run the corpus once instead.
  if ((s == 0)); then budget=(-runs=0); else budget=(-max_total_time="$s"); fi
  options=()
  [[ -n $dict ]] && options+=(-dict="$root/fuzz/dict/$dict.dict")
  # fuzz_api: a program's steps may take seconds under ASan on a loaded machine (it stops after 2 s
  # of them): a longer timeout, so that a slow valid scene is not reported as a hang.
  # The file targets: their seeds are a few KB, each run makes a world and steps it.
  case "$target" in
    fuzz_api) options+=(-max_len=4096 -timeout=30) ;;
    fuzz_state | fuzz_recording) options+=(-max_len=16384 -timeout=30) ;;
    *) options+=(-max_len=65536 -timeout=10) ;;
  esac
  work="$build/corpus/$target"
  mkdir -p "$work"
  before=$(find "$crashes" -maxdepth 1 -type f -name "$target-*" | sort)
  echo "=== $target: ${s}s"
  status=0
  "$build/$target" "$work" "${seeds[@]}" "${options[@]}" \
    "${budget[@]}" -rss_limit_mb=2048 \
    -artifact_prefix="$crashes/$target-" -print_final_stats=1 \
    >"$build/$target.log" 2>&1 || status=$?
  # The final lines: coverage, corpus size, executions (and the report of a crash).
  if [[ $status -eq 0 ]]; then
    grep -E '^(#[0-9]+[[:space:]]+DONE|Done [0-9]+ runs|stat::peak_rss_mb)' "$build/$target.log" ||
      tail -n 5 "$build/$target.log"
    continue
  fi
  failed+=("$target")
  echo "--- $target FAILED (exit $status); the fuzzer's report, from $build/$target.log:"
  report=$(sed -n '/^==[0-9]*== \{0,1\}ERROR\|runtime error\|==== mica fuzz/,$p' \
    "$build/$target.log")
  if [[ -n "$report" ]]; then head -n 120 <<<"$report"; else tail -n 60 "$build/$target.log"; fi
  after=$(find "$crashes" -maxdepth 1 -type f -name "$target-*" | sort)
  new=$(comm -13 <(printf '%s\n' "$before") <(printf '%s\n' "$after") | sed '/^$/d')
  for file in $new; do
    echo "--- new crasher $file ($(wc -c <"$file") bytes), base64:"
    base64 -w 76 "$file" | head -n 200
  done
  [[ -n "$new" ]] || echo "--- (no new file under fuzz/crashes: the same input was saved before)"
done

if ((${#failed[@]})); then
  echo "fuzz.sh: FAILED: ${failed[*]}; crashers in $crashes" >&2
  exit 1
fi
echo "fuzz.sh: no crash in: $targets (${seconds}s each, fuzz_api ${api_seconds}s)"
