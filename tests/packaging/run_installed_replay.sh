#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_installed_replay.sh <staged prefix> <work dir> [recording]
# The program mica_replay is installed with the library (bin/) and runs from there without
# LD_LIBRARY_PATH (its RPATH finds the libmica beside it): --help, and the recording if given.
set -eu
prefix=$1
work=$2
recording=${3:-}
replay=$prefix/bin/mica_replay
if [ ! -x "$replay" ]; then
  echo "FAIL: the install has no bin/mica_replay"
  exit 1
fi
unset LD_LIBRARY_PATH
found=$(ldd "$replay" | sed -n 's/.*libmica\.so\.[0-9]* => \([^ ]*\).*/\1/p')
case "$found" in
  "$prefix"/*) echo "bin/mica_replay loads $found" ;;
  *) echo "FAIL: bin/mica_replay resolves libmica to '$found', not the one under $prefix"; exit 1 ;;
esac
"$replay" --help | grep -q "^usage: mica_replay" || { echo "FAIL: bin/mica_replay --help printed no usage"; exit 1; }
if [ -n "$recording" ]; then
  rm -rf "$work"
  "$replay" "$recording" "$work"
fi
