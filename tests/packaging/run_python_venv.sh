#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_python_venv.sh <staged prefix> <python project dir> <work dir>
# A Python other than the one `cmake --install` put the package in front of: a venv. The pip
# project installed under the prefix (<project dir>: pyproject.toml, setup.py, mica/) installs
# into it offline, as docs/bindings.md says, without writing into the installed tree; the venv's
# python then imports that copy, which finds the staged libmica by itself (no MICA_LIBRARY, no
# LD_LIBRARY_PATH), has mica.__version__ and py.typed, and steps a world.
# Exit 77 (skip) without Debian's python3 with venv, pip, setuptools and numpy.
set -eu
prefix=$1
project=$2
work=$3
case "$project" in /*) ;; *) project=$prefix/$project ;; esac
unset MICA_LIBRARY LD_LIBRARY_PATH PYTHONPATH

py=/usr/bin/python3
[ -x "$py" ] || py=$(command -v python3 || true)
if [ -z "$py" ] || ! "$py" -c "import setuptools, numpy, venv, pip" 2>/dev/null; then
  echo "SKIP: python3 with venv, pip, setuptools and numpy not found (Debian packages python3-venv, python3-pip, python3-setuptools, python3-numpy)"
  exit 77
fi
[ -f "$project/pyproject.toml" ] && [ -f "$project/mica/_install.py" ] || {
  echo "FAIL: no pip project with mica/_install.py at $project"
  exit 1
}

rm -rf "$work"
mkdir -p "$work"
before=$(cd "$project" && find . | sort)
# --system-site-packages: numpy and setuptools from Debian, so nothing is downloaded. (The venv
# gets no pip of its own, to save seconds: the system's pip installs into it with --python.)
"$py" -m venv --without-pip --system-site-packages "$work/venv"
"$py" -m pip --python "$work/venv/bin/python" install --quiet --no-build-isolation --no-index --no-cache-dir "$project"
after=$(cd "$project" && find . | sort)
[ "$before" = "$after" ] || { echo "FAIL: pip install wrote into $project"; exit 1; }

cd "$work"
PYTHONDONTWRITEBYTECODE=1 "$work/venv/bin/python" - "$prefix" "$work/venv" <<'PY'
import os
import sys
import mica
prefix, venv = sys.argv[1], sys.argv[2]
here = os.path.dirname(mica.__file__)
assert here.startswith(venv + "/"), "imported %s, not the venv's copy" % mica.__file__
assert mica.native.path.startswith(prefix + "/"), "loaded %s, not the staged library" % mica.native.path
v = mica.version()
assert mica.__version__ == "%d.%d.%d" % (v // 10000, v // 100 % 100, v % 100), (mica.__version__, v)
assert os.path.isfile(os.path.join(here, "py.typed")), "no py.typed: type checkers would see an untyped package"
with mica.World(gravity=(0, -9.81, 0)) as world:
    cube = world.create_box((-0.05, 0, -0.05), (0.05, 0.1, 0.05), (2, 2, 2), youngs_modulus=1e4)
    cube.add_lpc(cube.select_nodes_by_plane((0, 0, 0), (0, 1, 0)))
    world.step(0.01)
    assert cube.positions[:, 1].max() < 0.1, "the cube sags under gravity"
print("OK: a venv's python imports mica %s (pip-installed from %s), loads %s"
      % (mica.__version__, os.path.dirname(here), mica.native.path))
PY
