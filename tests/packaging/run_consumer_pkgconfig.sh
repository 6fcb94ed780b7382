#!/bin/sh
# run_consumer_pkgconfig.sh <staged prefix> <consumer.c> <work dir>
# Builds consumer.c with `$CC $(pkg-config --cflags --libs mica)` against the staged install
# and runs it. CC and CONSUMER_FLAGS (e.g. sanitizer flags) come from the environment.
set -eu
prefix=$1
source=$2
work=$3
CC=${CC:-cc}

# GNUInstallDirs may have put the library in lib/ or lib/<multiarch>/: find mica.pc.
pc=$(find "$prefix" -path '*/pkgconfig/mica.pc' | head -n 1)
if [ -z "$pc" ]; then
  echo "FAIL: no pkgconfig/mica.pc under $prefix"
  exit 1
fi
PKG_CONFIG_PATH=$(dirname "$pc")
export PKG_CONFIG_PATH

libdir=$(pkg-config --variable=libdir mica)
cflags=$(pkg-config --cflags mica)
libs=$(pkg-config --libs mica)
echo "mica.pc: $pc"
echo "pkg-config --cflags --libs mica: $cflags $libs"
case "$libdir" in
  "$prefix"/*) ;;
  *) echo "FAIL: mica.pc libdir '$libdir' is not under the staged prefix $prefix"; exit 1 ;;
esac

rm -rf "$work"
mkdir -p "$work"
# The public header must compile cleanly as C99 with every warning on.
# shellcheck disable=SC2086 # flags are word lists
"$CC" -std=c99 -Wall -Wextra -Wpedantic -Werror ${CONSUMER_FLAGS:-} \
  -o "$work/consumer" "$source" $cflags $libs -lm

LD_LIBRARY_PATH=$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH} "$work/consumer"
