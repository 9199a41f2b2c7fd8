# SPDX-License-Identifier: MIT
# impact-hierarchy-bench: every hierarchy (BV x builder, kd-tree) on the same work.
set(hierarchy_libs "")
if(TARGET impact::io)
  set(hierarchy_libs impact::io)
endif()
impact_add_bench(impact-hierarchy-bench hierarchy_bench.cpp LIBS ${hierarchy_libs} SMOKE_ARGS --poses 10 --rays 50 --copies 300 BAD_OPTION --poses)
if(TARGET impact::io)
  target_compile_definitions(impact-hierarchy-bench PRIVATE IMPACT_HAVE_IO=1)
endif()
