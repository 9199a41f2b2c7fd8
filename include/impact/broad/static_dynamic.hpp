// SPDX-License-Identifier: MIT
/// \file
/// StaticDynamicBroadPhase: the static/dynamic split. Static objects go in a flat `Bvh<Aabb>` built
/// once (top-down, bvh/build_top_down.hpp); dynamic objects (awake or sleeping) go in a
/// DynamicTree with fattened leaves. Per call:
///   - each dynamic object that moved since the last call is refitted in the dynamic tree; only
///     when it left its fat box (and so was reinserted) is it queried against the static tree,
///     with the fat box, and the static objects found are kept as its candidates; otherwise its
///     candidates are only re-tested against its new tight box. An object that did not move is
///     neither refitted, nor queried, nor re-tested: its last static pairs are reported as they are;
///   - sleeping objects' static pairs are not reported (nor recomputed until they wake);
///   - dynamic–dynamic pairs come from a DynamicPairs cache of the pairs of overlapping fat boxes:
///     only the objects that were reinserted find theirs again, by a query of the dynamic tree
///     with the new fat box; every call re-tests the cached pairs of the active objects against
///     their tight boxes.
/// Static–static pairs are never looked at. O(reinserted * (log static + log dynamic) + moved *
/// candidates + cached dynamic pairs + output) per call instead of O(static * dynamic + dynamic^2).
/// Adding, removing or moving a static object marks the static tree for a rebuild at the next call, which also
/// re-queries every dynamic object: static objects are meant to stay put.
///
/// Everything cached (refits, static candidates, tight-box hits, dynamic pairs) is brought up to date by update(),
/// which the scene runs once after edits; find_pairs then only reads, so any number of threads may
/// run it (and split_pairs / find_pairs_part) at once between edits. Edits and update() must not
/// overlap any other call.
#pragma once

#include "impact/broad/dynamic_pairs.hpp"
#include "impact/broad/dynamic_tree.hpp"
#include "impact/broad/moved_objects.hpp"
#include "impact/broad/static_candidates.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/traverse.hpp"

#include <algorithm>

namespace impact {

template <class S>
class StaticDynamicBroadPhase {
 public:
  /// `tree` configures the dynamic tree; `static_leaf_size` the static tree's leaves.
  explicit StaticDynamicBroadPhase(const DynamicTreeOptions& tree = {}, int static_leaf_size = 2)
      : dyn_(tree), static_leaf_size_(static_leaf_size) {}

  void insert(std::int32_t slot, const ObjectTable<S>& t) {
    objects_.grow(slot);
    if (t.is_static(slot)) {
      static_dirty_ = true;
      return;
    }
    objects_.set_leaf(slot, dyn_.insert(slot, t.box(slot), t.active(slot)));
    cache_.add(slot, t.active(slot));
    pairs_.add();
    dyn_.mark_fresh(objects_.leaf(slot));
  }
  void remove(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot)) {
      static_dirty_ = true;  // candidates naming it are dropped by the rebuild
      return;
    }
    dyn_.remove(objects_.leaf(slot));
    objects_.set_leaf(slot, DynamicTree<S>::null);
    pairs_.remove(pos_of(slot));
    cache_.remove(slot);
  }
  void moved(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot)) {
      static_dirty_ = true;
      return;
    }
    objects_.mark_moved(slot);
  }
  void activity_changed(std::int32_t slot, const ObjectTable<S>& t) {
    cache_.set_active(pos_of(slot), t.active(slot));
    dyn_.set_active(objects_.leaf(slot), t.active(slot));
  }
  void filter_changed(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot))
      cache_.invalidate_all();  // every candidate list may name it
    else
      cache_.invalidate(pos_of(slot));
  }

  /// Applies the edits since the last update: refits and reinsertions of moved objects, rebuilds;
  /// then the static-tree queries of the objects whose fat box changed (on `threads` threads,
  /// each object writing only its own candidates) and the tight-box re-tests of those that moved.
  void update(const ObjectTable<S>& t, BroadPhaseStats& st, int threads) {
    flush(t, st);
    pairs_.update(dyn_, cache_, st, threads);
    // Dynamic against static: the static tree is large, so the queries' Morton order is what
    // keeps its nodes in cache.
    const Aabb<S>* bounds = static_tree_.empty() ? nullptr : &static_tree_.root().bv;
    cache_.update(t, bounds, threads, st,
                  [&](std::int32_t a, std::vector<std::int32_t>& cand, BroadPhaseStats& cs) { query_static(t, a, cand, cs); });
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

  const DynamicTree<S>& dynamic_tree() const { return dyn_; }
  const Bvh<Aabb<S>>& static_tree() const { return static_tree_; }

 private:
  /// Static-tree query of dynamic object a with its fat box: its accepted candidates.
  void query_static(const ObjectTable<S>& t, std::int32_t a, std::vector<std::int32_t>& cand, BroadPhaseStats& st) const {
    const Aabb<S>& fat = dyn_.box(objects_.leaf(a));
    traverse(
        static_tree_,
        [&](const Aabb<S>& bv) {
          ++st.bv_tests;
          return overlap(bv, fat);
        },
        [&](std::int32_t k) {
          const std::int32_t b = static_slots_[static_cast<std::size_t>(k)];
          ++st.bv_tests;
          if (!overlap(t.box(b), fat)) return true;
          if (t.accepts(a, b))
            cand.push_back(b);
          else
            ++st.pairs_filtered;
          return true;
        });
  }

  /// The position of dynamic object `slot` in cache_.
  std::size_t pos_of(std::int32_t slot) const { return cache_.pos_of(slot); }

  void flush(const ObjectTable<S>& t, BroadPhaseStats& st) {
    objects_.drain(
        t, [&](std::int32_t, std::int32_t leaf) -> const Aabb<S>& { return dyn_.box(leaf); },
        [&](std::int32_t slot, std::int32_t leaf) { detail::refit_moved_dynamic(dyn_, cache_, pairs_, t, slot, leaf, st); });
    if (dyn_.maybe_rebuild()) ++st.rebuilds;
    if (static_dirty_) {
      rebuild_static(t);
      ++st.rebuilds;
    }
  }

  void rebuild_static(const ObjectTable<S>& t) {
    static_slots_.clear();
    std::vector<Vec3<S>> centers;
    for (std::int32_t i = 0; i < t.size(); ++i)
      if (t.alive(i) && t.is_static(i)) {
        static_slots_.push_back(i);
        centers.push_back(t.box(i).center());
      }
    BuildConfig cfg;
    cfg.leaf_size = static_leaf_size_;
    static_tree_ = build_top_down<Aabb<S>>(
        centers,
        [&](const std::int32_t* ids, std::size_t n) {
          Aabb<S> b;
          for (std::size_t k = 0; k < n; ++k) b.extend(t.box(static_slots_[static_cast<std::size_t>(ids[k])]));
          return b;
        },
        cfg);
    static_dirty_ = false;
    cache_.invalidate_all();
  }

  DynamicTree<S> dyn_;
  int static_leaf_size_;
  Bvh<Aabb<S>> static_tree_;
  std::vector<std::int32_t> static_slots_;  // static tree primitive id -> slot
  bool static_dirty_ = false;
  MovedObjects<S> objects_;  // slot -> dynamic tree leaf, and the dynamic objects moved since the last update
  StaticCandidates<S> cache_;  // the dynamic objects, each with its static candidates and hits
  DynamicPairs<S> pairs_;      // per dynamic object (by its position in cache_), its dynamic pairs of fat boxes
};

}  // namespace impact
