#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# check_replay_cut.sh <mica_replay> <recording> <scratch folder>
# A recording cut short (head -c, as a host that died leaves it) is not replayed as a success:
# mica_replay replays its whole steps, then exits 4 saying after how many steps it was cut, here
# 500 bytes before the end (a few steps fewer) and inside the body's mesh (before any step). The
# whole file exits 0.
set -u
replay=$1
recording=$2
work=$3
rm -rf "$work"
mkdir -p "$work"
size=$(wc -c <"$recording")
failed=0

# expect <bytes kept> <exit status> <pattern the output must have>
expect() {
  head -c "$1" "$recording" >"$work/cut.micarec"
  "$replay" "$work/cut.micarec" "$work" >"$work/out.txt" 2>&1
  status=$?
  if [ "$status" -ne "$2" ] || ! grep -q "$3" "$work/out.txt"; then
    echo "FAIL: the first $1 of $size bytes: exit $status (expected $2), output (expected '$3'):"
    cat "$work/out.txt"
    failed=1
  else
    echo "the first $1 of $size bytes: exit $status, $(grep "$3" "$work/out.txt" | head -n 1)"
  fi
}

expect "$size" 0 "each as recorded, bit for bit"
expect $((size - 500)) 4 "cut short after [1-9][0-9]* steps"
expect 2000 4 "cut short after 0 steps"
exit $failed
