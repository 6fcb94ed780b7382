# SPDX-License-Identifier: Apache-2.0
# Siconos numerics, the independent oracle of tests/solver/test_lcp_oracle.cpp (Lemke) and
# tests/solver/test_frictional_contact_oracle.cpp (fc3d): a test-only dependency (Debian:
# libsiconos-numerics-dev). Included by tests/CMakeLists.txt after the core test targets exist.
# Without Siconos the tests still build, exit with 77, and ctest reports them as skipped
# instead of failing the build.
set(MICA_ORACLE_TESTS)
foreach(name lcp_oracle frictional_contact_oracle)
  if(TARGET solver_test_${name})
    list(APPEND MICA_ORACLE_TESTS ${name})
  endif()
endforeach()
if(NOT MICA_ORACLE_TESTS)
  return()
endif()

# Its headers include each other by bare name, and SiconosConfig.h sits one level up.
find_path(MICA_SICONOS_NUMERICS_INCLUDE_DIR NAMES LinearComplementarityProblem.h LCP_Solvers.h
          PATH_SUFFIXES siconos/numerics)
find_path(MICA_SICONOS_CONFIG_INCLUDE_DIR NAMES SiconosConfig.h PATH_SUFFIXES siconos)
find_library(MICA_SICONOS_NUMERICS_LIBRARY NAMES siconos_numerics)

if(MICA_SICONOS_NUMERICS_INCLUDE_DIR AND MICA_SICONOS_CONFIG_INCLUDE_DIR AND MICA_SICONOS_NUMERICS_LIBRARY)
  message(STATUS "Oracle tests: Siconos numerics at ${MICA_SICONOS_NUMERICS_LIBRARY}")
  foreach(name ${MICA_ORACLE_TESTS})
    target_include_directories(solver_test_${name} SYSTEM PRIVATE
                               ${MICA_SICONOS_NUMERICS_INCLUDE_DIR} ${MICA_SICONOS_CONFIG_INCLUDE_DIR})
    target_link_libraries(solver_test_${name} PRIVATE ${MICA_SICONOS_NUMERICS_LIBRARY})
    target_compile_definitions(solver_test_${name} PRIVATE MICA_HAVE_SICONOS=1)
  endforeach()
else()
  message(STATUS "Oracle tests: Siconos numerics not found (install libsiconos-numerics-dev); "
                 "solver/test_lcp_oracle and solver/test_frictional_contact_oracle will be skipped")
  foreach(name ${MICA_ORACLE_TESTS})
    target_compile_definitions(solver_test_${name} PRIVATE MICA_HAVE_SICONOS=0)
  endforeach()
endif()
foreach(name ${MICA_ORACLE_TESTS})
  set_tests_properties(solver/test_${name} PROPERTIES SKIP_RETURN_CODE 77)
endforeach()
