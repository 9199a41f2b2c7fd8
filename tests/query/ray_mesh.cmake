# SPDX-License-Identifier: MIT
# Ray-mesh, swept-sphere-mesh and closest-point-on-mesh queries against brute force (included by
# tests/query/CMakeLists.txt).
impact_add_test(test-ray-mesh test_ray_mesh.cpp)
impact_add_test(test-closest-point-mesh test_closest_point_mesh.cpp)
