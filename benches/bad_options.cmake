# SPDX-License-Identifier: MIT
# Runs a bench with bad command lines and checks that each is refused before any work: exit status
# 2 (not a crash, not a run on a number nobody typed) and a message on stderr that names the
# problem. OPTION is one of the bench's integer options, REAL_OPTION (when given) one of its
# real-number options whose range lies within [0, 1e200]; MISSING_DIR a folder that does not exist.
include(${CMAKE_CURRENT_LIST_DIR}/expect_exit.cmake)
function(expect_refused what pattern)
  expect_exit("${what}" 2 "${pattern}" ${ARGN})
endfunction()

# Values no integer option may take: words, trailing characters, overflow, NaN, a fraction, and
# values beyond every integer option's range (above 2^31 - 1, below -2^31: an int would wrap).
foreach(value abc 12x 99999999999999999999 nan 1e999 2.5 -99999999999 2147483648)
  expect_refused("${OPTION} ${value}" "${OPTION} wants" ${OPTION} ${value})
endforeach()
# Values no real option may take: words, trailing characters, NaN, infinities, overflow, and
# values below 0 or above 1e200.
if(REAL_OPTION)
  foreach(value abc 1x nan inf -inf 1e999 -1 1e300)
    expect_refused("${REAL_OPTION} ${value}" "${REAL_OPTION} wants" ${REAL_OPTION} ${value})
  endforeach()
endif()
# an empty value (a list element cannot be empty, so not through expect_refused)
execute_process(COMMAND ${EXE} ${OPTION} "" RESULT_VARIABLE rc ERROR_VARIABLE err TIMEOUT 30)
if(NOT rc STREQUAL "2" OR NOT err MATCHES "${OPTION} wants")
  message(FATAL_ERROR "${OPTION} '': ${EXE} exited with '${rc}'\nstderr: ${err}")
endif()
expect_refused("${OPTION} without its value" "missing value" ${OPTION})
expect_refused("an unknown option" "unknown option" --no-such-option)
expect_refused("--json into a missing folder" "cannot write the --json file" --json ${MISSING_DIR}/out.json)
