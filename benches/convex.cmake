# SPDX-License-Identifier: MIT
# impact-convex-bench: boolean, distance and penetration queries between convex shapes (impact's
# convex layer, target impact::convex) against FCL's shape primitives on the same poses; without
# FCL it runs without the FCL rows, without libccd it is not built.
if(TARGET impact::convex)
  impact_add_bench(impact-convex-bench convex_bench.cpp LIBS impact::convex SMOKE_ARGS --pairs 6 --min-time 0)
  if(TARGET fcl)
    target_link_libraries(impact-convex-bench PRIVATE fcl)
    target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_FCL=1)
  else()
    message(STATUS "impact: FCL not found, impact-convex-bench runs without the FCL rows")
  endif()
else()
  message(STATUS "impact: libccd not found, impact-convex-bench is not built")
endif()
