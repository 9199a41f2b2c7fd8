# SPDX-License-Identifier: MIT
# expect_exit(WHAT CODE PATTERN ARG...): runs ${EXE} ARG... and fails the calling script unless the
# bench exits with status CODE and its stderr matches PATTERN (WHAT names the case in the message).
# Shared by bad_options.cmake and degenerate_mesh.cmake.
function(expect_exit what code pattern)
  execute_process(COMMAND ${EXE} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
  if(NOT rc STREQUAL "${code}")
    message(FATAL_ERROR "${what}: ${EXE} exited with '${rc}', not ${code}\nstdout: ${out}\nstderr: ${err}")
  endif()
  if(NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: the message does not match '${pattern}'\nstderr: ${err}")
  endif()
endfunction()
