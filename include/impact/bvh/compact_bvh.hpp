// SPDX-License-Identifier: MIT
/// \file
/// CompactBvh: a read-only traversal copy of a Bvh<Aabb<S>> made to stay in cache: float boxes
/// rounded outward, each pair of siblings in one 64-byte cache line with their boxes stored axis
/// by axis (so one pass of arithmetic tests both siblings), laid out depth-first, and every
/// subtree of at most `leaf_size` primitives collapsed into one leaf (a subtree's primitives are a
/// contiguous range of the permutation). The bunny's 139k-node tree (7.8 MB in double) becomes
/// about 1 MB with leaves of 4. Made for first-hit ray casts that run many times against a static
/// mesh (particles).
///
/// Contract: every float box contains the source box (lower corner rounded down, upper corner
/// rounded up) and every collapsed leaf holds exactly its subtree's primitives, so a traversal
/// that is conservative on the source tree is conservative here and tests a superset of the
/// primitives, in leaves no larger than leaf_size (or the source's leaves, if larger). Rebuild
/// it when the source tree changes (refit).
///
/// Thread safety: immutable after construction; any number of threads may cast through one
/// CompactBvh at once. Rebuilding (assigning a new one) must not overlap those casts.
#pragma once

#include "impact/bvh/bvh.hpp"
#include "impact/bvh/traversal_stack.hpp"
#include "impact/core/next_float.hpp"
#include "impact/core/validate.hpp"
#include "impact/geometry/aabb.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

namespace impact {

namespace detail {
/// v rounded to float downwards (dir < 0) or upwards (dir > 0).
template <class S>
inline float round_to_float(S v, int dir) {
  float f = static_cast<float>(v);
  if (dir < 0 ? S(f) > v : S(f) < v)
    f = dir < 0 ? next_down(f) : next_up(f);
  return f;
}
}  // namespace detail

/// A node of a CompactBvh, as a value: its float box, and either its children's pair (inner
/// node, count 0) or a range of the primitive permutation (leaf, count > 0).
struct CompactBvhNode {
  float lo[3] = {0, 0, 0};
  float hi[3] = {0, 0, 0};
  std::int32_t first = 0;  ///< inner: index into CompactBvh::pairs(); leaf: offset into primitives()
  std::int32_t count = 0;  ///< 0 for inner nodes

  bool is_leaf() const { return count > 0; }
  Aabb<float> box() const { return {Vec3<float>(lo[0], lo[1], lo[2]), Vec3<float>(hi[0], hi[1], hi[2])}; }
};

/// Two siblings in one cache line, their boxes axis by axis: lo[axis][side], hi[axis][side].
struct alignas(64) CompactBvhPair {
  float lo[3][2] = {{0, 0}, {0, 0}, {0, 0}};
  float hi[3][2] = {{0, 0}, {0, 0}, {0, 0}};
  std::int32_t first[2] = {0, 0};  ///< per side, as CompactBvhNode::first
  std::int32_t count[2] = {0, 0};  ///< per side, as CompactBvhNode::count

  CompactBvhNode child(int side) const {
    CompactBvhNode n;
    for (int k = 0; k < 3; ++k) n.lo[k] = lo[k][side], n.hi[k] = hi[k][side];
    n.first = first[side];
    n.count = count[side];
    return n;
  }
  void set(int side, const CompactBvhNode& n) {
    for (int k = 0; k < 3; ++k) lo[k][side] = n.lo[k], hi[k][side] = n.hi[k];
    first[side] = n.first;
    count[side] = n.count;
  }
};
static_assert(sizeof(CompactBvhPair) == 64, "CompactBvhPair: one cache line");

class CompactBvh {
 public:
  /// Node id of the root (other ids are 2 * pair + side).
  static constexpr std::int32_t kRoot = -1;

  CompactBvh() = default;

  /// Copies `tree`, collapsing subtrees of at most leaf_size (>= 1) primitives into leaves. O(nodes).
  /// Throws InvalidInput for leaf_size < 1.
  template <class S>
  explicit CompactBvh(const Bvh<Aabb<S>>& tree, int leaf_size = 4) : primitives_(tree.primitives) {
    validate_in_range(leaf_size, 1, std::numeric_limits<int>::max(), "CompactBvh", "leaf_size");
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
      CompactBvhNode c = node(id);
      if (n.is_leaf() || size[s] <= leaf_size) {
        c.first = begin[s];
        c.count = size[s];
        set_node(id, c);
        // the whole subtree maps to this leaf
        std::vector<std::int32_t> sub{src};
        while (!sub.empty()) {
          const std::int32_t k = sub.back();
          sub.pop_back();
          map_[static_cast<std::size_t>(k)] = id;
          const auto& ck = tree.nodes[static_cast<std::size_t>(k)];
          if (!ck.is_leaf()) sub.insert(sub.end(), {ck.left(), ck.right()});
        }
        continue;
      }
      map_[s] = id;
      const auto p = static_cast<std::int32_t>(pairs_.size());
      pairs_.push_back({});
      pairs_.back().set(0, convert(tree.nodes[static_cast<std::size_t>(n.left())].bv));
      pairs_.back().set(1, convert(tree.nodes[static_cast<std::size_t>(n.right())].bv));
      c.first = p;
      c.count = 0;
      set_node(id, c);
      stack.push_back({n.right(), 2 * p + 1});
      stack.push_back({n.left(), 2 * p});
    }
  }

