// SPDX-License-Identifier: MIT
/// \file
/// Bottom-up construction: agglomerative clustering of nearby primitives, after the parallel
/// locally-ordered clustering (PLOC) of Meister and Bittner 2018. The primitives are sorted along
/// a Morton curve of their centroids; every cluster looks for the cluster within `window` places
/// of it in that order whose merged box has the smallest surface area; pairs that choose each
/// other merge; the list is compacted (keeping the curve order) and the rounds repeat until one
/// cluster is left. The decisions use the primitives' axis-aligned boxes; the tree's BVs (any BV
/// type) are then fitted by the caller's `fit` around each node's primitives, as in the top-down
/// build (axis-aligned boxes: leaves fitted, inner nodes merged from their children, which gives
/// the same boxes bit for bit in O(n)), and the tree is laid out depth-first in the flat form of
/// bvh.hpp (children adjacent and after their parent, so refit works unchanged). Subtrees of at
/// most leaf_size primitives become leaves.
///
/// Termination: ties are broken by a symmetric order on pairs, so the pair of neighbours that is
/// smallest in that order chooses itself from both ends and every round merges at least one pair
/// (equal primitives pair up in twos, so even all-coincident input takes log2 n rounds).
/// Time: O(n window) per round, the cluster count shrinks geometrically in practice; fitting is
/// O(sum of the leaves' depths) as for the top-down build, O(n) for axis-aligned boxes.
#pragma once

#include "impact/bvh/build_config.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/bvh.hpp"
#include "impact/core/error.hpp"
#include "impact/detail/morton.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

