# SPDX-License-Identifier: MIT
# Runs a bench on MESH, a mesh whose vertices all lie at one point, and checks that it is refused
# at once: exit status 1 and a message that the mesh has no extent (not a hang, not an abort on an
# uncaught exception). ARGS: the bench's arguments, MESH among them, separated by commas.
string(REPLACE "," ";" ARGS "${ARGS}")
execute_process(COMMAND ${EXE} ${ARGS} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
if(NOT rc STREQUAL "1")
  message(FATAL_ERROR "${EXE} on a mesh without extent exited with '${rc}', not 1\nstdout: ${out}\nstderr: ${err}")
endif()
if(NOT err MATCHES "no extent")
  message(FATAL_ERROR "${EXE} on a mesh without extent: the message does not say so\nstderr: ${err}")
endif()
