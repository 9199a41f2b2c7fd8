// SPDX-License-Identifier: MIT
/// \file
/// CompactBvh: a read-only traversal copy of a Bvh<Aabb<S>> made to stay in cache: 32-byte nodes
/// (float boxes rounded outward), each pair of siblings in one 64-byte cache line, laid out
/// depth-first, and every subtree of at most `leaf_size` primitives collapsed into one leaf (a
/// subtree's primitives are a contiguous range of the permutation). The bunny's 139k-node tree
/// (7.8 MB in double) becomes about 1 MB with leaves of 4, which fits in a core's L2 cache. Made
/// for first-hit ray casts that run many times against a static mesh (particles).
///
/// Contract: every float box contains the source box (lower corner rounded down, upper corner
/// rounded up) and every collapsed leaf holds exactly its subtree's primitives, so a traversal
/// that is conservative on the source tree is conservative here and tests a superset of the
/// primitives, in leaves no larger than leaf_size (or the source's leaves, if larger). Rebuild
/// it when the source tree changes (refit).
#pragma once

#include "impact/bvh/bvh.hpp"
#include "impact/bvh/traversal_stack.hpp"
#include "impact/geometry/aabb.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

namespace impact {

/// A node of a CompactBvh: its float box, and either its children's pair (inner node, count 0)
/// or a range of the primitive permutation (leaf, count > 0).
struct CompactBvhNode {
  float lo[3] = {0, 0, 0};
  std::int32_t first = 0;  ///< inner: index into CompactBvh::pairs(); leaf: offset into primitives()
  float hi[3] = {0, 0, 0};
  std::int32_t count = 0;  ///< 0 for inner nodes

  bool is_leaf() const { return count > 0; }
  Aabb<float> box() const { return {Vec3<float>(lo[0], lo[1], lo[2]), Vec3<float>(hi[0], hi[1], hi[2])}; }
};

/// Two siblings, one cache line.
struct alignas(64) CompactBvhPair {
  CompactBvhNode child[2];
};

class CompactBvh {
 public:
  /// Node id of the root (other ids are 2 * pair + side).
  static constexpr std::int32_t kRoot = -1;

  CompactBvh() = default;

  /// Copies `tree`, collapsing subtrees of at most leaf_size (>= 1) primitives into leaves. O(nodes).
  template <class S>
  explicit CompactBvh(const Bvh<Aabb<S>>& tree, int leaf_size = 4) : primitives_(tree.primitives) {
    if (tree.empty()) return;
    const auto m = tree.nodes.size();
    // primitive count and first primitive of every subtree (children come after their parent)
    std::vector<std::int32_t> size(m), begin(m);
    for (std::size_t j = m; j-- > 0;) {
      const auto& n = tree.nodes[j];
      if (n.is_leaf()) {
        size[j] = n.count;
        begin[j] = n.first;
      } else {
        size[j] = size[static_cast<std::size_t>(n.left())] + size[static_cast<std::size_t>(n.right())];
        begin[j] = begin[static_cast<std::size_t>(n.left())];
      }
    }
    map_.assign(m, kRoot);
    pairs_.reserve(m / 2);
    root_ = convert(tree.nodes[0].bv);
    std::vector<std::pair<std::int32_t, std::int32_t>> stack{{0, kRoot}};  // (source node, compact id)
    while (!stack.empty()) {
      const auto [src, id] = stack.back();
      stack.pop_back();
      const auto s = static_cast<std::size_t>(src);
      const auto& n = tree.nodes[s];
      if (n.is_leaf() || size[s] <= leaf_size) {
        node(id).first = begin[s];
        node(id).count = size[s];
        // the whole subtree maps to this leaf
        std::vector<std::int32_t> sub{src};
        while (!sub.empty()) {
          const std::int32_t k = sub.back();
          sub.pop_back();
          map_[static_cast<std::size_t>(k)] = id;
          const auto& c = tree.nodes[static_cast<std::size_t>(k)];
          if (!c.is_leaf()) sub.insert(sub.end(), {c.left(), c.right()});
        }
        continue;
      }
      map_[s] = id;
      const auto p = static_cast<std::int32_t>(pairs_.size());
      pairs_.push_back({});
      pairs_.back().child[0] = convert(tree.nodes[static_cast<std::size_t>(n.left())].bv);
      pairs_.back().child[1] = convert(tree.nodes[static_cast<std::size_t>(n.right())].bv);
      node(id).first = p;
      node(id).count = 0;
      stack.push_back({n.right(), 2 * p + 1});
      stack.push_back({n.left(), 2 * p});
    }
  }

