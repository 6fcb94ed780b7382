#!/bin/sh
# run_getting_started.sh <staged prefix> <docs/getting-started.md> <work dir>
# The first program of docs/getting-started.md (sag.c, taken from the page itself) built and
# run against the staged install exactly as the page's "Running a program" says for a prefix
# the dynamic loader does not search. CC and CONSUMER_FLAGS come from the environment.
set -eu
prefix=$1
page=$2
work=$3
CC=${CC:-cc}

. "$(dirname "$0")/staged_pkgconfig.sh"

# The command the page gives, with its variables; it must still be on the page word for word.
documented='cc sag.c $(pkg-config --cflags --libs mica) -Wl,-rpath,$(pkg-config --variable=libdir mica) -o sag'
if ! grep -qF "$documented" "$page"; then
  echo "FAIL: $page no longer shows: $documented (update this test with the page)"
  exit 1
fi

rm -rf "$work"
mkdir -p "$work"
# The first C block after "## A first program".
awk '/^## A first program/ { on = 1 } on && /^```c$/ { copy = 1; next } copy && /^```$/ { exit } copy { print }' \
  "$page" >"$work/sag.c"
if ! grep -q 'int main' "$work/sag.c"; then
  echo "FAIL: no C program under '## A first program' in $page"
  exit 1
fi

cd "$work"
unset LD_LIBRARY_PATH
# shellcheck disable=SC2086 # flags are word lists
"$CC" ${CONSUMER_FLAGS:-} sag.c $(pkg-config --cflags --libs mica) -Wl,-rpath,"$(pkg-config --variable=libdir mica)" -o sag
./sag | tee sag.out
grep -q '^node [0-9]* is at' sag.out || { echo "FAIL: sag printed no node position"; exit 1; }
[ -s sag.vtk ] || { echo "FAIL: sag wrote no sag.vtk"; exit 1; }
echo "OK: the getting-started program runs against the install at $prefix without LD_LIBRARY_PATH"
