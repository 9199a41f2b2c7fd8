// SPDX-License-Identifier: MIT
/// \file
/// The order of a tree's nodes in memory: treelets of about one memory page. The builders append
/// each node's two children as they cut, depth first, so a path from the root that turns right
/// jumps over the whole left subtree, and near the root every level of a walk lands on another
/// page. Queries on large meshes that run between other work (the mesh–mesh queries of the
/// collide bench: each boolean query after another pose's all-pairs query) pay for those pages:
/// address-translation and cache misses on nodes, not the tests. lay_out_in_treelets renumbers the
/// nodes so that each node's descendants down to a few levels below it lie together, in one
/// block of at most a page (breadth first within the block), and the blocks below follow one
/// another depth first. The tree is the same: every node keeps its BV, its children (still
/// adjacent, left then right, after their parent) and its primitives; only the indices change.
/// On Linux the new array is also offered 2 MiB pages (detail::advise_huge_pages), for the same
/// address-translation misses on trees of many megabytes.
#pragma once

#include "impact/bvh/bvh.hpp"

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>
#if defined(__linux__) && !defined(IMPACT_NO_HUGE_PAGES)
#include <sys/mman.h>
#endif

namespace impact {

namespace detail {
/// Asks the kernel (Linux, transparent huge pages in their default "madvise" mode) to back the
/// 2 MiB-aligned extents inside [p, p + bytes) with 2 MiB pages when they are first written: a
/// walk down a large tree then needs one address translation per 2 MiB instead of one per 4 KiB
/// page. Only whole extents inside the range are advised, so no memory is added. A hint: nothing
/// happens elsewhere, when the kernel declines, or with IMPACT_NO_HUGE_PAGES defined.
inline void advise_huge_pages(void* p, std::size_t bytes) {
#if defined(__linux__) && !defined(IMPACT_NO_HUGE_PAGES) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t huge = std::uintptr_t(1) << 21;
  const auto p0 = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t a0 = (p0 + huge - 1) & ~(huge - 1), a1 = (p0 + bytes) & ~(huge - 1);
  if (a1 > a0) (void)madvise(reinterpret_cast<void*>(a0), a1 - a0, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}
}  // namespace detail

/// Levels of children per treelet for nodes of `node_bytes`: the most whose 2 + 4 + ... nodes fit in
/// `page_bytes` (oriented boxes in double, 136 bytes a node: 4 levels, 30 nodes, 4,080 bytes;
/// axis-aligned boxes, 56 bytes: 5; spheres, 40 bytes: 5), at least 1.
constexpr int treelet_levels(std::size_t node_bytes, std::size_t page_bytes = 4096) {
  int levels = 1;
  while (levels < 30 && ((std::size_t(1) << (levels + 2)) - 2) * node_bytes <= page_bytes) ++levels;
  return levels;
}

/// Renumbers the nodes of `tree` in treelets of `levels` levels (treelet_levels of the node size by
/// default): the root stays at 0; from a treelet's root, the pairs of children of its descendants
/// down to `levels` levels are placed together, level by level; each node at the treelet's bottom
/// that has children roots the next treelet, the leftmost first. Children stay adjacent and after
/// their parent (refit's reverse sweep and every walk rely on it), leaves keep their primitive
/// ranges, and every walk visits the same node pairs in the same order. O(n), one copy of the nodes.
template <class BV> void lay_out_in_treelets(Bvh<BV>& tree, int levels = treelet_levels(sizeof(BvhNode<BV>))) {
  const std::size_t n = tree.nodes.size();
  if (n < 3 || levels < 1) return;
  std::vector<BvhNode<BV>> out;
  out.reserve(n);
  detail::advise_huge_pages(out.data(), n * sizeof(BvhNode<BV>));  // before the first write
  out.push_back(tree.nodes[0]);
  std::vector<std::int32_t> placed(n, -1);  // old index -> new index
  placed[0] = 0;
  std::vector<std::int32_t> roots{0}, level, next;
  while (!roots.empty()) {
    const std::int32_t r = roots.back();
    roots.pop_back();
    level.assign(1, r);
    for (int d = 0; d < levels && !level.empty(); ++d) {
      next.clear();
      for (const std::int32_t k : level) {
        const BvhNode<BV>& node = tree.nodes[static_cast<std::size_t>(k)];
        if (node.is_leaf()) continue;
        const auto p = static_cast<std::int32_t>(out.size());
        out[static_cast<std::size_t>(placed[static_cast<std::size_t>(k)])].first = p;
        out.push_back(tree.nodes[static_cast<std::size_t>(node.left())]);
        out.push_back(tree.nodes[static_cast<std::size_t>(node.right())]);
        placed[static_cast<std::size_t>(node.left())] = p;
        placed[static_cast<std::size_t>(node.right())] = p + 1;
        next.push_back(node.left());
        next.push_back(node.right());
      }
      std::swap(level, next);
    }
    // the bottom's inner nodes root the next treelets, the leftmost on top of the stack
    for (auto it = level.rbegin(); it != level.rend(); ++it)
      if (!tree.nodes[static_cast<std::size_t>(*it)].is_leaf()) roots.push_back(*it);
  }
  tree.nodes.swap(out);
}

}  // namespace impact
