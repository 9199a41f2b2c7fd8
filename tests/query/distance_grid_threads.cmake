# SPDX-License-Identifier: MIT
# DistanceGrid built on several threads: the same grid for every thread count (included by
# tests/query/CMakeLists.txt).
impact_add_test(test-distance-grid-threads test_distance_grid_threads.cpp CONCURRENCY)
