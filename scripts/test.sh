#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The whole test suite: install what is missing, build, run every test through ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/build.sh" -DMICA_WARNINGS_AS_ERRORS=ON  # a warning in the library fails the run
ctest --test-dir "$root/build" --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" "$@"
