# SPDX-License-Identifier: MIT
# The kd-tree over triangles: rays, segments and closest points against brute force (included by
# tests/query/CMakeLists.txt).
impact_add_test(test-kd-tree test_kd_tree.cpp)
