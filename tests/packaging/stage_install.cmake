# cmake -DBUILD_DIR=<build> -DPREFIX=<dir> -P stage_install.cmake
# A fresh `cmake --install` of the build tree into PREFIX (no stale files from earlier runs).
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}"
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "cmake --install ${BUILD_DIR} --prefix ${PREFIX} failed: ${result}")
endif()
