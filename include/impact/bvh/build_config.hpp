// SPDX-License-Identifier: MIT
/// \file
/// BuildConfig: the knobs of the top-down builder, with documented defaults.
#pragma once

namespace impact {

/// Where the top-down builder cuts a node along the longest axis of its primitives' centroid box.
enum class SplitRule {
  /// Middle of the centroid box along its longest axis (the default). O(n) per level, and it
  /// gave the fastest queries in impact-collide-bench (see README, "Split rule").
  SpatialMiddle,
  /// Median of the centroids along that axis: a balanced tree (depth log2 n), but cells of
  /// unequal size on uneven meshes. O(n) per level with nth_element.
  CentroidMedian,
};

struct BuildConfig {
  SplitRule split = SplitRule::SpatialMiddle;
  int leaf_size = 1;  ///< maximum primitives per leaf (>= 1); leaves may be larger only when all centroids coincide
};

}  // namespace impact
