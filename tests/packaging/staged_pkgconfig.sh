# SPDX-License-Identifier: Apache-2.0
# Sourced by the run_*.sh scripts with $prefix set: points PKG_CONFIG_PATH at the staged
# install's mica.pc (GNUInstallDirs may have put it under lib/ or lib/<multiarch>/).
pc=$(find "$prefix" -path '*/pkgconfig/mica.pc' | head -n 1)
if [ -z "$pc" ]; then
  echo "FAIL: no pkgconfig/mica.pc under $prefix"
  exit 1
fi
PKG_CONFIG_PATH=$(dirname "$pc")
export PKG_CONFIG_PATH
