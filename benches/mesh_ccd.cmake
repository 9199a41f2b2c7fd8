# SPDX-License-Identifier: MIT
# impact-mesh-ccd-bench: mesh_ccd and mesh_self_ccd over the steps of two moving scenes, on one
# thread and on T, checked against a sweep over every primitive pair.
set(mesh_ccd_libs "")
if(TARGET impact::io)
  set(mesh_ccd_libs impact::io)
endif()
impact_add_bench(impact-mesh-ccd-bench mesh_ccd_bench.cpp LIBS ${mesh_ccd_libs} SMOKE_ARGS --steps 2 --threads 2 BAD_OPTION --steps)
if(TARGET impact::io)
  target_compile_definitions(impact-mesh-ccd-bench PRIVATE IMPACT_HAVE_IO=1)
endif()
