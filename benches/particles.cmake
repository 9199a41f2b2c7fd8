# SPDX-License-Identifier: MIT
# impact-particles-bench: particle collision response, backtracking against projection against an
# all-triangles reference and the loop a user would write on Embree 3 (when found), run time
# against error.
set(particles_libs "")
if(TARGET impact::io)
  set(particles_libs impact::io)
endif()
impact_add_bench(impact-particles-bench particles_bench.cpp LIBS ${particles_libs} ${impact_embree_target} SMOKE_ARGS --particles 200 --steps 5 BAD_OPTION --particles REAL_OPTION --dt)
if(impact_embree_target)
  target_compile_definitions(impact-particles-bench PRIVATE IMPACT_HAVE_EMBREE=1)
endif()
if(TARGET impact::io)
  target_compile_definitions(impact-particles-bench PRIVATE IMPACT_HAVE_IO=1)
endif()

# Starts exactly on the mesh are drawn again (particles_surface_starts.cmake): a cube far from the
# origin in float, where many draws round onto a face, and a flat square, where all do.
if(TARGET impact::io)
  set(impact_far_cube ${CMAKE_CURRENT_BINARY_DIR}/far-cube.obj)
  set(impact_flat_square ${CMAKE_CURRENT_BINARY_DIR}/flat-square.obj)
  file(WRITE ${impact_far_cube} "v 4194304 4194304 4194304\nv 4194308 4194304 4194304\nv 4194308 4194308 4194304\nv 4194304 4194308 4194304\n"
                                "v 4194304 4194304 4194308\nv 4194308 4194304 4194308\nv 4194308 4194308 4194308\nv 4194304 4194308 4194308\n"
                                "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n")
  file(WRITE ${impact_flat_square} "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
  add_test(NAME impact-particles-bench-surface-starts
    COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:impact-particles-bench> -DCUBE=${impact_far_cube} -DFLAT=${impact_flat_square}
            -P ${CMAKE_CURRENT_SOURCE_DIR}/particles_surface_starts.cmake)
  set_tests_properties(impact-particles-bench-surface-starts PROPERTIES LABELS "bench-smoke" TIMEOUT 240)
endif()
