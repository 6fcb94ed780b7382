# SPDX-License-Identifier: Apache-2.0
# Run by `cmake --install` after libmica is installed (MICA_INSTALL_LIBDIR and
# CMAKE_INSTALL_PREFIX are set): makes the installed libmica.so.0 loadable, or says how.
#   - libdir searched by the dynamic loader (an ld.so.conf directory, e.g. /usr/local/lib on
#     Debian): its cache must be refreshed. As root, this runs `ldconfig`; otherwise it says to.
#   - a staged install (DESTDIR set, a package build): nothing (the package runs ldconfig).
#   - any other libdir: programs need -Wl,-rpath,<libdir> or LD_LIBRARY_PATH; said here and in
#     docs/getting-started.md ("Running a program").
set(_libdir "${MICA_INSTALL_LIBDIR}")
if(NOT IS_ABSOLUTE "${_libdir}")
  set(_libdir "${CMAKE_INSTALL_PREFIX}/${_libdir}")
endif()
get_filename_component(_libdir "${_libdir}" REALPATH)

if(NOT "$ENV{DESTDIR}" STREQUAL "")
  return()
endif()

find_program(_ldconfig ldconfig PATHS /sbin /usr/sbin NO_CACHE)
set(_searched FALSE)
if(_ldconfig)
  # `ldconfig -v -N` (no cache update) prints each directory it searches as "<dir>: ...".
  execute_process(COMMAND "${_ldconfig}" -v -N OUTPUT_VARIABLE _out ERROR_QUIET)
  string(REPLACE "\n" ";" _lines "${_out}")
  foreach(_line IN LISTS _lines)
    if(_line MATCHES "^(/[^:]*):")
      set(_dir "${CMAKE_MATCH_1}")
      if(EXISTS "${_dir}")
        get_filename_component(_dir "${_dir}" REALPATH)
      endif()
      if(_dir STREQUAL _libdir)
        set(_searched TRUE)
      endif()
    endif()
  endforeach()
endif()

if(_searched)
  execute_process(COMMAND id -u OUTPUT_VARIABLE _uid OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(_uid STREQUAL "0")
    message(STATUS "libmica: ${_libdir} is a system library directory: running ldconfig")
    execute_process(COMMAND "${_ldconfig}")
  else()
    message(STATUS "libmica: run `sudo ldconfig` so that programs find libmica.so.0 in ${_libdir}")
  endif()
else()
  message(STATUS "libmica: the dynamic loader does not search ${_libdir}: link programs with "
                 "-Wl,-rpath,${_libdir} (or run them with LD_LIBRARY_PATH=${_libdir}); "
                 "see docs/getting-started.md")
endif()
