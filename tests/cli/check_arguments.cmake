# SPDX-License-Identifier: Apache-2.0
# cmake -DPROGRAMS=<file setting program_<name> to each program's path> -DWORK=<scratch folder>
#       -P check_arguments.cmake
# Each example and benchmark given bad arguments: a number that is not one, or only begins like
# one ("20x"), or is out of range, and an option without its value. Each must exit with status 2
# before doing any work, saying on stderr what is wrong. And the folders a program writes into
# (its output folder, the parent of a --record file) are made. A program not built is skipped.
include(${PROGRAMS})
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
set(failures "")

# expect(<program> <exit status> <regular expression stderr must match> <arguments...>)
function(expect program status pattern)
  if(NOT DEFINED program_${program})
    message(STATUS "skipped (not built): ${program}")
    return()
  endif()
  execute_process(COMMAND ${program_${program}} ${ARGN} WORKING_DIRECTORY ${WORK} TIMEOUT 60
                  RESULT_VARIABLE got OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(REPLACE ";" " " command "${program} ${ARGN}")
  if(NOT got STREQUAL "${status}" OR NOT err MATCHES "${pattern}")
    set(failures "${failures}\n${command}: exit ${got} (expected ${status}), stderr '${err}' "
                 "(expected to match '${pattern}')" PARENT_SCOPE)
  else()
    message(STATUS "${command}: exit ${got}")
  endif()
endfunction()

# Numbers read whole and in range.
expect(cantilever_sag 2 "steps must be a whole number .*not 'abc'" . abc)
expect(cantilever_sag 2 "steps must be a whole number .*not '20x'" . 20x)
expect(cantilever_sag 2 "steps must be a whole number .*not '-5'" . -5)
expect(sphere_indent 2 "steps must be a whole number .*not '20x'" . 20x)
expect(sphere_indent 2 "steps must be a whole number from 12 .*not '5'" . 5)
expect(convergence_vs_stiffness 2 "steps must be .*not 'abc'" . abc)
expect(convergence_vs_stiffness 2 "cells-per-side must be .*not '1'" . 3 1)
expect(convergence_vs_stiffness 2 "iteration-cap must be .*not '1e3'" . 3 6 1e3)
expect(haptic_loop 2 "seconds must be a number .*not 'abc'" . abc)
expect(haptic_loop 2 "seconds must be a number .*not '2s'" . 2s)
expect(two_hands 2 "seconds must be a number .*not 'abc'" . abc)
expect(two_hands 2 "seconds must be a number .*not 'nan'" . nan)
expect(mica_replay 2 "--vtk-every must be a whole number .*not 'ten'" missing.micarec . --vtk-every ten)
expect(bench_solvers 2 "cells-per-side must be .*not '8x'" 8x)
expect(bench_servo 2 "seconds must be a number .*not 'abc'" abc)
expect(bench_servo 2 "refactor interval must be .*not '-1'" 1 data/nidus/nidus.msh -1)
expect(bench_nidus 2 "tolerance must be a number .*not 'abc'" mesh.msh abc)
expect(bench_nidus 2 "steps must be .*not '10x'" --defaults mesh.msh 10x)
expect(bench_nidus 2 "max-tets must be .*not 'many'" --scaling out.csv many)
expect(bench_contact 2 "--tol must be a number .*not 'abc'" --tol abc)
expect(bench_contact 2 "--run-limit must be a number .*not '0'" --run-limit 0)
expect(bench_scaling 2 "max-tets must be .*not '1e5'" out.csv 1e5)
expect(bench_factor 2 "cube:N must be .*not 'x'" cube:x)
expect(study_anchors 2 "cells must be .*not 'abc'" out hertz abc 1 1)

# An option without its value.
expect(haptic_loop 2 "--record needs FILE" . 2 --record)
expect(mica_replay 2 "--vtk-every needs N" missing.micarec . --vtk-every)
expect(bench_contact 2 "--csv needs FILE" --csv)

# Output folders and the folder of a --record file are made.
expect(haptic_loop 0 "" made/out 0.2 --record made/recording/session.micarec)
expect(cantilever_sag 0 "" made/cantilever 1)
foreach(file made/out/haptic_loop.csv made/recording/session.micarec made/cantilever/cantilever.csv)
  if(DEFINED program_haptic_loop AND NOT EXISTS ${WORK}/${file})
    set(failures "${failures}\nno ${file}: the program did not make its folder")
  endif()
endforeach()
# A folder that cannot be made is refused before the work, naming it.
file(WRITE ${WORK}/a-file "")
expect(cantilever_sag 1 "cannot make the folder 'a-file/out'" a-file/out 1)

if(failures)
  message(FATAL_ERROR "${failures}")
endif()
