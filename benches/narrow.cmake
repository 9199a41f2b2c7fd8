# SPDX-License-Identifier: MIT
# impact-narrow-micro: Google Benchmark micro-benchmarks of the narrow-phase primitives
# (triangle–triangle against FCL's intersect_Triangle when FCL is found, ray–triangle, closest point).
if(TARGET benchmark::benchmark)
  set(narrow_libs benchmark::benchmark)
  if(TARGET fcl)
    list(APPEND narrow_libs fcl)
  endif()
  impact_add_bench(impact-narrow-micro narrow_micro.cpp LIBS ${narrow_libs} SMOKE_ARGS --benchmark_min_time=0.01)
  if(TARGET fcl)
    target_compile_definitions(impact-narrow-micro PRIVATE IMPACT_HAVE_FCL=1)
  endif()
else()
  message(STATUS "impact: Google Benchmark not found, impact-narrow-micro is not built")
endif()
