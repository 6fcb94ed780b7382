# SPDX-License-Identifier: Apache-2.0
# The project is described in pyproject.toml; this only sends setuptools' scratch files (build/,
# mica.egg-info) to a temporary directory, so `pip install` works from a read-only copy such as
# <prefix>/share/libmica/python and leaves the source tree clean.
import tempfile

from setuptools import setup

_scratch = tempfile.TemporaryDirectory(prefix="mica-build-")
setup(options={"build": {"build_base": _scratch.name + "/build"}, "egg_info": {"egg_base": _scratch.name}})
