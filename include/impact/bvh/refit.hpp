// SPDX-License-Identifier: MIT
/// \file
/// Refit for deforming primitives: keep the tree's topology, recompute the BVs bottom-up after the
/// primitives moved. Leaves are refitted by the caller's `fit` around their primitives; inner
/// nodes either by merging the children's BVs (RefitMode::Merge, O(n), looser) or by fitting around
/// all their primitives again (RefitMode::Fit, O(n log n), as tight as a fresh build).
#pragma once

#include "impact/bvh/bvh.hpp"

namespace impact {

enum class RefitMode { Merge, Fit };

/// Children always have larger indices than their parent (builders append them), so a reverse
/// sweep over the node array visits children before parents.
template <class BV, class Fit> void refit(Bvh<BV>& tree, Fit&& fit, RefitMode mode = RefitMode::Merge) {
  for (std::size_t k = tree.nodes.size(); k-- > 0;) {
    auto& node = tree.nodes[k];
    if (node.is_leaf()) {
      node.bv = fit(tree.primitives.data() + node.first, static_cast<std::size_t>(node.count));
    } else if (mode == RefitMode::Merge) {
      node.bv = BvTraits<BV>::merge(tree.nodes[node.left()].bv, tree.nodes[node.right()].bv);
    }
  }
  if (mode == RefitMode::Fit) {
    // Inner node ranges: gather the primitive range of each inner node from its leaves.
    std::vector<std::pair<std::int32_t, std::int32_t>> range(tree.nodes.size());
    for (std::size_t k = tree.nodes.size(); k-- > 0;) {
      const auto& node = tree.nodes[k];
      if (node.is_leaf()) {
        range[k] = {node.first, node.first + node.count};
      } else {
        range[k] = {std::min(range[node.left()].first, range[node.right()].first),
                    std::max(range[node.left()].second, range[node.right()].second)};
        tree.nodes[k].bv = fit(tree.primitives.data() + range[k].first, static_cast<std::size_t>(range[k].second - range[k].first));
      }
    }
  }
}

}  // namespace impact
