# SPDX-License-Identifier: Apache-2.0
# Every dependency is a Debian package; scripts/install-deps.sh installs them by name.
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)            # libeigen3-dev

# CHOLMOD (libsuitesparse-dev): Debian 12 ships neither a CMake package nor a .pc for it.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSECONFIG_LIBRARY suitesparseconfig REQUIRED)
add_library(mica::cholmod INTERFACE IMPORTED)
set_target_properties(mica::cholmod PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}"
  INTERFACE_LINK_LIBRARIES "${CHOLMOD_LIBRARY};${SUITESPARSECONFIG_LIBRARY}")

# libccd (libccd-dev) ships ccd.pc.
find_package(PkgConfig REQUIRED)
pkg_check_modules(CCD REQUIRED IMPORTED_TARGET ccd)
add_library(mica::ccd INTERFACE IMPORTED)
set_target_properties(mica::ccd PROPERTIES INTERFACE_LINK_LIBRARIES PkgConfig::CCD)
