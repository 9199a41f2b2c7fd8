# SPDX-License-Identifier: MIT
# Argument checks of the public queries: poses, rays, radii, options, grid configs (included by
# tests/query/CMakeLists.txt).
impact_add_test(test-query-validation test_query_validation.cpp)
impact_add_test(test-scale-range test_scale_range.cpp)
