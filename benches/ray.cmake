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
