#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# check.sh <libmica.so.N built with -g>: fails on any difference between the library's ABI and
# the baseline abi/libmica.abi (a ctest test, label "abi"; exit 77 without libabigail).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
lib=$1
baseline=$here/libmica.abi

if ! command -v abidw >/dev/null 2>&1 || ! command -v abidiff >/dev/null 2>&1; then
  echo "SKIP: abidw/abidiff not found (Debian package abigail-tools)"
  exit 77
fi
if [ ! -f "$baseline" ]; then
  echo "FAIL: no baseline $baseline; create it with abi/update.sh <build-dir>"
  exit 1
fi

current=$(mktemp "${TMPDIR:-/tmp}/libmica-abi.XXXXXX")
trap 'rm -f "$current"' EXIT
sh "$here/abidw.sh" "$lib" "$current"

status=0
abidiff --no-show-locs "$baseline" "$current" || status=$?
if [ "$status" -eq 0 ]; then
  echo "OK: the ABI of $(basename "$lib") matches abi/libmica.abi"
  exit 0
fi
# abidiff's exit status is a bit field: 1 error, 2 usage, 4 ABI change, 8 incompatible change.
if [ $((status & 3)) -ne 0 ]; then
  echo "FAIL: abidiff could not compare (exit status $status)"
  exit 1
fi
# abidiff flags a change behind a pointer (a def struct growing) as a change, not as incompatible:
# read the report above rather than the exit status.
cat <<MSG
FAIL: the ABI of libmica differs from the baseline abi/libmica.abi (report above).
If the change is intended, update the baseline in the same commit:
    sh abi/update.sh <build-dir>
and commit abi/libmica.abi with it. The rule: a change that breaks the ABI (a removed or
changed function, a struct field removed, moved or retyped) bumps MICA_VERSION_MAJOR in
include/mica/mica.h (and the project VERSION, hence the SONAME) in that same commit.
Additions (new functions, fields appended to a def struct, which struct_size covers)
bump MICA_VERSION_MINOR.
MSG
exit 1
