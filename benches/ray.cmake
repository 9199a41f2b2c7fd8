# SPDX-License-Identifier: MIT
# impact-ray-bench: first-hit ray casts, impact against Intel Embree 3 (Debian libembree-dev, found
# through its CMake package or pkg-config), wrong answers judged by an exact referee; without
# Embree it runs without the Embree rows and says so.
set(ray_libs "")
if(TARGET impact::io)
  list(APPEND ray_libs impact::io)
endif()
impact_add_bench(impact-ray-bench ray_bench.cpp LIBS ${ray_libs} ${impact_embree_target} SMOKE_ARGS --rays 2000 --repeat 1 --threads 2 --grid 16 BAD_OPTION --rays)
if(TARGET impact::io)
  target_compile_definitions(impact-ray-bench PRIVATE IMPACT_HAVE_IO=1)
endif()
if(impact_embree_target)
  target_compile_definitions(impact-ray-bench PRIVATE IMPACT_HAVE_EMBREE=1)
endif()

# A flat mesh of one triangle (every origin of the short and long sets in its plane, about half of
# them on it): the referee judges starts on the triangle by the library's tie rule, so impact's
# answers count 0 wrong (ray_surface_starts.cmake). Label "bench-smoke".
if(TARGET impact::io)
  set(impact_one_triangle ${CMAKE_CURRENT_BINARY_DIR}/one-triangle.obj)
  file(WRITE ${impact_one_triangle} "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
  add_test(NAME impact-ray-bench-surface-starts
    COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:impact-ray-bench> -DMESH=${impact_one_triangle}
            "-DARGS=--rays,2000,--repeat,1,--threads,2,--grid,16" -DJSON=${CMAKE_CURRENT_BINARY_DIR}/impact-ray-bench-surface-starts.json
            -P ${CMAKE_CURRENT_SOURCE_DIR}/ray_surface_starts.cmake)
  set_tests_properties(impact-ray-bench-surface-starts PROPERTIES LABELS "bench-smoke" TIMEOUT 180)
endif()
