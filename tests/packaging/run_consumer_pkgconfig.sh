#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_consumer_pkgconfig.sh <staged prefix> <consumer.c> <work dir>
# Builds consumer.c against the staged install as docs/getting-started.md says for a prefix the
# dynamic loader does not search: `$CC ... $(pkg-config --cflags --libs mica)
# -Wl,-rpath,$(pkg-config --variable=libdir mica)`, and runs it without LD_LIBRARY_PATH.
# CC and CONSUMER_FLAGS (e.g. sanitizer flags) come from the environment.
set -eu
prefix=$1
source=$2
work=$3
CC=${CC:-cc}

. "$(dirname "$0")/staged_pkgconfig.sh"

libdir=$(pkg-config --variable=libdir mica)
cflags=$(pkg-config --cflags mica)
libs=$(pkg-config --libs mica)
licence=$(pkg-config --variable=license mica)
echo "mica.pc: $pc"
echo "pkg-config --cflags --libs mica: $cflags $libs"
case "$libdir" in
  "$prefix"/*) ;;
  *) echo "FAIL: mica.pc libdir '$libdir' is not under the staged prefix $prefix"; exit 1 ;;
esac
if [ "$licence" != "Apache-2.0" ]; then
  echo "FAIL: pkg-config --variable=license mica is '$licence', not Apache-2.0"
  exit 1
fi

rm -rf "$work"
mkdir -p "$work"
# The public header must compile cleanly as C99 with every warning on.
# shellcheck disable=SC2086 # flags are word lists
"$CC" -std=c99 -Wall -Wextra -Wpedantic -Werror ${CONSUMER_FLAGS:-} \
  -o "$work/consumer" "$source" $cflags $libs -Wl,-rpath,"$libdir" -lm

# The RPATH alone must find the staged library (not a build tree, not another install).
unset LD_LIBRARY_PATH
found=$(ldd "$work/consumer" | sed -n 's/.*libmica\.so\.[0-9]* => \([^ ]*\).*/\1/p')
case "$found" in
  "$libdir"/*) echo "libmica.so loaded from $found" ;;
  *) echo "FAIL: the consumer resolves libmica to '$found', not the staged $libdir"; exit 1 ;;
esac
"$work/consumer"
