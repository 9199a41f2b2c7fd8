# SPDX-License-Identifier: MIT
# Runs a bench on MESH, a mesh whose vertices all lie at one point, and checks that it is refused
# at once: exit status 1 and a message that the mesh has no extent (not a hang, not an abort on an
# uncaught exception). ARGS: the bench's arguments, MESH among them, separated by commas.
string(REPLACE "," ";" ARGS "${ARGS}")
include(${CMAKE_CURRENT_LIST_DIR}/expect_exit.cmake)
expect_exit("a mesh without extent" 1 "no extent" ${ARGS})
