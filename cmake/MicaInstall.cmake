# SPDX-License-Identifier: Apache-2.0
# Install rules: libmica (shared, and static when built), the program mica_replay, the public
# headers, a CMake package (find_package(mica) -> mica::mica, mica::mica_static), mica.pc, and the
# licence (LICENSE, NOTICE), README and CHANGELOG under share/doc/libmica.
# Included by the top-level CMakeLists once the targets mica, mica_replay and (optionally)
# mica_static exist.
# The docs HTML (component docs) is installed from cmake/MicaDocs.cmake, next to its target.
include(CMakePackageConfigHelpers)

set(MICA_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/mica)
set(MICA_INSTALL_TARGETS mica)
set(MICA_INSTALL_STATIC OFF)

if(TARGET mica_static)
  list(APPEND MICA_INSTALL_TARGETS mica_static)
  set(MICA_INSTALL_STATIC ON)
  # A static library carries its private dependencies as $<LINK_ONLY:...> targets that exist
  # only in this build (mica::cholmod, mica::ccd, Eigen3::Eigen). Keep them for the build
  # tree and give the installed target plain library names, so that the package config
  # needs nothing but Threads and consumers of the shared library need nothing at all.
  get_target_property(_mica_static_iface mica_static INTERFACE_LINK_LIBRARIES)
  set(_mica_static_new_iface "")
  foreach(_item IN LISTS _mica_static_iface)
    list(APPEND _mica_static_new_iface "$<BUILD_INTERFACE:${_item}>")
  endforeach()
  foreach(_lib cholmod suitesparseconfig ccd stdc++ m ${CMAKE_DL_LIBS} Threads::Threads)
    list(APPEND _mica_static_new_iface "$<INSTALL_INTERFACE:$<LINK_ONLY:${_lib}>>")
  endforeach()
  set_property(TARGET mica_static PROPERTY INTERFACE_LINK_LIBRARIES "${_mica_static_new_iface}")
endif()

install(TARGETS ${MICA_INSTALL_TARGETS} EXPORT micaTargets
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})

# mica_replay (examples_c/mica_replay.c) replays a recording; it finds the libmica installed beside it.
set_target_properties(mica_replay PROPERTIES INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")
install(TARGETS mica_replay RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/mica/
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mica
  FILES_MATCHING PATTERN "*.h")

# The licence and the release notes. The directory is named after the library (libmica), not
# the CMake project (GNUInstallDirs' DOCDIR would be share/doc/mica).
set(MICA_INSTALL_DOCDIR ${CMAKE_INSTALL_DATAROOTDIR}/doc/libmica)
install(FILES
  ${PROJECT_SOURCE_DIR}/LICENSE
  ${PROJECT_SOURCE_DIR}/NOTICE
  ${PROJECT_SOURCE_DIR}/README.md
  ${PROJECT_SOURCE_DIR}/CHANGELOG.md
  DESTINATION ${MICA_INSTALL_DOCDIR})

install(EXPORT micaTargets
  NAMESPACE mica::
  DESTINATION ${MICA_INSTALL_CMAKEDIR})

configure_package_config_file(
  ${PROJECT_SOURCE_DIR}/cmake/micaConfig.cmake.in
  ${PROJECT_BINARY_DIR}/cmake/micaConfig.cmake
  INSTALL_DESTINATION ${MICA_INSTALL_CMAKEDIR}
  PATH_VARS MICA_INSTALL_DOCDIR)
# SOVERSION is the major version, so any release with the same major is a drop-in.
write_basic_package_version_file(
  ${PROJECT_BINARY_DIR}/cmake/micaConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMajorVersion)
install(FILES
  ${PROJECT_BINARY_DIR}/cmake/micaConfig.cmake
  ${PROJECT_BINARY_DIR}/cmake/micaConfigVersion.cmake
  DESTINATION ${MICA_INSTALL_CMAKEDIR})

# mica.pc: `cmake --install --prefix` may pick another prefix than the configured one, and the
# .pc must name the prefix the files really land in, so the prefix is filled in at install time.
foreach(_dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${_dir}}")
    set(MICA_PC_${_dir} "${CMAKE_INSTALL_${_dir}}")
  else()
    set(MICA_PC_${_dir} "\${prefix}/${CMAKE_INSTALL_${_dir}}")
  endif()
endforeach()
# What a static link needs besides libmica, named only when libmica.a is installed: pkg-config
# resolves Requires.private for --cflags too, so naming libccd would make every consumer of the
# shared library install libccd's development files.
set(MICA_PC_PRIVATE "")
if(MICA_INSTALL_STATIC)
  set(MICA_PC_PRIVATE "Requires.private: ccd\nLibs.private: -lcholmod -lsuitesparseconfig -lstdc++ -lm -ldl -lpthread")
endif()
set(MICA_PC_PREFIX "@MICA_PC_PREFIX@")  # survives this pass, replaced at install time
configure_file(${PROJECT_SOURCE_DIR}/pkgconfig/mica.pc.in
               ${PROJECT_BINARY_DIR}/pkgconfig/mica.pc.stage @ONLY)
install(CODE "
  set(MICA_PC_PREFIX \"\${CMAKE_INSTALL_PREFIX}\")
  configure_file(\"${PROJECT_BINARY_DIR}/pkgconfig/mica.pc.stage\"
                 \"${PROJECT_BINARY_DIR}/pkgconfig/mica.pc\" @ONLY)")
install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/mica.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# After the library lands: make it loadable (cmake/MicaLoaderCache.cmake). A program linked
# against libmica.so.0 finds it at run time only where the dynamic loader looks: the ld.so.conf
# directories (through ldconfig's cache), the program's RPATH, or LD_LIBRARY_PATH.
if(CMAKE_SYSTEM_NAME STREQUAL "Linux")
  configure_file(${PROJECT_SOURCE_DIR}/cmake/MicaLoaderCache.cmake ${PROJECT_BINARY_DIR}/cmake/MicaLoaderCache.cmake
                 COPYONLY)
  install(CODE "set(MICA_INSTALL_LIBDIR \"${CMAKE_INSTALL_LIBDIR}\")
include(\"${PROJECT_BINARY_DIR}/cmake/MicaLoaderCache.cmake\")")
endif()
