#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# check_exports.sh <libmica.so> <expected SONAME>
# The shared library exports the C API (mica_*) and nothing else, under the expected SONAME.
set -eu
lib=$1
soname=$2
status=0

# Defined dynamic symbols without their version suffix (mica_step@@MICA_0 -> mica_step);
# type A entries are version nodes (MICA_0), not symbols.
symbols=$(nm -D --defined-only "$lib" | awk '$2 != "A" { sub(/@.*/, "", $3); print $3 }' | sort -u)

stray=$(printf '%s\n' "$symbols" | grep -v -e '^mica_' -e '^_init$' -e '^_fini$' -e '^$' || true)
if [ -n "$stray" ]; then
  echo "FAIL: $lib exports symbols outside mica_*:"
  printf '%s\n' "$stray" | sed 's/^/  /'
  status=1
fi

for required in mica_version mica_world_create mica_step mica_add_lpc; do
  if ! printf '%s\n' "$symbols" | grep -qx "$required"; then
    echo "FAIL: $lib does not export $required"
    status=1
  fi
done

actual=$(readelf -d "$lib" | sed -n 's/.*(SONAME).*\[\(.*\)\].*/\1/p')
if [ "$actual" != "$soname" ]; then
  echo "FAIL: SONAME of $lib is '${actual}', expected '$soname'"
  status=1
fi

if [ "$status" -eq 0 ]; then
  echo "OK: $(printf '%s\n' "$symbols" | grep -c .) symbols, all mica_*; SONAME $actual"
fi
exit "$status"
