# SPDX-License-Identifier: Apache-2.0
# The `docs` target: the Doxygen HTML reference of the public headers, in <build>/docs/html.
# Not part of ALL; any Doxygen warning fails it (WARN_AS_ERROR in docs/Doxyfile.in).
find_package(Doxygen QUIET)
if(NOT DOXYGEN_FOUND)
  message(STATUS "Doxygen not found: the docs target is not available")
  return()
endif()

set(MICA_DOCS_OUTPUT_DIR ${PROJECT_BINARY_DIR}/docs)

# Inputs: include/mica/ plus every docs/*.md page; docs/index.md is the main page if present.
file(GLOB MICA_DOCS_PAGES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/docs/*.md)
file(GLOB MICA_DOCS_HEADERS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/include/mica/*.h)
set(MICA_DOCS_INPUT "\"${PROJECT_SOURCE_DIR}/include/mica\"")
foreach(_page IN LISTS MICA_DOCS_PAGES)
  string(APPEND MICA_DOCS_INPUT " \"${_page}\"")
endforeach()
set(MICA_DOCS_MAINPAGE "")
if(EXISTS ${PROJECT_SOURCE_DIR}/docs/index.md)
  set(MICA_DOCS_MAINPAGE "\"${PROJECT_SOURCE_DIR}/docs/index.md\"")
endif()

configure_file(${PROJECT_SOURCE_DIR}/docs/Doxyfile.in ${MICA_DOCS_OUTPUT_DIR}/Doxyfile @ONLY)

# The pages' pictures (![...](images/...)) are linked as they are, relative to the page: copied
# beside the HTML.
add_custom_target(docs
  COMMAND Doxygen::doxygen ${MICA_DOCS_OUTPUT_DIR}/Doxyfile
  COMMAND ${CMAKE_COMMAND} -E copy_directory ${PROJECT_SOURCE_DIR}/docs/images ${MICA_DOCS_OUTPUT_DIR}/html/images
  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
  DEPENDS ${MICA_DOCS_OUTPUT_DIR}/Doxyfile ${MICA_DOCS_HEADERS} ${MICA_DOCS_PAGES}
  COMMENT "Doxygen: API reference in ${MICA_DOCS_OUTPUT_DIR}/html"
  VERBATIM)

# `cmake --install <build> --component docs` after building docs; plain installs skip it.
install(DIRECTORY ${MICA_DOCS_OUTPUT_DIR}/html/
  DESTINATION ${MICA_INSTALL_DOCDIR}/html
  COMPONENT docs
  OPTIONAL
  EXCLUDE_FROM_ALL)
