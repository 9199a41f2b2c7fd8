# SPDX-License-Identifier: MIT
# impact-convex-bench: boolean, distance and penetration queries between convex shapes (impact's
# convex layer, target impact::convex) against FCL's shape primitives on the same poses; without
# FCL it runs without the FCL rows, without libccd it is not built. Its mesh rows (mesh against each
# shape) take --mesh FILE through impact::io when assimp is there.
if(TARGET impact::convex)
  impact_add_bench(impact-convex-bench convex_bench.cpp LIBS impact::convex SMOKE_ARGS --pairs 6 --mesh-poses 4 --min-time 0 BAD_OPTION --pairs REAL_OPTION --min-time)
  if(TARGET impact::io)  # --mesh FILE through the assimp loader
    target_link_libraries(impact-convex-bench PRIVATE impact::io)
    target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_IO=1)
  endif()
  if(TARGET fcl)
    target_link_libraries(impact-convex-bench PRIVATE fcl)
    target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_FCL=1)
  else()
    message(STATUS "impact: FCL not found, impact-convex-bench runs without the FCL rows")
  endif()
else()
  message(STATUS "impact: libccd not found, impact-convex-bench is not built")
endif()