  bool empty() const { return primitives_.empty(); }
  /// Node by id (kRoot or 2 * pair + side), as a value.
  CompactBvhNode node(std::int32_t id) const { return id < 0 ? root_ : pairs_[static_cast<std::size_t>(id >> 1)].child(id & 1); }
  const std::vector<CompactBvhPair>& pairs() const { return pairs_; }
  const std::vector<std::int32_t>& primitives() const { return primitives_; }
  std::size_t num_primitives() const { return primitives_.size(); }
  /// The id of the node standing for node `source` of the source tree: its copy, or the collapsed
  /// leaf that holds it. The subtrees hold the same primitives, or the leaf a superset.
  std::int32_t from_source(std::int32_t source) const { return map_[static_cast<std::size_t>(source)]; }
  /// Bytes read by traversals (nodes and primitive permutation).
  std::size_t memory_bytes() const { return pairs_.size() * sizeof(CompactBvhPair) + primitives_.size() * sizeof(std::int32_t); }

 private:
  void set_node(std::int32_t id, const CompactBvhNode& n) {
    if (id < 0)
      root_ = n;
    else
      pairs_[static_cast<std::size_t>(id >> 1)].set(id & 1, n);
  }
  template <class S>
  static CompactBvhNode convert(const Aabb<S>& b) {
    CompactBvhNode c;
    for (int k = 0; k < 3; ++k) {
      c.lo[k] = detail::round_to_float(b.min[k], -1);
      c.hi[k] = detail::round_to_float(b.max[k], 1);
    }
    return c;
  }

  CompactBvhNode root_;
  std::vector<CompactBvhPair> pairs_;
  std::vector<std::int32_t> primitives_;
  std::vector<std::int32_t> map_;  // source node -> compact id
};

/// Nearest-first walk over a CompactBvh from node `start` (kRoot by default; it is entered
/// without a test), the contract of traverse_nearest (traverse.hpp) with the node keys computed
/// a pair at a time: `pair_keys(const CompactBvhPair&, S (&keys)[2])` gives for both siblings a
/// lower bound of what the node can hold, or NaN to skip it; a node is entered while its key is
/// <= `bound() -> S`; `visit(primitive_id) -> bool` (false stops the walk). The nearer sibling is
/// entered at once, the farther one kept on the stack. Returns the number of pairs tested.
template <class S, class PairKeys, class Bound, class Visit>
std::size_t traverse_nearest_pairs(const CompactBvh& tree, PairKeys&& pair_keys, Bound&& bound, Visit&& visit,
                                   std::int32_t start = CompactBvh::kRoot) {
  std::size_t tested = 0;
  if (tree.empty()) return tested;
  const CompactBvhNode root = tree.node(start);
  struct Entry {
    S key;
    std::int32_t node;
  };
  detail::TraversalStack<Entry, 128> stack;  // the farther siblings still to visit
  const std::int32_t* prims = tree.primitives().data();
  const CompactBvhPair* pairs = tree.pairs().data();
  std::int32_t first = root.first, count = root.count;
  for (;;) {
    if (count > 0) {
      for (std::int32_t k = first; k < first + count; ++k)
        if (!visit(prims[k])) return tested;
    } else {
      const CompactBvhPair& pair = pairs[first];
      S keys[2];
      pair_keys(pair, keys);
      ++tested;
      const S b = bound();
      const bool in0 = keys[0] <= b, in1 = keys[1] <= b;
      if (in0 || in1) {
        int side = in0 ? 0 : 1;
        if (in0 && in1) {
          side = keys[0] <= keys[1] ? 0 : 1;
          stack.push({keys[1 - side], 2 * first + (1 - side)});
        }
        first = pair.first[side];
        count = pair.count[side];
        continue;
      }
    }
    // the nearest pending node still below the bound
    for (;;) {
      if (stack.empty()) return tested;
      const Entry e = stack.pop();
      if (e.key <= bound()) {
        const CompactBvhPair& pair = pairs[e.node >> 1];
        first = pair.first[e.node & 1];
        count = pair.count[e.node & 1];
        break;
      }
    }
  }
}

}  // namespace impact
