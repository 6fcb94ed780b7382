#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_installed_bindings.sh <staged prefix> <python dir> <lua dir>
# The Python package and the LuaJIT module as `cmake --install` put them under the staged
# prefix find the staged libmica by themselves: no MICA_LIBRARY, no LD_LIBRARY_PATH (only the
# interpreters' own search paths point at the prefix, as they would not need to for /usr/local).
# Each steps a pressed box and checks the library it loaded. Exit 77 (skip) without python3 with
# numpy and without luajit.
set -eu
prefix=$1
pydir=$2
luadir=$3
case "$pydir" in /*) ;; *) pydir=$prefix/$pydir ;; esac
case "$luadir" in /*) ;; *) luadir=$prefix/$luadir ;; esac
unset MICA_LIBRARY LD_LIBRARY_PATH
ran=0

py=/usr/bin/python3
[ -x "$py" ] || py=$(command -v python3 || true)
if [ -n "$py" ] && "$py" -c "import numpy" 2>/dev/null; then
  [ -f "$pydir/mica/_install.py" ] || { echo "FAIL: no $pydir/mica/_install.py"; exit 1; }
  PYTHONDONTWRITEBYTECODE=1 PYTHONPATH=$pydir "$py" - "$prefix" <<'PY'
import sys
import mica
prefix = sys.argv[1]
assert mica.native.path.startswith(prefix + "/"), "loaded %s, not the staged library" % mica.native.path
with mica.World(solver=mica.MICA_SOLVER_MICA, mica_sweep=mica.MICA_SWEEP_FACTORED) as world:
    cube = world.create_box((-0.05, 0, -0.05), (0.05, 0.1, 0.05), (4, 4, 4), youngs_modulus=1e4)
    cube.add_lpc(cube.select_nodes_by_plane((0, 0, 0), (0, 1, 0)))
    world.step(0.01)
    assert cube.positions[:, 1].max() < 0.1
print("OK: python3 -c 'import mica' loads %s (libmica %d)" % (mica.native.path, mica.version()))
PY
  ran=1
else
  echo "python3 with numpy not found: the Python package is not tried"
fi

if command -v luajit >/dev/null 2>&1; then
  [ -f "$luadir/mica_install.lua" ] || { echo "FAIL: no $luadir/mica_install.lua"; exit 1; }
  LUA_PATH="$luadir/?.lua;;" luajit - "$prefix" <<'LUA'
local prefix = arg[1]
local mica = require("mica")
assert(mica.path:sub(1, #prefix + 1) == prefix .. "/", "loaded " .. mica.path .. ", not the staged library")
local world = mica.world{ solver = mica.C.MICA_SOLVER_MICA }
local cube = world:create_box({-0.05, 0, -0.05}, {0.05, 0.1, 0.05}, {4, 4, 4}, 5, { youngs_modulus = 1e4 })
world:step(0.01)
world:close()
print("OK: luajit require('mica') loads " .. mica.path)
LUA
  ran=1
else
  echo "luajit not found: the LuaJIT module is not tried"
fi

[ "$ran" -eq 1 ] || { echo "SKIP: neither python3 with numpy nor luajit"; exit 77; }