namespace impact {

namespace detail {

/// 63-bit Morton code of p quantised to 21 bits per axis over the box [lo, lo + 1 / inv_extent].
template <class S> std::uint64_t morton_code_63(const Vec3<S>& p, const Vec3<S>& lo, const Vec3<S>& inv_extent) {
  std::uint64_t code = 0;
  for (int k = 0; k < 3; ++k) {
    const S q = (p[k] - lo[k]) * inv_extent[k] * S(2097151);
    const std::uint64_t c = q > S(0) ? (q < S(2097151) ? static_cast<std::uint64_t>(q) : 2097151u) : 0u;
    code |= spread_bits_3(c) << k;
  }
  return code;
}

}  // namespace detail

/// Builds a tree over centroids.size() primitives bottom-up (see the file comment). `boxes`: one
/// axis-aligned box per primitive (the clustering's distance); `fit(const std::int32_t* ids,
/// std::size_t count) -> BV` as for build_top_down. BuildConfig::cluster_window: how many
/// neighbours on each side of the Morton order a cluster considers.
/// Throws InvalidInput on leaf_size < 1, cluster_window < 1 or a box count that does not match.
template <class BV, class Fit>
Bvh<BV> build_bottom_up(const std::vector<Vec3<typename BvTraits<BV>::Scalar>>& centroids,
                        const std::vector<Aabb<typename BvTraits<BV>::Scalar>>& boxes, Fit&& fit, const BuildConfig& cfg = {}) {
  using S = typename BvTraits<BV>::Scalar;
  if (cfg.leaf_size < 1) throw InvalidInput("build_bottom_up: leaf_size must be >= 1");
  const int window = cfg.cluster_window;
  if (window < 1) throw InvalidInput("build_bottom_up: cluster_window must be >= 1");
  if (boxes.size() != centroids.size()) throw InvalidInput("build_bottom_up: one box per primitive");
  Bvh<BV> tree;
  const auto n = static_cast<std::int32_t>(centroids.size());
  if (n == 0) return tree;

  // Cluster nodes: 0..n-1 are the primitives, later ones merges of two earlier nodes.
  std::vector<Aabb<S>> box(boxes.begin(), boxes.end());
  box.reserve(static_cast<std::size_t>(2 * n));
  std::vector<std::pair<std::int32_t, std::int32_t>> kids(static_cast<std::size_t>(n), {-1, -1});
  kids.reserve(static_cast<std::size_t>(2 * n));

  std::vector<std::int32_t> clusters(static_cast<std::size_t>(n));
  {
    Aabb<S> cbox;
    for (const auto& c : centroids) cbox.extend(c);
    Vec3<S> inv = Vec3<S>::Zero();
    for (int k = 0; k < 3; ++k) {
      const S e = cbox.max[k] - cbox.min[k];
      inv[k] = e > S(0) ? S(1) / e : S(0);
    }
    std::vector<std::pair<std::uint64_t, std::int32_t>> order(static_cast<std::size_t>(n));
    for (std::int32_t i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = {detail::morton_code_63(centroids[static_cast<std::size_t>(i)], cbox.min, inv), i};
    std::sort(order.begin(), order.end());
    for (std::size_t i = 0; i < order.size(); ++i) clusters[i] = order[i].second;
  }

  std::vector<std::int32_t> nearest;
  std::vector<S> best;
  std::vector<std::int32_t> next;
  std::vector<Aabb<S>> round_box;
  while (clusters.size() > 1) {
    const auto m = static_cast<std::int32_t>(clusters.size());
    nearest.assign(static_cast<std::size_t>(m), -1);
    best.assign(static_cast<std::size_t>(m), std::numeric_limits<S>::infinity());
    // A strict order on unordered pairs {i, j}: area, then distance in the list, then pairs
    // starting at an even position, then the lower start. Being symmetric, its smallest pair
    // chooses itself from both ends; on ties (coincident or equal primitives) every even position
    // pairs with the next, so a round halves the clusters instead of merging one pair.
    const auto offer = [&](std::int32_t i, std::int32_t j, S d) {
      S& b = best[static_cast<std::size_t>(i)];
      std::int32_t& pick = nearest[static_cast<std::size_t>(i)];
      const auto key = [i](std::int32_t k) { return std::make_tuple(std::abs(k - i), std::min(i, k) % 2, std::min(i, k)); };
      if (d < b || (d == b && pick >= 0 && key(j) < key(pick))) b = d, pick = j;
    };
    // this round's boxes in list order: the window reads them in sequence (the boxes of merged
    // clusters are appended far from their neighbours' in `box`)
    round_box.resize(static_cast<std::size_t>(m));
    for (std::int32_t i = 0; i < m; ++i) round_box[static_cast<std::size_t>(i)] = box[static_cast<std::size_t>(clusters[static_cast<std::size_t>(i)])];
    for (std::int32_t i = 0; i < m; ++i) {  // each pair once: the area is symmetric
      const Aabb<S>& bi = round_box[static_cast<std::size_t>(i)];
      for (std::int32_t j = i + 1; j <= std::min(m - 1, i + window); ++j) {
        const Aabb<S>& bj = round_box[static_cast<std::size_t>(j)];
        // detail::half_area(merge(bi, bj)), the same operations, without its empty-box test
        // (boxes of finite triangles are never empty)
        const Vec3<S> e = bi.max.cwiseMax(bj.max) - bi.min.cwiseMin(bj.min);
        const S d = e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
        offer(i, j, d);
        offer(j, i, d);
      }
    }
    next.clear();
    for (std::int32_t i = 0; i < m; ++i) {
      const std::int32_t j = nearest[static_cast<std::size_t>(i)];
      const bool mutual = nearest[static_cast<std::size_t>(j)] == i;
      if (!mutual) {
        next.push_back(clusters[static_cast<std::size_t>(i)]);
      } else if (i < j) {
        const std::int32_t a = clusters[static_cast<std::size_t>(i)], b = clusters[static_cast<std::size_t>(j)];
        box.push_back(merge(box[static_cast<std::size_t>(a)], box[static_cast<std::size_t>(b)]));
        kids.emplace_back(a, b);
        next.push_back(static_cast<std::int32_t>(kids.size()) - 1);
      }
    }
    if (static_cast<std::int32_t>(next.size()) == m) {
      // cannot happen with the tie order above; merge the first two rather than loop forever
      const std::int32_t a = next[0], b = next[1];
      box.push_back(merge(box[static_cast<std::size_t>(a)], box[static_cast<std::size_t>(b)]));
      kids.emplace_back(a, b);
      next.erase(next.begin());
      next[0] = static_cast<std::int32_t>(kids.size()) - 1;
    }
    clusters.swap(next);

  }

  // Primitive counts of the cluster nodes (children precede parents in `kids`).
  std::vector<std::int32_t> size(kids.size(), 1);
  for (std::size_t k = static_cast<std::size_t>(n); k < kids.size(); ++k)
    size[k] = size[static_cast<std::size_t>(kids[k].first)] + size[static_cast<std::size_t>(kids[k].second)];

  // Depth-first layout: every flat node gets the range [begin, begin + size) of the permutation.
  tree.primitives.resize(static_cast<std::size_t>(n));
  tree.nodes.reserve(static_cast<std::size_t>(2 * n));
  tree.nodes.push_back({});
  struct Item {
    std::int32_t cluster, flat, begin;
  };
  std::vector<Item> stack{{clusters[0], 0, 0}};
  std::vector<std::pair<std::int32_t, std::int32_t>> range(1);
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const std::int32_t count = size[static_cast<std::size_t>(it.cluster)];
    range[static_cast<std::size_t>(it.flat)] = {it.begin, count};
    if (count <= cfg.leaf_size) {
      // collect the subtree's primitives into its range
      std::int32_t out = it.begin;
      std::vector<std::int32_t> sub{it.cluster};
      while (!sub.empty()) {
        const std::int32_t c = sub.back();
        sub.pop_back();
        if (c < n) {
          tree.primitives[static_cast<std::size_t>(out++)] = c;
        } else {
          sub.push_back(kids[static_cast<std::size_t>(c)].second);
          sub.push_back(kids[static_cast<std::size_t>(c)].first);
        }
      }
      tree.nodes[static_cast<std::size_t>(it.flat)].first = it.begin;
      tree.nodes[static_cast<std::size_t>(it.flat)].count = count;
      continue;
    }
    const auto [l, r] = kids[static_cast<std::size_t>(it.cluster)];
    const auto left = static_cast<std::int32_t>(tree.nodes.size());
    tree.nodes.push_back({});
    tree.nodes.push_back({});
    range.resize(tree.nodes.size());
    tree.nodes[static_cast<std::size_t>(it.flat)].first = left;
    tree.nodes[static_cast<std::size_t>(it.flat)].count = 0;
    stack.push_back({r, left + 1, it.begin + size[static_cast<std::size_t>(l)]});
    stack.push_back({l, left, it.begin});
  }
  if constexpr (std::is_same_v<BV, Aabb<S>>) {
    // The box around a node's primitives is the box around its children's boxes, exactly (min
    // and max are exact): leaves are fitted, inner nodes merged, children before their parent
    // (they come after it in the layout). O(n) instead of fitting every node around all of its
    // primitives, which costs the sum of the leaves' depths (PLOC's trees are deeper than the
    // top-down split's: on igea that fitting was 80 % of this build's instructions).
    for (std::size_t k = tree.nodes.size(); k-- > 0;) {
      auto& node = tree.nodes[k];
      if (node.is_leaf())
        node.bv = fit(tree.primitives.data() + range[k].first, static_cast<std::size_t>(range[k].second));
      else
        node.bv = merge(tree.nodes[static_cast<std::size_t>(node.left())].bv, tree.nodes[static_cast<std::size_t>(node.right())].bv);
    }
  } else {
    for (std::size_t k = 0; k < tree.nodes.size(); ++k)
      tree.nodes[k].bv = fit(tree.primitives.data() + range[k].first, static_cast<std::size_t>(range[k].second));
  }
  return tree;
}

}  // namespace impact
