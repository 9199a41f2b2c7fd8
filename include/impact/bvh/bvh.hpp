// SPDX-License-Identifier: MIT
/// \file
/// Bvh<BV>: a bounding-volume hierarchy stored flat. One vector of nodes, root at index 0; an inner
/// node's two children are adjacent (left = first, right = first + 1); a leaf covers the range
/// [first, first + count) of `primitives`, a permutation of the primitive ids given to the builder.
/// Builders (build_top_down.hpp) fill it, refit.hpp updates it, traverse*.hpp walk it.
///
/// Thread safety: traversals take a `const Bvh&` and only read: any number of threads may walk one
/// tree at once. refit() and rebuilding write: not concurrently with any traversal of that tree.
#pragma once

#include "impact/fit/bv_traits.hpp"

#include <cstdint>
#include <vector>

namespace impact {

template <class BV> struct BvhNode {
  BV bv;
  std::int32_t first = 0;  ///< inner: index of the left child; leaf: offset into Bvh::primitives
  std::int32_t count = 0;  ///< 0 for inner nodes, number of primitives for leaves

  bool is_leaf() const { return count > 0; }
  std::int32_t left() const { return first; }
  std::int32_t right() const { return first + 1; }
};

template <class BV> struct Bvh {
  using Traits = BvTraits<BV>;
  using Scalar = typename Traits::Scalar;
  using Node = BvhNode<BV>;

  std::vector<Node> nodes;             ///< nodes[0] is the root
  std::vector<std::int32_t> primitives;  ///< primitive ids in leaf order

  bool empty() const { return nodes.empty(); }
  const Node& root() const { return nodes.front(); }
  std::size_t num_primitives() const { return primitives.size(); }
};

/// Shape statistics of a tree, for benchmarks and tests.
struct BvhStats {
  std::size_t nodes = 0, leaves = 0, max_depth = 0, max_leaf_size = 0;
  double mean_leaf_depth = 0;
};

template <class BV> BvhStats bvh_stats(const Bvh<BV>& t) {
  BvhStats s;
  if (t.empty()) return s;
  s.nodes = t.nodes.size();
  std::vector<std::pair<std::int32_t, std::size_t>> stack{{0, 0}};
  double depth_sum = 0;
  while (!stack.empty()) {
    auto [i, d] = stack.back();
    stack.pop_back();
    const auto& n = t.nodes[static_cast<std::size_t>(i)];
    s.max_depth = std::max(s.max_depth, d);
    if (n.is_leaf()) {
      ++s.leaves;
      depth_sum += double(d);
      s.max_leaf_size = std::max(s.max_leaf_size, std::size_t(n.count));
    } else {
      stack.push_back({n.left(), d + 1});
      stack.push_back({n.right(), d + 1});
    }
  }
  s.mean_leaf_depth = depth_sum / double(s.leaves);
  return s;
}

}  // namespace impact
