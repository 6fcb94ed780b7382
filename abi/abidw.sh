#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# abidw.sh <libmica.so.N> <out.abi>: the ABI of libmica as libabigail sees it, limited to the
# exported functions and the types they reach that the public headers (include/mica) define:
# what abi/libmica.abi holds and abi/check.sh compares.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
src=${MICA_SOURCE_DIR:-$(dirname "$here")}
# --exported-interfaces-only keeps the C++ internals of the C layer's translation units out;
# no locations, paths or sequence ids, so the baseline changes only when the ABI does.
exec abidw --no-corpus-path --no-comp-dir-path --no-show-locs --type-id-style hash \
  --headers-dir "$src/include/mica" --drop-private-types --drop-undefined-syms --exported-interfaces-only \
  --out-file "$2" "$1"
