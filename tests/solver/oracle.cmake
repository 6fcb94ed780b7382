# Siconos numerics, the independent oracle of tests/solver/test_lcp_oracle.cpp: a test-only
# dependency (Debian: libsiconos-numerics-dev). Included by tests/CMakeLists.txt after the
# core test targets exist. Without Siconos the test still builds, exits with 77, and ctest
# reports it as skipped instead of failing the build.
if(NOT TARGET solver_test_lcp_oracle)
  return()
endif()

# Its headers include each other by bare name, and SiconosConfig.h sits one level up.
find_path(MICA_SICONOS_NUMERICS_INCLUDE_DIR NAMES LinearComplementarityProblem.h LCP_Solvers.h
          PATH_SUFFIXES siconos/numerics)
find_path(MICA_SICONOS_CONFIG_INCLUDE_DIR NAMES SiconosConfig.h PATH_SUFFIXES siconos)
find_library(MICA_SICONOS_NUMERICS_LIBRARY NAMES siconos_numerics)

if(MICA_SICONOS_NUMERICS_INCLUDE_DIR AND MICA_SICONOS_CONFIG_INCLUDE_DIR AND MICA_SICONOS_NUMERICS_LIBRARY)
  message(STATUS "LCP oracle test: Siconos numerics at ${MICA_SICONOS_NUMERICS_LIBRARY}")
  target_include_directories(solver_test_lcp_oracle SYSTEM PRIVATE
                             ${MICA_SICONOS_NUMERICS_INCLUDE_DIR} ${MICA_SICONOS_CONFIG_INCLUDE_DIR})
  target_link_libraries(solver_test_lcp_oracle PRIVATE ${MICA_SICONOS_NUMERICS_LIBRARY})
  target_compile_definitions(solver_test_lcp_oracle PRIVATE MICA_HAVE_SICONOS=1)
else()
  message(STATUS "LCP oracle test: Siconos numerics not found (install libsiconos-numerics-dev); "
                 "solver/test_lcp_oracle will be skipped")
  target_compile_definitions(solver_test_lcp_oracle PRIVATE MICA_HAVE_SICONOS=0)
endif()
set_tests_properties(solver/test_lcp_oracle PROPERTIES SKIP_RETURN_CODE 77)
