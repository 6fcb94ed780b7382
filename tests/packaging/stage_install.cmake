# SPDX-License-Identifier: Apache-2.0
# cmake -DBUILD_DIR=<build> -DPREFIX=<dir> -P stage_install.cmake
# A fresh `cmake --install` of the build tree into PREFIX (no stale files from earlier runs),
# then the files a user relies on: the licence under share/doc/libmica, the headers, mica.pc
# naming the licence; and, as the prefix is not one the dynamic loader searches, the install
# says how programs find libmica.so.0.
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}"
                RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
message("${output}")
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cmake --install ${BUILD_DIR} --prefix ${PREFIX} failed: ${result}")
endif()

foreach(file share/doc/libmica/LICENSE share/doc/libmica/NOTICE share/doc/libmica/CHANGELOG.md
             share/doc/libmica/README.md include/mica/mica.h include/mica/mica_device.h)
  if(NOT EXISTS "${PREFIX}/${file}")
    message(FATAL_ERROR "the install has no ${file}")
  endif()
endforeach()
file(READ "${PREFIX}/share/doc/libmica/LICENSE" licence)
if(NOT licence MATCHES "Apache License[ \n]+Version 2.0, January 2004" OR NOT licence MATCHES "END OF TERMS AND CONDITIONS")
  message(FATAL_ERROR "share/doc/libmica/LICENSE is not the full Apache-2.0 text")
endif()

file(GLOB_RECURSE pc "${PREFIX}/*/pkgconfig/mica.pc")
if(NOT pc)
  message(FATAL_ERROR "the install has no pkgconfig/mica.pc")
endif()
file(READ "${pc}" pc_text)
if(NOT pc_text MATCHES "\nLicense: Apache-2.0\n")
  message(FATAL_ERROR "${pc} does not name the licence (License: Apache-2.0)")
endif()

if(NOT output MATCHES "does not search")
  message(FATAL_ERROR "installing to ${PREFIX} did not say how programs find libmica.so.0 there")
endif()
