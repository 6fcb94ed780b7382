#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_pc_alone.sh <staged prefix> <work dir>
# `pkg-config --cflags --libs mica` on a machine with no other .pc file (no libccd or
# SuiteSparse development files): PKG_CONFIG_LIBDIR is a folder holding only the staged mica.pc.
# A consumer of the shared library needs nothing else, so mica.pc names private requirements
# (Requires.private, Libs.private) only when the static library is installed.
set -eu
prefix=$1
work=$2

. "$(dirname "$0")/staged_pkgconfig.sh"

rm -rf "$work"
mkdir -p "$work"
cp "$pc" "$work/"
unset PKG_CONFIG_PATH
PKG_CONFIG_LIBDIR=$work
export PKG_CONFIG_LIBDIR

if ! flags=$(pkg-config --cflags --libs mica 2>&1); then
  echo "FAIL: pkg-config --cflags --libs mica, with only mica.pc installed: $flags"
  echo "--- $pc:"
  cat "$pc"
  exit 1
fi
echo "pkg-config --cflags --libs mica, with only mica.pc: $flags"

static=$(find "$prefix" -name libmica.a | head -n 1)
if [ -n "$static" ] && ! grep -q '^Requires.private: ccd' "$pc"; then
  echo "FAIL: $static is installed, but $pc does not name libccd for a static link (Requires.private)"
  exit 1
fi
if [ -z "$static" ] && grep -q '^Requires.private\|^Libs.private' "$pc"; then
  echo "FAIL: no libmica.a is installed, but $pc names private requirements:"
  grep '^Requires.private\|^Libs.private' "$pc"
  exit 1
fi
echo "private requirements: ${static:+named for $static}${static:-none (no static library)}"
