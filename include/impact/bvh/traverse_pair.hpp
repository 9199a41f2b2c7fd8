// SPDX-License-Identifier: MIT
/// \file
/// Pair traversal of two trees (or of one tree against itself), iterative, written once for every
/// BV type. Where two nodes' BVs overlap, the larger node (BvTraits::size) is split first, or the
/// inner one when the other is a leaf, or (box trees) the other one when exactly one is a twig
/// (both children leaves) that splitting would not shrink (split_first); leaf pairs go to the visitor. The overlap callable carries
/// any relative transform, so neither tree is rebuilt or copied to move one mesh against another.
/// A query that stops at its first hit can pass an order (traverse_pair_nodes' last argument)
/// that says which of the two children to walk first; every other walk keeps the tree's order.
#pragma once

#include "impact/bvh/bvh.hpp"
#include "impact/bvh/traversal_stack.hpp"
#include "impact/geometry/aabb.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/sphere.hpp"

#include <cstddef>
#include <cstdint>
#include <type_traits>
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

/// True when node n (inner) is a twig: both its children are leaves.
template <class BV> bool is_twig(const Bvh<BV>& t, const BvhNode<BV>& n) {
  return t.nodes[static_cast<std::size_t>(n.left())].is_leaf() && t.nodes[static_cast<std::size_t>(n.right())].is_leaf();
}

/// Half the surface area of a box: what a box of the other tree is assumed to meet in proportion
/// to, as the SAH builder assumes of rays.
template <class S> S twig_area(const Aabb<S>& x) {
  const Vec3<S> e = x.max - x.min;
  return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}
template <class S> S twig_area(const Obb<S>& x) {
  const Vec3<S>& e = x.half;
  return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}

/// True when splitting node n (a twig: both children leaves) gains nothing by the surface-area
/// measure: its children's areas add up to at least its own (two long slivers side by side, as
/// the walls and floor of env.obj).
template <class BV> bool twig_split_gains_nothing(const Bvh<BV>& t, const BvhNode<BV>& n) {
  return twig_area(t.nodes[static_cast<std::size_t>(n.left())].bv) + twig_area(t.nodes[static_cast<std::size_t>(n.right())].bv) >=
         twig_area(n.bv);
}

/// The size rule for two inner nodes: true to split na (tree a), false to split nb: the larger
/// (BvTraits::size), a on ties, except for the twig rule of box trees: when exactly one of the two
/// is a twig and splitting it gains nothing (twig_split_gains_nothing), the other is split. A
/// twig's children are leaves that cannot be split further, so splitting the twig first leaves the
/// other node whole against each leaf and walks the other's subtree once per leaf; when the leaves
/// are about as large as the twig, one walk against the twig, split only at the other's leaves,
/// tests fewer pairs (env/rob, SAH OBB trees, leaf size 1, 1,000 poses: boolean node tests per
/// query 36.0 -> 21.1, triangle tests 5.6 -> 0.9; one pose 447 -> 51 node tests). With the twig
/// rule for every twig, whatever its children, trees whose twigs hold two triangles far apart
/// (median split of env: a wall and a floor sliver) did up to 3x the node tests: the area test
/// keeps those on the size rule.
/// Sphere trees keep the size rule alone: the mesh queries' node test culls a leaf's triangles
/// against the other node's ball, which only a split twig reaches (env/rob, SAH sphere trees:
/// boolean 220 -> 2,792 node tests per query with the twig rule).
template <class BVA, class BVB>
bool split_first(const Bvh<BVA>& a, const BvhNode<BVA>& na, const Bvh<BVB>& b, const BvhNode<BVB>& nb) {
  using SA = typename BvTraits<BVA>::Scalar;
  using SB = typename BvTraits<BVB>::Scalar;
  const bool larger_a = BvTraits<BVA>::size(na.bv) >= BvTraits<BVB>::size(nb.bv);
  if constexpr (!std::is_same_v<BVA, Sphere<SA>> && !std::is_same_v<BVB, Sphere<SB>>) {
    // Where the twig is the smaller node the size rule already splits the other, so only the
    // larger node's children are read (they are read anyway to split it), the other's only when
    // the larger is a twig.
    if (larger_a) return !(is_twig(a, na) && !is_twig(b, nb) && twig_split_gains_nothing(a, na));
    return is_twig(b, nb) && !is_twig(a, na) && twig_split_gains_nothing(b, nb);
  }
  return larger_a;
}

/// One step of pair traversal for nodes i (tree a) and j (tree b) that passed the node test: hand
/// a leaf pair to the visitor, or push the children of the node split_first picks (the inner one
/// if the other is a leaf). Returns false when the visitor stopped the walk.
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
  } else if (lb || (!la && split_first(a, na, b, nb))) {
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
