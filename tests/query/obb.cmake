# SPDX-License-Identifier: MIT
# Oriented-box trees: brute force always, FCL's OBB trees when FCL and assimp are there.
if(TARGET fcl AND TARGET impact::io)
  impact_add_test(test-mesh-collide-obb test_mesh_collide_obb.cpp LIBS fcl impact::io)
else()
  message(STATUS "impact: FCL or assimp missing, the OBB tree tests are not built")
endif()
