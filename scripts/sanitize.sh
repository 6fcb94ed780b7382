#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The test suite under a sanitizer, in its own build folder:
#   bash scripts/sanitize.sh address   # AddressSanitizer + UndefinedBehaviorSanitizer, every test
#   bash scripts/sanitize.sh thread    # ThreadSanitizer, the tests labelled "threads"
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:?usage: sanitize.sh address|thread}
case "$kind" in
  address) flags="address;undefined"; select=(); examples=OFF ;;  # the demos: minutes under ASan, run by the main suite
  thread) flags="thread"; select=(-L threads); examples=ON ;;      # haptic_loop is a threaded test
  *) echo "sanitize.sh: unknown sanitizer '$kind' (address or thread)" >&2; exit 2 ;;
esac
bash "$root/scripts/install-deps.sh"
build="$root/build-$kind"
# -O1 -g1: what the sanitizers need (file:line in their stacks) at half -O2 -g's compile time.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMICA_SANITIZE="$flags" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
  -DMICA_BUILD_DOCS=OFF -DMICA_BUILD_BENCH=OFF -DMICA_BUILD_EXAMPLES=$examples >/dev/null
# Only what the selected tests run is built (CI time: the thread build needs a dozen programs).
targets=()
if [[ $kind == thread ]]; then
  # A test's program is its target: <concern>/<name> is <concern>_<name>, examples/<name> is <name>.
  read -r -a targets < <(ctest --test-dir "$build" "${select[@]}" --show-only=json-v1 | python3 -c \
    'import json, sys; print(" ".join(sorted({n.split("/", 1)[1] if n.startswith("examples/") else n.replace("/", "_") for n in (t["name"] for t in json.load(sys.stdin)["tests"])})))')
fi
cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)" ${targets[@]:+--target "${targets[@]}"}
# Leaks count as failures; UBSan stops at the first report (the build sets -fno-sanitize-recover).
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 TSAN_OPTIONS=halt_on_error=1
# OpenBLAS and OpenMP (under CHOLMOD) on the calling thread: their own worker threads are not
# instrumented, and TSan reports their internal hand-offs as races.
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 OMP_THREAD_LIMIT=1
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
# The examples (demos at full size, already run by the main suite) would take minutes under ASan.
ctest --test-dir "$build" --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" "${select[@]}" -LE "packaging|examples|physics"
