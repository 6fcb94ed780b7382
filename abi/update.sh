#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# update.sh <build-dir>: rewrites the ABI baseline abi/libmica.abi from the build tree's
# libmica (its debug twin, target mica_abi). Commit the result with the change that caused it;
# an incompatible change also bumps MICA_VERSION_MAJOR (see abi/check.sh).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
build=${1:?usage: abi/update.sh <build-dir>}
cmake --build "$build" --target mica_abi -j2
major=$(sed -n 's/^#define MICA_VERSION_MAJOR \([0-9]*\).*/\1/p' "$here/../include/mica/mica.h")
sh "$here/abidw.sh" "$build/abi/libmica.so.$major" "$here/libmica.abi"
echo "wrote $here/libmica.abi ($(grep -c '<function-decl' "$here/libmica.abi") functions)"
