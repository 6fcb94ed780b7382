#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_consumer_cmake.sh <cmake> <consumer project dir> <work dir> <staged prefix>
# Configures, builds and runs the find_package(mica) consumer against the staged install.
# CC, CMAKE_GENERATOR and CONSUMER_FLAGS (e.g. sanitizer flags) come from the environment.
set -eu
cmake=$1
source=$2
work=$3
prefix=$4

rm -rf "$work"
# No package registries: the package must come from the staged prefix.
"$cmake" -S "$source" -B "$work" \
  -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF \
  -DCMAKE_C_FLAGS="${CONSUMER_FLAGS:-}" \
  -DCMAKE_EXE_LINKER_FLAGS="${CONSUMER_FLAGS:-}"
"$cmake" --build "$work"

mica_dir=$(sed -n 's/^mica_DIR:PATH=//p' "$work/CMakeCache.txt")
case "$mica_dir" in
  "$prefix"/*) echo "mica_DIR: $mica_dir" ;;
  *) echo "FAIL: find_package(mica) found '$mica_dir', not the staged prefix $prefix"; exit 1 ;;
esac

# The imported target carries the library's location: the build RPATH finds libmica.so.
unset LD_LIBRARY_PATH
"$work/app"
# Installed with INSTALL_RPATH_USE_LINK_PATH, the program still finds it.
"$cmake" --install "$work" --prefix "$work/installed"
"$work/installed/bin/app"
# The static library is exercised too when it was installed (MICA_BUILD_STATIC=ON).
if [ -x "$work/app_static" ]; then
  "$work/app_static"
fi
