#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_luajit.sh <test_luajit.lua>: runs the LuaJIT binding's tests against the generated cdef
# (exit 77, a skip, without luajit or the generated files).
set -eu
if ! command -v luajit >/dev/null 2>&1; then
  echo "SKIP: luajit not found (Debian package luajit)"
  exit 77
fi
lua_dir=$MICA_BINDINGS_BUILD_DIR/luajit
if [ ! -f "$lua_dir/mica_cdef.lua" ] || [ ! -f "$MICA_MANIFEST_TSV" ]; then
  echo "SKIP: the LuaJIT cdef or the manifest was not generated (configure found no python3)"
  exit 77
fi
# The module from the source tree, its cdef from the build tree.
LUA_PATH="$MICA_SOURCE_DIR/bindings/luajit/?.lua;$lua_dir/?.lua;;" exec luajit "$1"
