# SPDX-License-Identifier: Apache-2.0
# cmake -DPROGRAM=<example or benchmark> -P check_cli.cmake: `PROGRAM --help` exits 0 and prints
# its usage; `PROGRAM --no-such-option` exits 2 and names the option on stderr (without running).
execute_process(COMMAND ${PROGRAM} --help RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err
                TIMEOUT 30)
if(NOT status STREQUAL "0")
  message(FATAL_ERROR "${PROGRAM} --help exited with ${status}, not 0\n${out}${err}")
endif()
string(STRIP "${out}" text)
string(FIND "${text}" "usage:" at)
if(text STREQUAL "" OR NOT at EQUAL 0)
  message(FATAL_ERROR "${PROGRAM} --help printed no usage on stdout (it printed: '${out}')")
endif()
string(LENGTH "${text}" length)
message(STATUS "${PROGRAM} --help: exit 0, ${length} characters of usage")

execute_process(COMMAND ${PROGRAM} --no-such-option RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err
                TIMEOUT 30)
if(NOT status STREQUAL "2")
  message(FATAL_ERROR "${PROGRAM} --no-such-option exited with ${status}, not 2\n${out}${err}")
endif()
string(FIND "${err}" "--no-such-option" at)
if(at LESS 0)
  message(FATAL_ERROR "${PROGRAM} --no-such-option: stderr does not name the option\n${err}")
endif()
message(STATUS "${PROGRAM} --no-such-option: exit 2, named on stderr")
