// SPDX-License-Identifier: MIT
/// \file
/// Top-down construction: start with every primitive in the root; cut each node across the longest
/// axis of its primitives' centroid box (at the middle, or at the median: BuildConfig::split);
/// assign each primitive by its centroid; recurse until a node holds at most leaf_size primitives.
/// Each node's BV is fitted by the caller's `fit` callable around that node's primitives (for a
/// mesh: around the triangles' vertices), which is tighter than merging the children's BVs.
/// Degenerate splits (all centroids equal along the axis) fall back to cutting the index range in
/// half, so the build always terminates. Time O(n log n) for balanced splits.
#pragma once

#include "impact/bvh/build_config.hpp"
#include "impact/bvh/bvh.hpp"
#include "impact/core/error.hpp"

#include <algorithm>
#include <numeric>

namespace impact {

/// Builds a tree over centroids.size() primitives.
/// `fit(const std::int32_t* ids, std::size_t count) -> BV` returns a BV holding those primitives.
template <class BV, class Fit>
Bvh<BV> build_top_down(const std::vector<Vec3<typename BvTraits<BV>::Scalar>>& centroids, Fit&& fit, const BuildConfig& cfg = {}) {
  using S = typename BvTraits<BV>::Scalar;
  if (cfg.leaf_size < 1) throw InvalidInput("build_top_down: leaf_size must be >= 1");
  Bvh<BV> tree;
  const auto n = static_cast<std::int32_t>(centroids.size());
  if (n == 0) return tree;
  tree.primitives.resize(static_cast<std::size_t>(n));
  std::iota(tree.primitives.begin(), tree.primitives.end(), 0);
  tree.nodes.reserve(static_cast<std::size_t>(2 * (n / cfg.leaf_size + 1)));
  tree.nodes.push_back({});
  tree.nodes[0].first = 0;
  tree.nodes[0].count = n;  // provisional: every node starts as a leaf over its range

  std::vector<std::int32_t> stack{0};
  std::int32_t* ids = tree.primitives.data();
  while (!stack.empty()) {
    const std::int32_t ni = stack.back();
    stack.pop_back();
    const std::int32_t begin = tree.nodes[ni].first, count = tree.nodes[ni].count;
    tree.nodes[ni].bv = fit(ids + begin, static_cast<std::size_t>(count));
    if (count <= cfg.leaf_size) continue;

    Aabb<S> cbox;
    for (std::int32_t k = begin; k < begin + count; ++k) cbox.extend(centroids[ids[k]]);
    const int axis = cbox.longest_axis();
    std::int32_t mid;
    if (!(cbox.max[axis] > cbox.min[axis])) {
      mid = begin + count / 2;  // all centroids coincide: cut the range in half
    } else if (cfg.split == SplitRule::CentroidMedian) {
      mid = begin + count / 2;
      std::nth_element(ids + begin, ids + mid, ids + begin + count,
                       [&](std::int32_t a, std::int32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    } else {
      const S cut = (cbox.min[axis] + cbox.max[axis]) / S(2);
      std::int32_t* m = std::partition(ids + begin, ids + begin + count, [&](std::int32_t p) { return centroids[p][axis] < cut; });
      mid = static_cast<std::int32_t>(m - ids);
      if (mid == begin || mid == begin + count) mid = begin + count / 2;  // rounding at the cut
    }
    const auto left = static_cast<std::int32_t>(tree.nodes.size());
    tree.nodes.push_back({});
    tree.nodes.push_back({});
    tree.nodes[left].first = begin;
    tree.nodes[left].count = mid - begin;
    tree.nodes[left + 1].first = mid;
    tree.nodes[left + 1].count = begin + count - mid;
    tree.nodes[ni].first = left;
    tree.nodes[ni].count = 0;
    stack.push_back(left + 1);
    stack.push_back(left);
  }
  return tree;
}

}  // namespace impact
