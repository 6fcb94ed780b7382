# SPDX-License-Identifier: Apache-2.0
# Numerical-stability stress tests (tests/stress/, docs/stability.md). Included by
# tests/CMakeLists.txt after mica_test_core exists.
#
#   ctest -L stress                                   the representative slice (also in the default run)
#   ctest -C StressFull -L stress-full                the whole matrix, one test per scenario
#   ctest -C Long -L long                             100000 steps with a virtual hand
#
# The heavy tests carry CONFIGURATIONS, so a plain `ctest` (no -C) leaves them out. Every run
# writes one CSV per test into ${CMAKE_BINARY_DIR}/stress/; scripts/stability_table.py turns
# the stress-full ones into the table of docs/stability.md.
set(MICA_STRESS_OUT ${CMAKE_BINARY_DIR}/stress)
file(MAKE_DIRECTORY ${MICA_STRESS_OUT})

foreach(name test_stress test_long_run)
  add_executable(stress_${name} ${CMAKE_CURRENT_LIST_DIR}/${name}.cpp)
  target_include_directories(stress_${name} PRIVATE ${CMAKE_CURRENT_LIST_DIR}/..)
  target_link_libraries(stress_${name} PRIVATE mica_test_core PkgConfig::CMOCKA)
endforeach()

# One ctest per scenario, so a failure names its scenario and -j spreads them over the cores.
foreach(scenario a b c d e f g h i)
  add_test(NAME stress/slice_${scenario}
           COMMAND stress_test_stress --only ${scenario} --csv ${MICA_STRESS_OUT}/slice-${scenario}.csv)
  set_tests_properties(stress/slice_${scenario} PROPERTIES LABELS "unit;stress"
                       ENVIRONMENT "CMOCKA_MESSAGE_OUTPUT=STDOUT")
  add_test(NAME stress/full_${scenario} CONFIGURATIONS StressFull
           COMMAND stress_test_stress --full --only ${scenario} --csv ${MICA_STRESS_OUT}/full-${scenario}.csv)
  set_tests_properties(stress/full_${scenario} PROPERTIES LABELS "stress-full" TIMEOUT 1800
                       ENVIRONMENT "CMOCKA_MESSAGE_OUTPUT=STDOUT")
endforeach()

add_test(NAME stress/long_run CONFIGURATIONS Long
         COMMAND stress_test_long_run --csv ${MICA_STRESS_OUT}/long-run.csv)
set_tests_properties(stress/long_run PROPERTIES LABELS "long" TIMEOUT 3600
                     ENVIRONMENT "CMOCKA_MESSAGE_OUTPUT=STDOUT")