  bool empty() const { return primitives_.empty(); }
  /// Node by id (kRoot or 2 * pair + side).
  const CompactBvhNode& node(std::int32_t id) const {
    return id < 0 ? root_ : pairs_[static_cast<std::size_t>(id >> 1)].child[id & 1];
  }
  const std::vector<CompactBvhPair>& pairs() const { return pairs_; }
  const std::vector<std::int32_t>& primitives() const { return primitives_; }
  std::size_t num_primitives() const { return primitives_.size(); }
  /// The id of the node standing for node `source` of the source tree: its copy, or the collapsed
  /// leaf that holds it. The subtrees hold the same primitives, or the leaf a superset.
  std::int32_t from_source(std::int32_t source) const { return map_[static_cast<std::size_t>(source)]; }
  /// Bytes read by traversals (nodes and primitive permutation).
  std::size_t memory_bytes() const { return pairs_.size() * sizeof(CompactBvhPair) + primitives_.size() * sizeof(std::int32_t); }

 private:
  CompactBvhNode& node(std::int32_t id) { return id < 0 ? root_ : pairs_[static_cast<std::size_t>(id >> 1)].child[id & 1]; }
  template <class S>
  static CompactBvhNode convert(const Aabb<S>& b) {
    CompactBvhNode c;
    for (int k = 0; k < 3; ++k) {
      c.lo[k] = round(b.min[k], -std::numeric_limits<float>::infinity());
      c.hi[k] = round(b.max[k], std::numeric_limits<float>::infinity());
    }
    return c;
  }
  /// v rounded to float towards `dir` (-inf: down, +inf: up).
  template <class S>
  static float round(S v, float dir) {
    float f = static_cast<float>(v);
    if (dir < 0 ? S(f) > v : S(f) < v) f = std::nextafter(f, dir);
    return f;
  }

  CompactBvhNode root_;
  std::vector<CompactBvhPair> pairs_;
  std::vector<std::int32_t> primitives_;
  std::vector<std::int32_t> map_;  // source node -> compact id
};

/// Nearest-first walk over a CompactBvh from node `start` (kRoot by default), with the contract of
/// traverse_nearest (traverse.hpp): `key(const CompactBvhNode&) -> std::optional<S>`,
/// `bound() -> S`, `visit(primitive_id) -> bool`.
template <class Key, class Bound, class Visit>
void traverse_nearest(const CompactBvh& tree, Key&& key, Bound&& bound, Visit&& visit, std::int32_t start = CompactBvh::kRoot) {
  using S = typename std::invoke_result_t<Key&, const CompactBvhNode&>::value_type;
  if (tree.empty()) return;
  const std::optional<S> k0 = key(tree.node(start));
  if (!k0) return;
  detail::TraversalStack<std::pair<S, std::int32_t>, 128> stack;  // (key, node id)
  stack.push({*k0, start});
  const auto& prims = tree.primitives();
  while (!stack.empty()) {
    const auto [d, i] = stack.pop();
    if (!(d <= bound())) continue;
    const CompactBvhNode& n = tree.node(i);
    if (n.is_leaf()) {
      for (std::int32_t k = n.first; k < n.first + n.count; ++k)
        if (!visit(prims[static_cast<std::size_t>(k)])) return;
      continue;
    }
    const CompactBvhPair& pair = tree.pairs()[static_cast<std::size_t>(n.first)];
#if defined(__GNUC__) || defined(__clang__)
    // the grandchildren's lines: the next steps read them
    for (const CompactBvhNode& c : pair.child)
      if (!c.is_leaf()) __builtin_prefetch(&tree.pairs()[static_cast<std::size_t>(c.first)]);
#endif
    const std::int32_t l = 2 * n.first, r = l + 1;
    const auto kl = key(pair.child[0]);
    const auto kr = key(pair.child[1]);
    if (kl && kr) {
      if (*kl <= *kr) {
        stack.push({*kr, r});
        stack.push({*kl, l});
      } else {
        stack.push({*kl, l});
        stack.push({*kr, r});
      }
    } else if (kl) {
      stack.push({*kl, l});
    } else if (kr) {
      stack.push({*kr, r});
    }
  }
}

}  // namespace impact
