#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Installs the Debian 12 packages libmica needs to build, test and document itself.
# Idempotent: does nothing (and prints nothing) when everything is already installed.
set -eu

PACKAGES="g++ cmake make pkg-config libeigen3-dev libsuitesparse-dev libopenblas0 libccd-dev libcmocka-dev
doxygen python3 python3-numpy python3-matplotlib python3-venv python3-pip python3-setuptools libsiconos-numerics-dev
luajit mono-mcs mono-runtime libmono-system-numerics-vectors4.0-cil abigail-tools clang-14 libclang-rt-14-dev llvm-14 graphviz"

missing=""
for pkg in $PACKAGES; do
  # dpkg-query prints "install ok installed" only for a fully installed package.
  status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)
  if [ "$status" != "install ok installed" ]; then
    missing="$missing $pkg"
  fi
done

[ -z "$missing" ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  SUDO=""
elif command -v sudo >/dev/null 2>&1; then
  SUDO="sudo"
else
  echo "install-deps.sh: missing packages:$missing; run this script as root (no sudo found)" >&2
  exit 1
fi

echo "install-deps.sh: installing$missing"
$SUDO apt-get update
# shellcheck disable=SC2086 # $missing is a list of package names
$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $missing
