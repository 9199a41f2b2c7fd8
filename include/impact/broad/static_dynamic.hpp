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
///   - dynamic–dynamic pairs come from the self pair traversal of the dynamic tree, which skips
///     sleeping–sleeping subtrees.
/// Static–static pairs are never looked at. O(reinserted * log static + moved * candidates +
/// dynamic pairs + output) per call instead of O(static * dynamic + dynamic^2). Adding, removing or
/// moving a static object marks the static tree for a rebuild at the next call, which also
/// re-queries every dynamic object: static objects are meant to stay put.
///
/// Everything cached (refits, static candidates, tight-box hits) is brought up to date by update(),
/// which the scene runs once after edits; find_pairs then only reads, so any number of threads may
/// run it (and split_pairs / find_pairs_part) at once between edits. Edits and update() must not
/// overlap any other call.
#pragma once

#include "impact/broad/dynamic_tree.hpp"
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
    grow(slot);
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      static_dirty_ = true;
      return;
    }
    leaf_[s] = dyn_.insert(slot, t.box(s), t.active(slot));
    dyn_pos_[s] = static_cast<std::int32_t>(dynamics_.size());
    dynamics_.push_back(slot);
    cache_.push_back(t.active(slot));
  }
  void remove(std::int32_t slot, const ObjectTable<S>& t) {
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      static_dirty_ = true;  // candidates naming it are dropped by the rebuild
      return;
    }
    dyn_.remove(leaf_[s]);
    leaf_[s] = DynamicTree<S>::null;
    const std::int32_t pos = dyn_pos_[s];
    cache_.swap_remove(static_cast<std::size_t>(pos));
    const std::int32_t last = dynamics_.back();
    dynamics_[static_cast<std::size_t>(pos)] = last;
    dyn_pos_[static_cast<std::size_t>(last)] = pos;
    dynamics_.pop_back();
    dyn_pos_[s] = -1;
  }
  void moved(std::int32_t slot, const ObjectTable<S>& t) {
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      static_dirty_ = true;
      return;
    }
    if (!moved_flag_[s]) {
      moved_flag_[s] = 1;
      moved_.push_back(slot);
    }
  }
  void activity_changed(std::int32_t slot, const ObjectTable<S>& t) {
    cache_.set_active(pos_of(slot), t.active(slot));
    dyn_.set_active(leaf_[static_cast<std::size_t>(slot)], t.active(slot));
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
    // Dynamic against static: the static tree is large, so the queries' Morton order is what
    // keeps its nodes in cache.
    const Aabb<S>* bounds = static_tree_.empty() ? nullptr : &static_tree_.root().bv;
    cache_.update(t, dynamics_, bounds, threads, st,
                  [&](std::int32_t a, std::vector<std::int32_t>& cand, BroadPhaseStats& cs) { query_static(t, a, cand, cs); });
  }

  template <class Visit>
  bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) const {
    if (!cache_.pairs(dynamics_, 0, dynamics_.size(), visit, st)) return false;
    return dyn_.self_pairs(pair_filter(t, visit, st), st);
  }

  /// Parts of find_pairs: ranges of the dynamic objects' static pairs, then seeds of the dynamic
  /// tree's self traversal.
  std::vector<PairTask> split_pairs(const ObjectTable<S>&, std::size_t want) const {
    std::vector<PairTask> tasks;
    const std::size_t n = dynamics_.size();
    const std::size_t chunk = std::max<std::size_t>(64, n / std::max<std::size_t>(want, 1));
    for (std::size_t b = 0; b < n; b += chunk) tasks.push_back({0, -1, -1, 0, b, std::min(n, b + chunk)});
    for (const auto& seed : dyn_.split_self_pairs(want)) tasks.push_back({1, seed.i, seed.j, seed.pre_bv_tests, 0, 0});
    return tasks;
  }
  template <class Visit>
  bool find_pairs_part(const ObjectTable<S>& t, const PairTask& task, Visit&& visit, BroadPhaseStats& st) const {
    if (task.kind == 0) return cache_.pairs(dynamics_, task.begin, task.end, visit, st);
    return dyn_.self_pairs_from({task.i, task.j, task.pre_bv_tests}, pair_filter(t, visit, st), st);
  }

  const DynamicTree<S>& dynamic_tree() const { return dyn_; }
  const Bvh<Aabb<S>>& static_tree() const { return static_tree_; }

 private:
  /// The dynamic tree's leaf-pair visitor: rules 1 to 3 of the pair rule, then visit.
  template <class Visit>
  static auto pair_filter(const ObjectTable<S>& t, Visit& visit, BroadPhaseStats& st) {
    return [&t, &visit, &st](std::int32_t a, std::int32_t b) {
      if (!t.active(a) && !t.active(b)) return true;
      if (!detail::test_pair(t, a, b, st)) return true;
      ++st.pairs_found;
      return bool(visit(a, b));
    };
  }

  /// Static-tree query of dynamic object a with its fat box: its accepted candidates.
  void query_static(const ObjectTable<S>& t, std::int32_t a, std::vector<std::int32_t>& cand, BroadPhaseStats& st) const {
    const Aabb<S>& fat = dyn_.box(leaf_[static_cast<std::size_t>(a)]);
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

  /// The position of dynamic object `slot` in dynamics_ (and in cache_).
  std::size_t pos_of(std::int32_t slot) const { return static_cast<std::size_t>(dyn_pos_[static_cast<std::size_t>(slot)]); }

  void grow(std::int32_t slot) {
    const auto n = static_cast<std::size_t>(slot) + 1;
    if (n > leaf_.size()) {
      leaf_.resize(n, DynamicTree<S>::null);
      dyn_pos_.resize(n, -1);
      moved_flag_.resize(n, 0);
    }
  }

  void flush(const ObjectTable<S>& t, BroadPhaseStats& st) {
    for (const std::int32_t slot : moved_) {
      const auto s = static_cast<std::size_t>(slot);
      moved_flag_[s] = 0;
      const std::int32_t leaf = leaf_[s];
      if (leaf == DynamicTree<S>::null) continue;  // removed (or now static) since it moved
      ++st.refits;
      cache_.moved(pos_of(slot));
      if (dyn_.update(leaf, t.box(s))) {
        ++st.reinserts;
        cache_.invalidate(pos_of(slot));  // the fat box changed: query the static tree again
      }
    }
    moved_.clear();
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
  std::vector<std::int32_t> leaf_;      // slot -> dynamic tree leaf
  std::vector<std::int32_t> dyn_pos_;   // slot -> index in dynamics_
  std::vector<std::int32_t> dynamics_;  // dynamic slots
  std::vector<std::uint8_t> moved_flag_;
  std::vector<std::int32_t> moved_;
  StaticCandidates<S> cache_;  // position in dynamics_ -> static candidates and hits
};

}  // namespace impact
