// SPDX-License-Identifier: MIT
/// \file
/// Single-tree traversal, driven by callables: a node predicate decides whether to enter a node
/// (for a ray, a point, a sphere...), a leaf visitor receives each primitive and says whether to go
/// on. Narrow-phase code lives in the visitor, never here.
#pragma once

#include "impact/bvh/bvh.hpp"
#include "impact/bvh/traversal_stack.hpp"

#include <optional>

namespace impact {

/// Depth-first walk. `enter(const BV&) -> bool`; `visit(std::int32_t primitive_id) -> bool` (false
/// stops the walk). Returns false when a visitor stopped it.
template <class BV, class Enter, class Visit> bool traverse(const Bvh<BV>& tree, Enter&& enter, Visit&& visit) {
  if (tree.empty()) return true;
  detail::TraversalStack<std::int32_t> stack;
  stack.push(0);
  while (!stack.empty()) {
    const std::int32_t i = stack.pop();
    const auto& node = tree.nodes[static_cast<std::size_t>(i)];
    if (!enter(node.bv)) continue;
    if (node.is_leaf()) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k)
        if (!visit(tree.primitives[static_cast<std::size_t>(k)])) return false;
    } else {
      stack.push(node.right());
      stack.push(node.left());
    }
  }
  return true;
}

/// Nearest-first walk for first-hit queries (ray casts, closest point). `key(const BV&) ->
/// std::optional<S>` gives a lower bound of what can be found inside a node (entry distance of a
/// ray, distance to a point), or nullopt to skip it; nodes whose key is not below the current
/// `bound()` are skipped. `visit(primitive_id)` tests a primitive and may lower the bound it shares
/// with `bound`; it returns false to stop. Children are entered nearer first. `start` (the root by
/// default) restricts the walk to that node's subtree: the caller guarantees nothing outside it
/// can be found.
template <class BV, class Key, class Bound, class Visit>
void traverse_nearest(const Bvh<BV>& tree, Key&& key, Bound&& bound, Visit&& visit, std::int32_t start = 0) {
  using S = typename BvTraits<BV>::Scalar;
  if (tree.empty()) return;
  const std::optional<S> k0 = key(tree.nodes[static_cast<std::size_t>(start)].bv);
  if (!k0) return;
  detail::TraversalStack<std::pair<S, std::int32_t>, 128> stack;  // no allocation per query
  stack.push({*k0, start});
  while (!stack.empty()) {
    const auto [d, i] = stack.pop();
    if (!(d <= bound())) continue;
    const auto& node = tree.nodes[static_cast<std::size_t>(i)];
    if (node.is_leaf()) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k)
        if (!visit(tree.primitives[static_cast<std::size_t>(k)])) return;
      continue;
    }
    const auto kl = key(tree.nodes[node.left()].bv);
    const auto kr = key(tree.nodes[node.right()].bv);
    if (kl && kr) {
      if (*kl <= *kr) {
        stack.push({*kr, node.right()});
        stack.push({*kl, node.left()});
      } else {
        stack.push({*kl, node.left()});
        stack.push({*kr, node.right()});
      }
    } else if (kl) {
      stack.push({*kl, node.left()});
    } else if (kr) {
      stack.push({*kr, node.right()});
    }
  }
}

}  // namespace impact
