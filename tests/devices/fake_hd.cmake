# SPDX-License-Identifier: Apache-2.0
# The fake OpenHaptics HD library (tests/devices/fake_hd/) that devices/test_touch_backend
# loads through MICA_HD_LIBRARY instead of libHD.so. Included by tests/CMakeLists.txt after
# the core test targets exist.
add_library(fake_hd SHARED ${CMAKE_CURRENT_LIST_DIR}/fake_hd/fake_hd.c)
target_include_directories(fake_hd PRIVATE ${PROJECT_SOURCE_DIR}/src)
# dlsym must find the HD names, which the project's default visibility would hide.
set_target_properties(fake_hd PROPERTIES C_VISIBILITY_PRESET default)
target_compile_options(fake_hd PRIVATE -Wall -Wextra)
target_link_libraries(fake_hd PRIVATE Threads::Threads m)

if(TARGET devices_test_touch_backend)
  # The test links the fake for its controls and hands its path to the backend, which
  # dlopens it: the dynamic linker maps the one file once, so both see the same fake.
  target_link_libraries(devices_test_touch_backend PRIVATE fake_hd)
  target_compile_definitions(devices_test_touch_backend PRIVATE MICA_FAKE_HD_LIBRARY="$<TARGET_FILE:fake_hd>")
endif()
