// SPDX-License-Identifier: MIT
/// \file
/// HierarchicalBroadPhase: the broad phase of two incremental AABB trees (DynamicTree), one over
/// the static objects and one over the dynamic ones, so that static objects too can be added,
/// removed and moved without a rebuild.
#pragma once

#include "impact/broad/broad_phase.hpp"
#include "impact/broad/dynamic_pairs.hpp"
#include "impact/broad/dynamic_tree.hpp"
#include "impact/broad/moved_objects.hpp"
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
    objects_.grow(slot);
    const bool st = t.is_static(slot);
    objects_.set_leaf(slot, (st ? static_ : dynamic_).insert(slot, t.box(slot), t.active(slot), st));
    if (st) {
      near_static_changed(t.box(slot));
      return;
    }
    cache_.add(slot, t.active(slot));
    pairs_.add();
    dynamic_.mark_fresh(objects_.leaf(slot));
  }
  void remove(std::int32_t slot, const ObjectTable<S>& t) {
    const std::int32_t leaf = objects_.leaf(slot);
    objects_.set_leaf(slot, DynamicTree<S>::null);
    if (t.is_static(slot)) {
      near_static_changed(static_.box(leaf));
      static_.remove(leaf);
      return;
    }
    dynamic_.remove(leaf);
    pairs_.remove(pos_of(slot));
    cache_.remove(slot);
  }
  void moved(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot)) {
      // The leaf still holds the box of the last update: every box the object had since is
      // queried when it is set, so the dynamic objects near any of them are invalidated.
      if (!objects_.moved(slot)) near_static_changed(static_.box(objects_.leaf(slot)));
      near_static_changed(t.box(slot));
    }
    objects_.mark_moved(slot);
  }
  void activity_changed(std::int32_t slot, const ObjectTable<S>& t) {
    cache_.set_active(pos_of(slot), t.active(slot));
    dynamic_.set_active(objects_.leaf(slot), t.active(slot));
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
          dynamic_.box(objects_.leaf(a)),
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

  void flush(const ObjectTable<S>& t, BroadPhaseStats& st) {
    objects_.drain(
        t,
        [&](std::int32_t slot, std::int32_t leaf) -> const Aabb<S>& {
          return t.is_static(slot) ? static_.box(leaf) : dynamic_.box(leaf);
        },
        [&](std::int32_t slot, std::int32_t leaf) {
          if (!t.alive(slot)) return;
          if (t.is_static(slot)) {
            ++st.refits;
            if (static_.update(leaf, t.box(slot))) ++st.reinserts;
            return;
          }
          detail::refit_moved_dynamic(dynamic_, cache_, pairs_, t, slot, leaf, st);
        });
    if (static_.maybe_rebuild()) ++st.rebuilds;
    if (dynamic_.maybe_rebuild()) ++st.rebuilds;
  }

  DynamicTree<S> static_, dynamic_;
  MovedObjects<S> objects_;  // slot -> leaf in its tree, and the objects moved since the last update
  StaticCandidates<S> cache_;  // the dynamic objects, each with its static candidates and hits
  DynamicPairs<S> pairs_;      // per dynamic object (by its position in cache_), its dynamic pairs of fat boxes
};

}  // namespace impact
