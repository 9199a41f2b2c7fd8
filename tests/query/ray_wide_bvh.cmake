# SPDX-License-Identifier: MIT
# WideBvh and its first-hit casts against brute force (included by tests/query/CMakeLists.txt).
impact_add_test(test-ray-wide-bvh test_ray_wide_bvh.cpp)
