# SPDX-License-Identifier: MIT
# Runs impact-particles-bench (EXE) in float on CUBE, an axis-aligned cube of side 4 at 2^22 (the
# float spacing there is 0.5: a start drawn in the cube's box and rounded lands on a face about a
# third of the time), and checks that such starts are drawn again until they are off the mesh:
# some drawn again, none left on it, no escape. Then on FLAT, a square in a plane, whose box is
# the square itself: every draw is on it, and the bench must give up after its 64 draws a particle
# (all left on the mesh) and still run, not loop.
# Neither the exit status nor the counts may differ. Label "bench-smoke".
function(starts_of mesh)
  execute_process(COMMAND ${EXE} ${mesh} --particles 100 --steps 3 --threads 1 --float --quick --ref-particles 10
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${EXE} ${mesh} exited with '${rc}'\nstdout: ${out}\nstderr: ${err}")
  endif()
  if(NOT out MATCHES "starts exactly on the mesh: ([0-9]+) drawn again, ([0-9]+) left on it")
    message(FATAL_ERROR "no count of the starts on the mesh\nstdout: ${out}")
  endif()
  set(redrawn ${CMAKE_MATCH_1} PARENT_SCOPE)
  set(left ${CMAKE_MATCH_2} PARENT_SCOPE)
  set(out "${out}" PARENT_SCOPE)
endfunction()

starts_of(${CUBE})
if(redrawn EQUAL 0 OR NOT left EQUAL 0)
  message(FATAL_ERROR "far cube: ${redrawn} starts drawn again and ${left} left on the mesh (want some, and none)\nstdout: ${out}")
endif()
string(REGEX MATCHALL "\n(backtrack-wide|reference) +1 +[0-9]+ +[0-9]+ +[^ ]+ +([0-9]+)" rows "${out}")
list(LENGTH rows n)
if(n LESS 2)
  message(FATAL_ERROR "far cube: no backtrack-wide and reference rows\nstdout: ${out}")
endif()
foreach(row ${rows})
  if(NOT row MATCHES " 0$")
    message(FATAL_ERROR "far cube: an escape: ${row}\nstdout: ${out}")
  endif()
endforeach()

starts_of(${FLAT})
if(NOT left EQUAL 100)
  message(FATAL_ERROR "flat square: ${left} starts left on the mesh, not all 100\nstdout: ${out}")
endif()
