# SPDX-License-Identifier: MIT
# Mesh-mesh collision tests (included by tests/query/CMakeLists.txt).
impact_add_test(test-mesh-collide test_mesh_collide.cpp)
if(TARGET fcl AND TARGET impact::io)
  impact_add_test(test-mesh-collide-fcl test_mesh_collide_fcl.cpp LIBS fcl impact::io)
else()
  message(STATUS "impact: FCL or assimp missing, the FCL cross-check tests are not built")
endif()
# exact oracle (Boost.Multiprecision integers, header-only, test-only)
impact_add_test(test-mesh-collide-exact test_mesh_collide_exact.cpp)
impact_add_test(test-work-counts test_work_counts.cpp)
