// SPDX-License-Identifier: MIT
/// \file
/// Top-down construction: start with every primitive in the root; cut each node across the longest
/// axis of its primitives' centroid box (at the middle, or at the median: BuildConfig::split), or
/// where the binned surface-area heuristic is lowest on any axis (SplitRule::Sah; by default
/// oriented-box trees split so and the other BVs at the middle: DefaultSplitRule);
/// assign each primitive by its centroid; recurse until a node holds at most leaf_size primitives.
/// Each node's BV is fitted by the caller's `fit` callable around that node's primitives (for a
/// mesh: around the triangles' vertices), which is tighter than merging the children's BVs.
/// Degenerate splits (all centroids equal along the axis) fall back to cutting the index range in
/// half, so the build always terminates; given a CopyOrder (MeshBvh passes one), a range whose
/// centroids all coincide is instead sorted by shape, cut between two shapes, and made one leaf
/// when it holds copies of a single triangle (see CopyOrder). Time O(n log n) for balanced splits.
#pragma once

#include "impact/bvh/build_config.hpp"
#include "impact/bvh/bvh.hpp"
#include "impact/core/error.hpp"
#include "impact/core/parallel.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <array>
#include <numeric>
#include <utility>
#include <vector>

namespace impact {

/// No ordering of primitives by shape: a range whose centroids all coincide is cut in half.
struct NoCopyOrder {
  static constexpr bool enabled = false;
};

/// Copies of a triangle (the same three points, in any vertex order) share their centroid, so no
/// cut by centroids can separate them, and a tree of many copies, whose nodes all hold the same
/// shape, cannot prune any of them in a nearest-first query (the keys of all nodes are equal).
/// With a CopyOrder a range whose centroids all coincide is sorted by key (the shape, then the
/// vertex order, then the id: a strict weak order, so the tree does not depend on the thread
/// count), cut at the boundary between two shapes nearest its middle, and made one leaf, of any
/// size, when it holds one shape. The queries then test one copy per vertex order
/// (MeshBvh::repeats_previous).
template <class S> struct TriangleCopyOrder {
  static constexpr bool enabled = true;
  const std::vector<Triangle<S>>* triangles;  ///< by primitive id

  /// The vertices sorted lexicographically (the shape: entries 0-8), then in their order (9-17).
  std::array<S, 18> key(std::int32_t p) const {
    const Triangle<S>& t = (*triangles)[static_cast<std::size_t>(p)];
    std::array<std::array<S, 3>, 3> v{{{t.a.x(), t.a.y(), t.a.z()}, {t.b.x(), t.b.y(), t.b.z()}, {t.c.x(), t.c.y(), t.c.z()}}};
    std::array<S, 18> k;
    for (std::size_t j = 0; j < 9; ++j) k[9 + j] = v[j / 3][j % 3];
    std::sort(v.begin(), v.end());
    for (std::size_t j = 0; j < 9; ++j) k[j] = v[j / 3][j % 3];
    return k;
  }
  /// Whether two keys are of one shape.
  static bool same_shape(const std::array<S, 18>& a, const std::array<S, 18>& b) { return std::equal(a.begin(), a.begin() + 9, b.begin()); }
};

namespace detail {

/// Half the surface area of a box (0 for an empty one).
template <class S> S half_area(const Aabb<S>& b) {
  if (b.empty()) return S(0);
  const Vec3<S> e = b.extent();
  return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}

/// Binned SAH over ids[begin, begin + count): the best cut (axis, bin) and its cost, or axis -1
/// when every centroid falls in one bin on every axis. Centroids are binned over the centroid box.
template <class S>
void sah_split(const std::vector<Vec3<S>>& centroids, const std::vector<Aabb<S>>& boxes, const std::int32_t* ids,
               std::int32_t count, const Aabb<S>& cbox, int bins, int& best_axis, int& best_bin) {
  constexpr int kMaxBins = 256;
  struct Bin {
    Aabb<S> box;
    std::int32_t n = 0;
  };
  std::array<Bin, kMaxBins> bin;
  std::array<S, kMaxBins> right_cost;
  S best = std::numeric_limits<S>::infinity();
  best_axis = -1;
  best_bin = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const S lo = cbox.min[axis], ext = cbox.max[axis] - lo;
    if (!(ext > S(0))) continue;
    const S scale = S(bins) / ext;
    for (int b = 0; b < bins; ++b) bin[b] = Bin{};
    for (std::int32_t k = 0; k < count; ++k) {
      const std::int32_t p = ids[k];
      const int b = std::min(bins - 1, static_cast<int>((centroids[p][axis] - lo) * scale));
      bin[b].box.extend(boxes[p]);
      ++bin[b].n;
    }
    // right_cost[b]: area * count of bins b..bins-1; then sweep from the left
    Aabb<S> acc;
    std::int32_t n = 0;
    for (int b = bins - 1; b > 0; --b) {
      acc.extend(bin[b].box);
      n += bin[b].n;
      right_cost[b] = half_area(acc) * S(n);
    }
    acc = Aabb<S>();
    n = 0;
    for (int b = 1; b < bins; ++b) {  // cut between bin b - 1 and bin b
      acc.extend(bin[b - 1].box);
      n += bin[b - 1].n;
      if (n == 0 || n == count) continue;
      const S cost = half_area(acc) * S(n) + right_cost[b];
      if (cost < best) best = cost, best_axis = axis, best_bin = b;
    }
  }
}

/// Cuts ids[begin, begin + count) between the centroids below `at` and the rest along `axis`: the
/// first position of the right part. Equal centroids stay on one side.
template <class S>
std::int32_t partition_below(const std::vector<Vec3<S>>& centroids, std::int32_t* ids, std::int32_t begin, std::int32_t count, int axis, S at) {
  std::int32_t* m = std::partition(ids + begin, ids + begin + count, [&](std::int32_t p) { return centroids[p][axis] < at; });
  return static_cast<std::int32_t>(m - ids);
}

/// Where ids[begin, begin + count) is cut by cfg.split (count > 1): the first position of the
/// right child, strictly inside the range, or begin + count when the range stays one leaf (copies
/// of one triangle, see TriangleCopyOrder). Reorders only that range of ids.
template <class S, class CopyOrder>
std::int32_t top_down_cut(const std::vector<Vec3<S>>& centroids, const std::vector<Aabb<S>>& sah_boxes, std::int32_t* ids,
                          std::int32_t begin, std::int32_t count, const BuildConfig& cfg, const CopyOrder& copies) {
  Aabb<S> cbox;
  for (std::int32_t k = begin; k < begin + count; ++k) cbox.extend(centroids[ids[k]]);
  const int axis = cbox.longest_axis();
  std::int32_t mid;
  if (!(cbox.max[axis] > cbox.min[axis])) {
    mid = begin + count / 2;  // all centroids coincide: cut the range in half, or
    if constexpr (CopyOrder::enabled) {  // between two shapes, nearest the middle
      std::int32_t* r = ids + begin;
      const auto first = copies.key(r[0]);
      std::int32_t k = 1;
      while (k < count && copies.key(r[k]) == first) ++k;
      if (k == count) return begin + count;  // one triangle, in one vertex order: a leaf as it is
      std::vector<std::pair<std::array<S, 18>, std::int32_t>> keyed(static_cast<std::size_t>(count));
      for (std::int32_t j = 0; j < count; ++j) keyed[static_cast<std::size_t>(j)] = {copies.key(r[j]), r[j]};
      std::sort(keyed.begin(), keyed.end());
      for (std::int32_t j = 0; j < count; ++j) r[j] = keyed[static_cast<std::size_t>(j)].second;
      const auto same = [&](std::int32_t a, std::int32_t b) {
        return CopyOrder::same_shape(keyed[static_cast<std::size_t>(a)].first, keyed[static_cast<std::size_t>(b)].first);
      };
      if (same(0, count - 1)) return begin + count;
      std::int32_t lo = count / 2, hi = count / 2;  // a boundary j: entries j - 1 and j differ
      while (lo > 1 && same(lo - 1, lo)) --lo;
      while (hi < count - 1 && same(hi - 1, hi)) ++hi;
      const bool lo_ok = !same(lo - 1, lo), hi_ok = !same(hi - 1, hi);
      mid = begin + (lo_ok && (!hi_ok || count / 2 - lo <= hi - count / 2) ? lo : hi);
    }
  } else if (cfg.split == SplitRule::Sah) {
    int sah_axis, sah_bin;
    sah_split(centroids, sah_boxes, ids + begin, count, cbox, cfg.sah_bins, sah_axis, sah_bin);
    if (sah_axis < 0) {
      mid = begin + count / 2;  // unreachable when the centroid box has extent; kept for safety
    } else {
      const S lo = cbox.min[sah_axis], scale = S(cfg.sah_bins) / (cbox.max[sah_axis] - lo);
      std::int32_t* m = std::partition(ids + begin, ids + begin + count, [&](std::int32_t p) {
        return std::min(cfg.sah_bins - 1, static_cast<int>((centroids[p][sah_axis] - lo) * scale)) < sah_bin;
      });
      mid = static_cast<std::int32_t>(m - ids);
    }
  } else if (cfg.split == SplitRule::CentroidMedian) {
    mid = begin + count / 2;
    std::nth_element(ids + begin, ids + mid, ids + begin + count,
                     [&](std::int32_t a, std::int32_t b) { return centroids[a][axis] < centroids[b][axis]; });
    // equal centroids on one side: those equal to the median go right, or left if none is below
    const S at = centroids[ids[mid]][axis];
    mid = partition_below(centroids, ids, begin, count, axis, at);
    if (mid == begin) {
      std::int32_t* m = std::partition(ids + begin, ids + begin + count, [&](std::int32_t p) { return !(at < centroids[p][axis]); });
      mid = static_cast<std::int32_t>(m - ids);
    }
  } else {
    mid = partition_below(centroids, ids, begin, count, axis, (cbox.min[axis] + cbox.max[axis]) / S(2));
  }
  // A cut rounded onto an end of the centroid box (its extent a few ulps) left one side empty:
  // cut below the largest centroid instead, which keeps equal centroids together (copies of a
  // triangle whose vertex orders round their centroids apart, see TriangleCopyOrder).
  if (mid == begin || mid == begin + count) mid = partition_below(centroids, ids, begin, count, axis, cbox.max[axis]);
  return mid;
}

/// Grows the subtree below nodes[root] (a provisional leaf: first and count give its range of
/// ids): pops a node, fits it, cuts it, appends its two children and visits the left subtree
/// before the right one. Nodes of more than leaf_size but at most `defer_at_most` primitives are
/// neither fitted nor cut but listed in `deferred`, in visiting order (defer_at_most = 0: none).
template <class BV, class Fit, class Cut>
void grow_top_down(std::vector<BvhNode<BV>>& nodes, std::int32_t root, const std::int32_t* ids, Fit& fit, Cut& cut,
                   int leaf_size, std::int32_t defer_at_most, std::vector<std::int32_t>& deferred) {
  std::vector<std::int32_t> stack{root};
  while (!stack.empty()) {
    const std::int32_t ni = stack.back();
    stack.pop_back();
    const std::int32_t begin = nodes[ni].first, count = nodes[ni].count;
    if (count > leaf_size && count <= defer_at_most) {
      deferred.push_back(ni);
      continue;
    }
    nodes[ni].bv = fit(ids + begin, static_cast<std::size_t>(count));
    if (count <= leaf_size) continue;
    const std::int32_t mid = cut(begin, count);
    if (mid == begin + count) continue;  // one leaf of copies
    const auto left = static_cast<std::int32_t>(nodes.size());
    nodes.push_back({});
    nodes.push_back({});
    nodes[left].first = begin;
    nodes[left].count = mid - begin;
    nodes[left + 1].first = mid;
    nodes[left + 1].count = begin + count - mid;
    nodes[ni].first = left;
    nodes[ni].count = 0;
    stack.push_back(left + 1);
    stack.push_back(left);
  }
}

}  // namespace detail

