# SPDX-License-Identifier: MIT
# DistanceGrid: distance bounds against closest-point queries, start nodes against plain ray casts
# (included by tests/query/CMakeLists.txt).
impact_add_test(test-distance-grid test_distance_grid.cpp)
