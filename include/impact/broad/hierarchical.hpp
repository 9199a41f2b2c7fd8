// SPDX-License-Identifier: MIT
/// \file
/// HierarchicalBroadPhase: the broad phase of two incremental AABB trees (DynamicTree), one over
/// the static objects and one over the dynamic ones, so that static objects too can be added,
/// removed and moved without a rebuild.
#pragma once

#include "impact/broad/broad_phase.hpp"
#include "impact/broad/dynamic_pairs.hpp"
#include "impact/broad/dynamic_tree.hpp"
#include "impact/broad/static_candidates.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace impact {

/// The hierarchical broad phase: two DynamicTrees, one over the static objects (tight leaves) and
/// one over the dynamic ones (fattened leaves, sleeping ones flagged inactive). At update() (the
/// scene's first query after edits), moved objects are refitted (reinserted only when they leave
/// their fat box; unmoved ones are not touched). Dynamic–dynamic pairs come from a DynamicPairs
/// cache of the pairs of overlapping fat boxes (only reinserted objects find theirs again, by a
/// query of the dynamic tree with the new fat box); dynamic–static pairs from a StaticCandidates
/// cache, as Bullet keeps its pairs: a dynamic object queries the static tree with its fat box only
/// when that box changed (or a static object near it was added, removed, moved or refiltered), and
/// otherwise re-tests its candidates against its tight box when it moved. Unlike the static/dynamic split, static objects can be added, removed or moved
/// incrementally without a rebuild: such an edit queries the dynamic tree with the static object's
/// boxes (before and after) and invalidates the candidates of the dynamic objects it finds.
///
/// Thread safety: find_pairs, split_pairs and find_pairs_part are const and read only: any number
/// of threads may run them at once between updates. Edits and update() must not overlap any call.
template <class S>
class HierarchicalBroadPhase {
 public:
  explicit HierarchicalBroadPhase(const DynamicTreeOptions& opt = {}) : static_(opt), dynamic_(opt) {}