/// Builds a tree over centroids.size() primitives.
/// `fit(const std::int32_t* ids, std::size_t count) -> BV` returns a BV holding those primitives.
/// `boxes` (one per primitive) are read by SplitRule::Sah only; without them SAH sees each
/// primitive as its centroid.
///
/// Threads (BuildConfig::threads): the levels above subtrees of about n / (8 * threads)
/// primitives are built on the calling thread, the subtrees below in parallel, each with its own
/// copy of `fit` (so a fit that keeps scratch memory must own it: copies run concurrently), and
/// the nodes are then laid out in the order the serial build gives. The cuts do not depend on the
/// order in which disjoint ranges are cut, so the tree is the same, node for node and bit for
/// bit, for every thread count. Meshes under 8,192 primitives are built serially.
///
/// `copies` (a TriangleCopyOrder, or NoCopyOrder) decides how ranges whose centroids all
/// coincide are cut; with a TriangleCopyOrder leaves may exceed cfg.leaf_size, holding copies of
/// one triangle only.
template <class BV, class Fit, class CopyOrder = NoCopyOrder>
Bvh<BV> build_top_down(const std::vector<Vec3<typename BvTraits<BV>::Scalar>>& centroids, Fit&& fit, const BuildConfig& config = {},
                       const std::vector<Aabb<typename BvTraits<BV>::Scalar>>& boxes = {}, const CopyOrder& copies = {}) {
  using S = typename BvTraits<BV>::Scalar;
  BuildConfig cfg = config;
  cfg.split = resolve_split_rule<BV>(config.split);
  if (cfg.leaf_size < 1) throw InvalidInput("build_top_down: leaf_size must be >= 1");
  if (cfg.split == SplitRule::Sah && (cfg.sah_bins < 2 || cfg.sah_bins > 256))
    throw InvalidInput("build_top_down: sah_bins must be in [2, 256]");
  if (!boxes.empty() && boxes.size() != centroids.size())
    throw InvalidInput("build_top_down: one box per primitive, or none");
  std::vector<Aabb<S>> point_boxes;
  if (cfg.split == SplitRule::Sah && boxes.empty()) {
    point_boxes.reserve(centroids.size());
    for (const auto& c : centroids) point_boxes.emplace_back(c, c);
  }
  const std::vector<Aabb<S>>& sah_boxes = boxes.empty() ? point_boxes : boxes;
  Bvh<BV> tree;
  const auto n = static_cast<std::int32_t>(centroids.size());
  if (n == 0) return tree;
  tree.primitives.resize(static_cast<std::size_t>(n));
  std::iota(tree.primitives.begin(), tree.primitives.end(), 0);
  std::int32_t* ids = tree.primitives.data();
  auto cut = [&](std::int32_t begin, std::int32_t count) {
    return detail::top_down_cut(centroids, sah_boxes, ids, begin, count, cfg, copies);
  };
  const int threads = resolve_threads(cfg.threads);
  const std::int32_t defer_at_most = threads > 1 && n >= 8192 ? n / (8 * threads) : 0;

  // The top of the tree (all of it when serial); provisional leaves: first/count give the range.
  std::vector<BvhNode<BV>> top(1);
  top[0].first = 0;
  top[0].count = n;
  top.reserve(defer_at_most > 0 ? std::size_t(64) * std::size_t(threads) : static_cast<std::size_t>(2 * (n / cfg.leaf_size + 1)));
  std::vector<std::int32_t> deferred;
  detail::grow_top_down(top, 0, ids, fit, cut, cfg.leaf_size, defer_at_most, deferred);
  if (deferred.empty()) {
    tree.nodes = std::move(top);
    return tree;
  }

  // The deferred subtrees, each in its own array: its root at 0, the rest in serial order.
  std::vector<std::vector<BvhNode<BV>>> sub(deferred.size());
  parallel_for(deferred.size(), threads, [&](std::size_t k) {
    auto f = fit;
    std::vector<std::int32_t> none;
    sub[k].reserve(static_cast<std::size_t>(2 * (top[deferred[k]].count / cfg.leaf_size + 1)));
    sub[k].push_back(top[deferred[k]]);
    detail::grow_top_down(sub[k], 0, ids, f, cut, cfg.leaf_size, 0, none);
  });

  // Lay the nodes out as the serial build does: replay its visiting order over the top, number
  // the top's nodes, and reserve each deferred subtree's nodes where the serial build would have
  // grown them; then copy the subtrees into their places in parallel.
  std::vector<std::int32_t> slot(top.size(), -1);
  for (std::size_t k = 0; k < deferred.size(); ++k) slot[static_cast<std::size_t>(deferred[k])] = static_cast<std::int32_t>(k);
  std::vector<std::pair<std::int32_t, std::int32_t>> place(deferred.size());  // (final index of its root, base)
  std::vector<std::pair<std::int32_t, BvhNode<BV>>> top_nodes;               // (final index, node)
  std::int32_t size = 1;
  std::vector<std::pair<std::int32_t, std::int32_t>> stack{{0, 0}};  // (top index, final index)
  while (!stack.empty()) {
    const auto [t, f] = stack.back();
    stack.pop_back();
    const std::int32_t k = slot[static_cast<std::size_t>(t)];
    if (k >= 0) {  // its sub index j >= 1 goes to base + j
      place[static_cast<std::size_t>(k)] = {f, size - 1};
      size += static_cast<std::int32_t>(sub[static_cast<std::size_t>(k)].size()) - 1;
      continue;
    }
    BvhNode<BV> node = top[static_cast<std::size_t>(t)];
    if (!node.is_leaf()) {
      stack.push_back({node.first + 1, size + 1});
      stack.push_back({node.first, size});
      node.first = size;
      size += 2;
    }
    top_nodes.push_back({f, node});
  }
  tree.nodes.resize(static_cast<std::size_t>(size));
  for (const auto& [f, node] : top_nodes) tree.nodes[static_cast<std::size_t>(f)] = node;
  parallel_for(deferred.size(), threads, [&](std::size_t k) {
    const auto& s = sub[k];
    const auto [f, base] = place[k];
    for (std::size_t j = 0; j < s.size(); ++j) {
      BvhNode<BV> node = s[j];
      if (!node.is_leaf()) node.first += base;
      tree.nodes[j == 0 ? static_cast<std::size_t>(f) : static_cast<std::size_t>(base) + j] = node;
    }
  });
  return tree;
}

}  // namespace impact
