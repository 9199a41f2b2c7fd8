// SPDX-License-Identifier: MIT
/// \file
/// BuildConfig: the knobs of the top-down builder, with documented defaults.
#pragma once

#include "impact/geometry/obb.hpp"

namespace impact {

/// Where the top-down builder cuts a node along the longest axis of its primitives' centroid box.
enum class SplitRule {
  /// The bounding volume's own default (the default of BuildConfig::split), DefaultSplitRule<BV>:
  /// Sah for oriented boxes, SpatialMiddle for spheres and AABBs (see docs/hierarchies.md, "SAH as
  /// the default split of oriented-box trees").
  Default,
  /// Middle of the centroid box along its longest axis. O(n) per level; the fastest build, and
  /// the default of sphere and AABB trees.
  SpatialMiddle,
  /// Median of the centroids along that axis: a balanced tree (depth log2 n), but cells of
  /// unequal size on uneven meshes. O(n) per level with nth_element.
  CentroidMedian,
  /// Binned surface-area heuristic (as ray-tracing libraries build; Wald 2007): on each of the
  /// three axes the centroids are put in BuildConfig::sah_bins bins, and the cut between bins
  /// that minimises area(left) * count(left) + area(right) * count(right) of the primitives'
  /// boxes is taken. Needs the primitives' boxes (build_top_down's `boxes`; MeshBvh passes the
  /// triangles' boxes). O(n) per level; a few times slower to build than the middle split (AABB
  /// trees 2.8-3.8x; oriented-box trees 1.1-1.6x, whose build is dominated by fitting). The
  /// default of oriented-box trees.
  Sah,
};

/// The split rule SplitRule::Default stands for in a tree of BV. Oriented boxes: Sah (in
/// impact-hierarchy-bench its median was lower or level on every query of all four meshes, for a
/// build of 1.1-1.6x the middle split's). Spheres and AABBs: SpatialMiddle (SAH builds their trees
/// about 3x slower; an explicit SplitRule::Sah is there for many-query uses).
template <class BV> struct DefaultSplitRule {
  static constexpr SplitRule value = SplitRule::SpatialMiddle;
};
template <class S> struct DefaultSplitRule<Obb<S>> {
  static constexpr SplitRule value = SplitRule::Sah;
};

/// `rule`, with SplitRule::Default replaced by the default of a tree of BV.
template <class BV> constexpr SplitRule resolve_split_rule(SplitRule rule) {
  return rule == SplitRule::Default ? DefaultSplitRule<BV>::value : rule;
}

/// How a tree is constructed (see bvh/build_top_down.hpp, bvh/build_bottom_up.hpp and
/// bvh/build_incremental.hpp).
enum class BuildMethod {
  TopDown,      ///< divide and conquer by BuildConfig::split (the default)
  BottomUp,     ///< agglomerative clustering of neighbours along a Morton curve (PLOC)
  Incremental,  ///< one primitive at a time, each next to the sibling of least surface-area cost
};

/// How IncrementalBvh searches for the sibling of a new leaf.
enum class SiblingSearch {
  /// Exact minimum of the cost: branch and bound over a priority queue (Bittner et al. 2015).
  /// Explores more nodes per insertion (a few hundred on scanned meshes).
  BranchAndBound,
  /// One path from the root (Catto's Box2D v3 descent): at each node, descend into the child
  /// whose subtree's lower bound is smaller and stop when neither can beat the best found.
  /// O(depth) per insertion; the cost it reaches is at most the root's and usually near the minimum.
  Greedy,
};

struct BuildConfig {
  BuildMethod method = BuildMethod::TopDown;
  /// Where top-down cuts; the default resolves per BV type (resolve_split_rule).
  SplitRule split = SplitRule::Default;
  int leaf_size = 1;  ///< maximum primitives per leaf (>= 1); a top-down leaf of a mesh may be larger when it holds copies of one triangle (MeshBvh)
  int sah_bins = 16;  ///< bins per axis of SplitRule::Sah, in [2, 256]
  /// Threads of BuildMethod::TopDown (bvh/build_top_down.hpp): <= 0 the hardware concurrency, 1
  /// the calling thread only. The tree is the same for every count.
  int threads = 0;
  /// Neighbours on each side that a cluster of BuildMethod::BottomUp considers (>= 1): larger
  /// finds better pairs and builds slower (8: igea builds in 1.6x the top-down time).
  int cluster_window = 8;
  /// BuildMethod::Incremental: how each new leaf's sibling is found, and whether the ancestors
  /// are improved by tree rotations (bvh/build_incremental.hpp).
  SiblingSearch sibling_search = SiblingSearch::Greedy;
  bool rotations = true;
};

}  // namespace impact
