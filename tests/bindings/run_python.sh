#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_python.sh <test_python.py>: runs the Python binding's tests with Debian's python3
# (exit 77, a skip, without python3, numpy or the generated manifest).
set -eu
py=/usr/bin/python3
[ -x "$py" ] || py=$(command -v python3 || true)
if [ -z "$py" ] || ! "$py" -c "import numpy" 2>/dev/null; then
  echo "SKIP: python3 with numpy not found (Debian packages python3, python3-numpy)"
  exit 77
fi
if [ ! -f "$MICA_MANIFEST" ]; then
  echo "SKIP: $MICA_MANIFEST was not generated (configure found no python3)"
  exit 77
fi
# No __pycache__ in the source tree.
PYTHONDONTWRITEBYTECODE=1 PYTHONPATH=$MICA_SOURCE_DIR/bindings/python exec "$py" "$1"