  void insert(std::int32_t slot, const ObjectTable<S>& t) {
    grow(slot);
    const auto s = static_cast<std::size_t>(slot);
    const bool st = t.is_static(slot);
    leaf_[s] = (st ? static_ : dynamic_).insert(slot, t.box(s), t.active(slot), st);
    if (st) {
      near_static_changed(t.box(s));
      return;
    }
    cache_.add(slot, t.active(slot));
    pairs_.add();
    dynamic_.mark_fresh(leaf_[s]);
  }
  void remove(std::int32_t slot, const ObjectTable<S>& t) {
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      near_static_changed(static_.box(leaf_[s]));
      static_.remove(leaf_[s]);
      leaf_[s] = DynamicTree<S>::null;
      return;
    }
    dynamic_.remove(leaf_[s]);
    leaf_[s] = DynamicTree<S>::null;
    pairs_.remove(pos_of(slot));
    cache_.remove(slot);
  }
  void moved(std::int32_t slot, const ObjectTable<S>& t) {
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      // The leaf still holds the box of the last update: every box the object had since is
      // queried when it is set, so the dynamic objects near any of them are invalidated.
      if (!moved_flag_[s]) near_static_changed(static_.box(leaf_[s]));
      near_static_changed(t.box(slot));
    }
    if (!moved_flag_[s]) {
      moved_flag_[s] = 1;
      moved_.push_back(slot);
    }
  }
  void activity_changed(std::int32_t slot, const ObjectTable<S>& t) {
    cache_.set_active(pos_of(slot), t.active(slot));
    dynamic_.set_active(leaf_[static_cast<std::size_t>(slot)], t.active(slot));
  }
  void filter_changed(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot))
      near_static_changed(t.box(slot));
    else
      cache_.invalidate(pos_of(slot));
  }

  /// Applies the moves since the last update: refits (reinsertions for objects that left their fat
  /// box) and rebuilds of degraded trees, serial; then the static-tree queries of the dynamic
  /// objects whose candidates are out of date and the tight-box re-tests of those that moved, on
  /// `threads` threads.
  void update(const ObjectTable<S>& t, BroadPhaseStats& st, int threads) {
    flush(t, st);
    pairs_.update(dynamic_, cache_, st, threads);
    const std::int32_t root = static_.root();
    const Aabb<S>* bounds = root == DynamicTree<S>::null ? nullptr : &static_.box(root);
    cache_.update(t, bounds, threads, st, [&](std::int32_t a, std::vector<std::int32_t>& cand, BroadPhaseStats& cs) {
      static_.query(
          dynamic_.box(leaf_[static_cast<std::size_t>(a)]),
          [&](std::int32_t b) {
            if (t.accepts(a, b))
              cand.push_back(b);
            else
              ++cs.pairs_filtered;
            return true;
          },
          cs);
    });
  }

  template <class Visit>
  bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) const {
    return find_split_pairs(cache_, pairs_, t, visit, st);
  }
  /// Parts of find_pairs (broad_phase.hpp): ranges of the dynamic objects' static pairs, then
  /// ranges of their dynamic pairs.
  std::vector<PairTask> split_pairs(const ObjectTable<S>&, std::size_t want) const {
    return split_pair_tasks(cache_.size(), want);
  }
  template <class Visit>
  bool find_pairs_part(const ObjectTable<S>& t, const PairTask& task, Visit&& visit, BroadPhaseStats& st) const {
    return find_split_pairs_part(cache_, pairs_, t, task, visit, st);
  }

  const DynamicTree<S>& static_tree() const { return static_; }
  const DynamicTree<S>& dynamic_tree() const { return dynamic_; }

 private:
  /// A static object with this box was added, removed, moved or refiltered: the dynamic objects
  /// whose fat boxes overlap it find their candidates again (the others' cannot name it, before or
  /// after). Counts nothing: an edit has no stats.
  void near_static_changed(const Aabb<S>& box) {
    BroadPhaseStats ignored;
    dynamic_.query(
        box,
        [&](std::int32_t a) {
          cache_.invalidate(pos_of(a));
          return true;
        },
        ignored);
  }

  /// The position of dynamic object `slot` in cache_.
  std::size_t pos_of(std::int32_t slot) const { return cache_.pos_of(slot); }

  void grow(std::int32_t slot) {
    const auto n = static_cast<std::size_t>(slot) + 1;
    if (n > leaf_.size()) {
      leaf_.resize(n, DynamicTree<S>::null);
      moved_flag_.resize(n, 0);
    }
  }
  void flush(const ObjectTable<S>& t, BroadPhaseStats& st) {
    const std::size_t n = moved_.size();
    for (std::size_t k = 0; k < n; ++k) {
      if (k + 8 < n) {  // this loop's scattered reads for the object 8 ahead, and its leaf for the one 4 ahead
        const auto f = static_cast<std::size_t>(moved_[k + 8]);
        detail::prefetch(&leaf_[f]);
        detail::prefetch(&moved_flag_[f]);
        detail::prefetch(&t.box(moved_[k + 8]));
      }
      if (k + 4 < n) {
        const std::int32_t l = leaf_[static_cast<std::size_t>(moved_[k + 4])];
        if (l != DynamicTree<S>::null) detail::prefetch(t.is_static(moved_[k + 4]) ? &static_.box(l) : &dynamic_.box(l));
      }
      const std::int32_t slot = moved_[k];
      moved_flag_[static_cast<std::size_t>(slot)] = 0;
      const std::int32_t leaf = leaf_[static_cast<std::size_t>(slot)];
      if (leaf == DynamicTree<S>::null || !t.alive(slot)) continue;
      ++st.refits;
      if (t.is_static(slot)) {
        if (static_.update(leaf, t.box(slot))) ++st.reinserts;
        continue;
      }
      cache_.moved(pos_of(slot));
      if (dynamic_.update(leaf, t.box(slot))) {
        ++st.reinserts;
        cache_.invalidate(pos_of(slot));  // the fat box changed: query the static tree again
        pairs_.drop(pos_of(slot));        // and find its dynamic pairs again
        dynamic_.mark_fresh(leaf);
      }
    }
    moved_.clear();
    if (static_.maybe_rebuild()) ++st.rebuilds;
    if (dynamic_.maybe_rebuild()) ++st.rebuilds;
  }

  DynamicTree<S> static_, dynamic_;
  std::vector<std::int32_t> leaf_;      // slot -> leaf in its tree
  std::vector<std::uint8_t> moved_flag_;
  std::vector<std::int32_t> moved_;
  StaticCandidates<S> cache_;  // the dynamic objects, each with its static candidates and hits
  DynamicPairs<S> pairs_;      // per dynamic object (by its position in cache_), its dynamic pairs of fat boxes
};

}  // namespace impact
