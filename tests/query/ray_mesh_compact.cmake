# SPDX-License-Identifier: MIT
# Ray casts through a CompactBvh against the plain tree (included by tests/query/CMakeLists.txt).
impact_add_test(test-ray-mesh-compact test_ray_mesh_compact.cpp)
