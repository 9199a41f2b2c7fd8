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
