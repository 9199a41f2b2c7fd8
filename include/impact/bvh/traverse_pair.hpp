// SPDX-License-Identifier: MIT
/// \file
/// Pair traversal of two trees (or of one tree against itself), iterative, written once for every
/// BV type. Where two nodes' BVs overlap, the larger node (BvTraits::size) is split first, or the
/// inner one when the other is a leaf; leaf pairs go to the visitor. The overlap callable carries
/// any relative transform, so neither tree is rebuilt or copied to move one mesh against another.
/// A query that stops at its first hit can pass an order (traverse_pair_nodes' last argument)
/// that says which of the two children to walk first; every other walk keeps the tree's order.
#pragma once

#include "impact/bvh/bvh.hpp"
#include "impact/bvh/traversal_stack.hpp"

#include <utility>

namespace impact {


namespace detail {
/// The tree's order: the left child first.
struct TreeOrder {
  template <class X, class Y>
  bool right_first_a(const X&, const X&, const Y&) const {
    return false;
  }
  template <class X, class Y>
  bool right_first_b(const X&, const Y&, const Y&) const {
    return false;
  }
};

/// One step of pair traversal for nodes i (tree a) and j (tree b) that passed the node test: hand
/// a leaf pair to the visitor, or push the children of the larger node (the inner one if the
/// other is a leaf). Returns false when the visitor stopped the walk.
/// `order` picks which child is walked first (right_first_a(left, right, other) for a split of
/// node i, right_first_b(other, left, right) for one of node j).
template <class BVA, class BVB, class Stack, class Visit, class Order = TreeOrder>
bool visit_or_split(const Bvh<BVA>& a, const Bvh<BVB>& b, std::int32_t i, std::int32_t j, Stack& stack, Visit& visit,
                    const Order& order = {}) {
  const auto& na = a.nodes[static_cast<std::size_t>(i)];
  const auto& nb = b.nodes[static_cast<std::size_t>(j)];
  const bool la = na.is_leaf(), lb = nb.is_leaf();
  if (la && lb) {
    for (std::int32_t p = na.first; p < na.first + na.count; ++p)
      for (std::int32_t q = nb.first; q < nb.first + nb.count; ++q)
        if (!visit(a.primitives[static_cast<std::size_t>(p)], b.primitives[static_cast<std::size_t>(q)])) return false;
  } else if (lb || (!la && BvTraits<BVA>::size(na.bv) >= BvTraits<BVB>::size(nb.bv))) {
    std::int32_t first = na.left(), second = na.right();
    if (order.right_first_a(a.nodes[static_cast<std::size_t>(first)].bv, a.nodes[static_cast<std::size_t>(second)].bv, nb.bv))
      std::swap(first, second);
    stack.push({second, j});
    stack.push({first, j});
  } else {
    std::int32_t first = nb.left(), second = nb.right();
    if (order.right_first_b(na.bv, b.nodes[static_cast<std::size_t>(first)].bv, b.nodes[static_cast<std::size_t>(second)].bv))
      std::swap(first, second);
    stack.push({i, second});
    stack.push({i, first});
  }
  return true;
}
}  // namespace detail

/// Visits every pair of primitives (id_a, id_b) whose leaves pass the node test.
/// `overlap(const BvhNode<BVA>& a, const BvhNode<BVB>& b) -> bool` sees whole nodes, so a query
/// can test a leaf's primitives directly instead of its BV; it must be conservative (never false
/// when the primitives below the two nodes can touch). `visit(std::int32_t id_a, std::int32_t id_b)
/// -> bool` returns false to stop. Returns false when the visitor stopped the walk. `start_a`,
/// `start_b` (the roots by default) restrict the walk to the pairs below those two nodes. `order`
/// (see detail::TreeOrder) chooses which child of a split node is walked first: it changes which
/// pair a stopped walk reaches first, never the set of pairs a full walk visits.
template <class BVA, class BVB, class NodeOverlap, class Visit, class Order = detail::TreeOrder>
bool traverse_pair_nodes(const Bvh<BVA>& a, const Bvh<BVB>& b, NodeOverlap&& overlap, Visit&& visit, std::int32_t start_a = 0,
                         std::int32_t start_b = 0, const Order& order = {}) {
  if (a.empty() || b.empty()) return true;
  // One node pair: its test, with the children (adjacent) of both nodes fetched while it runs (one
  // of the two pairs of children is read next whenever the test passes).
  const auto passes = [&](std::int32_t i, std::int32_t j) {
    const auto& na = a.nodes[static_cast<std::size_t>(i)];
    const auto& nb = b.nodes[static_cast<std::size_t>(j)];
    if (!na.is_leaf()) detail::prefetch_bytes(&a.nodes[static_cast<std::size_t>(na.first)], 2 * sizeof(na));
    if (!nb.is_leaf()) detail::prefetch_bytes(&b.nodes[static_cast<std::size_t>(nb.first)], 2 * sizeof(nb));
    return overlap(na, nb);
  };
  // The first pair is tested before the stack exists: a query decided there (most poses of two
  // meshes near each other are, at the roots) pays for nothing else. Same tests, same order.
  if (!passes(start_a, start_b)) return true;
  detail::TraversalStack<std::pair<std::int32_t, std::int32_t>> stack;
  if (!detail::visit_or_split(a, b, start_a, start_b, stack, visit, order)) return false;
  while (!stack.empty()) {
    const auto [i, j] = stack.pop();
    if (!passes(i, j)) continue;
    if (!detail::visit_or_split(a, b, i, j, stack, visit, order)) return false;
  }
  return true;
}

/// Visits every pair of primitives (id_a, id_b) whose leaves' BVs overlap.
/// `overlap(const BVA& a, const BVB& b) -> bool` must be conservative (never false for volumes
/// that touch). `visit(std::int32_t id_a, std::int32_t id_b) -> bool` returns false to stop.
/// Returns false when the visitor stopped the walk. `start_a`, `start_b` as for traverse_pair_nodes.
template <class BVA, class BVB, class Overlap, class Visit>
bool traverse_pair(const Bvh<BVA>& a, const Bvh<BVB>& b, Overlap&& overlap, Visit&& visit, std::int32_t start_a = 0,
                   std::int32_t start_b = 0) {
  return traverse_pair_nodes(
      a, b, [&](const BvhNode<BVA>& na, const BvhNode<BVB>& nb) { return overlap(na.bv, nb.bv); }, visit, start_a, start_b);
}

/// Visits every unordered pair {id_a, id_b}, id_a != id_b, of primitives of one tree whose
/// leaves' BVs overlap (pairs within one leaf are always visited). Same callables as
/// traverse_pair; each pair is visited once. The walk starts at (start_i, start_j), the root
/// (0, 0) by default: (i, i) stands for the pairs inside node i, (i, j), i != j, for the pairs
/// across nodes i and j.
template <class BV, class Overlap, class Visit>
bool traverse_self(const Bvh<BV>& t, Overlap&& overlap, Visit&& visit, std::int32_t start_i = 0, std::int32_t start_j = 0) {
  if (t.empty()) return true;
  detail::TraversalStack<std::pair<std::int32_t, std::int32_t>> stack;
  stack.push({start_i, start_j});
  while (!stack.empty()) {
    const auto [i, j] = stack.pop();
    const auto& ni = t.nodes[static_cast<std::size_t>(i)];
    if (i == j) {
      if (ni.is_leaf()) {
        for (std::int32_t p = ni.first; p < ni.first + ni.count; ++p)
          for (std::int32_t q = p + 1; q < ni.first + ni.count; ++q)
            if (!visit(t.primitives[static_cast<std::size_t>(p)], t.primitives[static_cast<std::size_t>(q)])) return false;
      } else {
        stack.push({ni.left(), ni.right()});
        stack.push({ni.right(), ni.right()});
        stack.push({ni.left(), ni.left()});
      }
      continue;
    }
    if (!overlap(ni.bv, t.nodes[static_cast<std::size_t>(j)].bv)) continue;
    if (!detail::visit_or_split(t, t, i, j, stack, visit)) return false;
  }
  return true;
}

}  // namespace impact
