#!/usr/bin/env bash
# The test suite under a sanitizer, in its own build folder:
#   bash scripts/sanitize.sh address   # AddressSanitizer + UndefinedBehaviorSanitizer, every test
#   bash scripts/sanitize.sh thread    # ThreadSanitizer, the tests labelled "threads"
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
kind=${1:?usage: sanitize.sh address|thread}
case "$kind" in
  address) flags="address;undefined"; select=() ;;
  thread) flags="thread"; select=(-L threads) ;;
  *) echo "sanitize.sh: unknown sanitizer '$kind' (address or thread)" >&2; exit 2 ;;
esac
bash "$root/scripts/install-deps.sh"
build="$root/build-$kind"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMICA_SANITIZE="$flags" \
  -DMICA_BUILD_DOCS=OFF -DMICA_BUILD_BENCH=OFF >/dev/null
cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)"
# Leaks count as failures; UBSan stops at the first report (the build sets -fno-sanitize-recover).
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 TSAN_OPTIONS=halt_on_error=1
# OpenBLAS and OpenMP (under CHOLMOD) on the calling thread: their own worker threads are not
# instrumented, and TSan reports their internal hand-offs as races.
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 OMP_THREAD_LIMIT=1
export LSAN_OPTIONS="suppressions=$root/tests/lsan.supp"
# The examples (demos at full size, already run by the main suite) would take minutes under ASan.
ctest --test-dir "$build" --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" "${select[@]}" -LE "packaging|examples|physics"
