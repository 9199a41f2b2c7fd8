# SPDX-License-Identifier: MIT
# Runs impact-ray-bench (EXE) on MESH, a flat mesh (one triangle in a plane z = const: every origin
# of the short and long sets lies in its plane, about half of them on the triangle), and checks
# that the exact referee counts no impact answer as wrong: a segment from a point of the triangle
# crosses it at t = 0 through its front face (d . n < 0) and not moving away from it, the library's
# tie rule, which the referee applies too (ray_referee.hpp; before, it counted every start as a
# crossing, and all of impact's rule-conforming answers moving away as missed). Also checks that
# some short segments do cross (those starting on the triangle through its front face), so that
# the rule is exercised.
# ARGS: the bench's arguments after MESH, separated by commas.
string(REPLACE "," ";" ARGS "${ARGS}")
file(REMOVE ${JSON})
execute_process(COMMAND ${EXE} ${MESH} ${ARGS} --json ${JSON} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} exited with '${rc}'\nstdout: ${out}\nstderr: ${err}")
endif()
if(NOT out MATCHES "set short: [0-9]+ segments, t_max [^,]*, ([0-9.]+)% cross")
  message(FATAL_ERROR "no short set in the output\nstdout: ${out}")
endif()
if(CMAKE_MATCH_1 STREQUAL "0.0")
  message(FATAL_ERROR "no short segment crosses the flat mesh: the tie rule is not exercised\nstdout: ${out}")
endif()
file(READ ${JSON} content)
string(JSON rows GET "${content}" rows)
string(JSON n LENGTH "${rows}")
math(EXPR last "${n} - 1")
set(judged 0)
foreach(i RANGE ${last})
  string(JSON library GET "${rows}" ${i} library)
  string(JSON method GET "${rows}" ${i} method)
  string(JSON set GET "${rows}" ${i} set)
  string(JSON wrong GET "${rows}" ${i} wrong)
  if(library STREQUAL "impact")
    math(EXPR judged "${judged} + 1")
    if(NOT wrong EQUAL 0)
      message(FATAL_ERROR "impact ${method} on set ${set}: ${wrong} wrong answers on a flat mesh\nstdout: ${out}")
    endif()
  endif()
endforeach()
if(judged LESS 9)
  message(FATAL_ERROR "only ${judged} impact rows in ${JSON}\nstdout: ${out}")
endif()
