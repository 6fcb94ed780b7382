#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_doc_program.sh <staged prefix> <page.md> <heading> <work dir> <expected output (grep -E)> [documented command]
# The first C program under "## <heading>" of a docs page, taken from the page itself, built and
# run against the staged install the way docs/getting-started.md ("Running a program") says for
# a prefix the dynamic loader does not search: pkg-config and an RPATH, no LD_LIBRARY_PATH.
# With a documented command, the page must still show it word for word. CC and CONSUMER_FLAGS
# come from the environment.
set -eu
prefix=$1
page=$2
heading=$3
work=$4
expected=$5
documented=${6:-}
CC=${CC:-cc}

. "$(dirname "$0")/staged_pkgconfig.sh"

if [ -n "$documented" ] && ! grep -qF -- "$documented" "$page"; then
  echo "FAIL: $page no longer shows: $documented (update this test with the page)"
  exit 1
fi

rm -rf "$work"
mkdir -p "$work"
awk -v heading="## $heading" '$0 == heading { on = 1; next } on && /^## / { exit }
     on && /^```c$/ { copy = 1; next } copy && /^```$/ { exit } copy { print }' "$page" >"$work/program.c"
if ! grep -q 'int main' "$work/program.c"; then
  echo "FAIL: no C program under '## $heading' in $page"
  exit 1
fi

cd "$work"
unset LD_LIBRARY_PATH
# shellcheck disable=SC2086 # flags are word lists
"$CC" -std=c99 -Wall -Wextra -Werror ${CONSUMER_FLAGS:-} program.c $(pkg-config --cflags --libs mica) \
  -Wl,-rpath,"$(pkg-config --variable=libdir mica)" -o program
./program | tee program.out
grep -Eq -- "$expected" program.out || { echo "FAIL: the output does not match '$expected'"; exit 1; }
echo "OK: the program of '$heading' in $(basename "$page") runs against the install at $prefix without LD_LIBRARY_PATH"
