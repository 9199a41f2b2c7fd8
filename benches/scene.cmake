# SPDX-License-Identifier: MIT
# impact-scene-bench: broad phases on big scenes (all pairs, static/dynamic split, hierarchical)
# against FCL's DynamicAABBTreeCollisionManager; without FCL it runs without the FCL column.
if(TARGET fcl)
  set(scene_fcl_lib fcl)
else()
  set(scene_fcl_lib "")
  message(STATUS "impact: FCL not found, impact-scene-bench runs without the FCL column")
endif()
impact_add_bench(impact-scene-bench scene_bench.cpp LIBS ${scene_fcl_lib} SMOKE_ARGS --objects 200 --steps 2)
if(TARGET fcl)
  target_compile_definitions(impact-scene-bench PRIVATE IMPACT_HAVE_FCL=1)
endif()
