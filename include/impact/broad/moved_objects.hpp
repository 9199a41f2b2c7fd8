// SPDX-License-Identifier: MIT
/// \file
/// MovedObjects: what the two tree broad phases (StaticDynamicBroadPhase, HierarchicalBroadPhase)
/// keep per object slot between updates (the object's leaf in its DynamicTree, and whether it
/// moved since the last update), and the refit of a moved dynamic object that both run at update.
#pragma once

#include "impact/broad/broad_phase.hpp"
#include "impact/broad/dynamic_pairs.hpp"
#include "impact/broad/dynamic_tree.hpp"
#include "impact/broad/static_candidates.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace impact {

/// Per object slot: its leaf in a DynamicTree (`DynamicTree::null` when it has none), and the list
/// of the slots that moved since the last drain, each listed once however often it moved.
template <class S>
class MovedObjects {
 public:
  /// Makes room for `slot` (new slots have no leaf and have not moved).
  void grow(std::int32_t slot) {
    const auto n = static_cast<std::size_t>(slot) + 1;
    if (n > leaf_.size()) {
      leaf_.resize(n, DynamicTree<S>::null);
      moved_flag_.resize(n, 0);
    }
  }

  std::int32_t leaf(std::int32_t slot) const { return leaf_[static_cast<std::size_t>(slot)]; }
  void set_leaf(std::int32_t slot, std::int32_t leaf) { leaf_[static_cast<std::size_t>(slot)] = leaf; }

  /// True when `slot` moved since the last drain.
  bool moved(std::int32_t slot) const { return moved_flag_[static_cast<std::size_t>(slot)] != 0; }
  /// Lists `slot` as moved (once until the next drain).
  void mark_moved(std::int32_t slot) {
    const auto s = static_cast<std::size_t>(slot);
    if (!moved_flag_[s]) {
      moved_flag_[s] = 1;
      moved_.push_back(slot);
    }
  }

  /// Calls visit(slot, leaf) for every slot listed since the last drain that still has a leaf, in
  /// the order they were listed, and empties the list. The pass reads scattered records, so it asks
  /// for the ones a few objects ahead: each object's leaf, flag and current box 8 ahead, and the
  /// leaf's box 4 ahead (`leaf_box(slot, leaf)` names it: the tree that holds the leaf).
  template <class LeafBox, class Visit>
  void drain(const ObjectTable<S>& t, LeafBox&& leaf_box, Visit&& visit) {
    const std::size_t n = moved_.size();
    for (std::size_t k = 0; k < n; ++k) {
      if (k + 8 < n) {
        const auto f = static_cast<std::size_t>(moved_[k + 8]);
        detail::prefetch(&leaf_[f]);
        detail::prefetch(&moved_flag_[f]);
        detail::prefetch(&t.box(moved_[k + 8]));
      }
      if (k + 4 < n) {
        const std::int32_t ahead = moved_[k + 4];
        const std::int32_t l = leaf_[static_cast<std::size_t>(ahead)];
        if (l != DynamicTree<S>::null) detail::prefetch(&leaf_box(ahead, l));
      }
      const std::int32_t slot = moved_[k];
      moved_flag_[static_cast<std::size_t>(slot)] = 0;
      const std::int32_t leaf = leaf_[static_cast<std::size_t>(slot)];
      if (leaf != DynamicTree<S>::null) visit(slot, leaf);  // else removed since it moved
    }
    moved_.clear();
  }

 private:
  std::vector<std::int32_t> leaf_;        // slot -> leaf in its tree
  std::vector<std::uint8_t> moved_flag_;  // slot -> listed in moved_
  std::vector<std::int32_t> moved_;
};

namespace detail {

/// Refits moved dynamic object `slot` (leaf `leaf` of `tree`) to its new tight box. Its cached
/// static candidates are re-tested at the next update; when the refit reinserted it (it left its
/// fat box), its static candidates are queried again and its dynamic pairs found again.
template <class S>
void refit_moved_dynamic(DynamicTree<S>& tree, StaticCandidates<S>& cache, DynamicPairs<S>& pairs,
                         const ObjectTable<S>& t, std::int32_t slot, std::int32_t leaf, BroadPhaseStats& st) {
  ++st.refits;
  const std::size_t pos = cache.pos_of(slot);
  cache.moved(pos);
  if (tree.update(leaf, t.box(slot))) {
    ++st.reinserts;
    cache.invalidate(pos);
    pairs.drop(pos);
    tree.mark_fresh(leaf);
  }
}

}  // namespace detail
}  // namespace impact
