// SPDX-License-Identifier: MIT
/// \file
/// StaticDynamicBroadPhase: the static/dynamic split. Static objects go in a flat `Bvh<Aabb>` built
/// once (top-down, bvh/build_top_down.hpp); dynamic objects (awake or sleeping) go in a
/// DynamicTree. Per call:
///   - each dynamic object that moved since the last call is refitted in the dynamic tree and
///     queried against the static tree once; the static objects it overlaps are cached, so an
///     object that did not move is never queried against the statics again;
///   - the cached static overlaps of every awake dynamic object are reported;
///   - dynamic–dynamic pairs come from the self pair traversal of the dynamic tree, which skips
///     sleeping–sleeping subtrees.
/// Static–static pairs are never looked at. O(moved * log static + dynamic pairs + output) per call
/// instead of O(static * dynamic + dynamic^2). Adding, removing or moving a static object marks the
/// static tree for a rebuild at the next call, which also re-queries every dynamic object: static
/// objects are meant to stay put.
#pragma once

#include "impact/broad/dynamic_tree.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/traverse.hpp"

namespace impact {

template <class S> class StaticDynamicBroadPhase {
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
    leaf_[s] = dyn_.insert(slot, t.box[s], t.active(slot));
    dyn_pos_[s] = static_cast<std::int32_t>(dynamics_.size());
    dynamics_.push_back(slot);
    cache_epoch_[s] = 0;
    cache_[s].clear();
  }
  void remove(std::int32_t slot, const ObjectTable<S>& t) {
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      static_dirty_ = true;  // caches naming it are dropped by the rebuild
      return;
    }
    dyn_.remove(leaf_[s]);
    leaf_[s] = DynamicTree<S>::null;
    const std::int32_t pos = dyn_pos_[s];
    const std::int32_t last = dynamics_.back();
    dynamics_[static_cast<std::size_t>(pos)] = last;
    dyn_pos_[static_cast<std::size_t>(last)] = pos;
    dynamics_.pop_back();
    dyn_pos_[s] = -1;
    cache_[s].clear();
    cache_epoch_[s] = 0;
  }
  void moved(std::int32_t slot, const ObjectTable<S>& t) {
    const auto s = static_cast<std::size_t>(slot);
    if (t.is_static(slot)) {
      static_dirty_ = true;
      return;
    }
    cache_epoch_[s] = 0;
    if (!moved_flag_[s]) {
      moved_flag_[s] = 1;
      moved_.push_back(slot);
    }
  }
  void activity_changed(std::int32_t slot, const ObjectTable<S>& t) {
    dyn_.set_active(leaf_[static_cast<std::size_t>(slot)], t.active(slot));
  }
  void filter_changed(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot)) ++epoch_;  // every cache may name it
    else cache_epoch_[static_cast<std::size_t>(slot)] = 0;
  }

  template <class Visit> bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) {
    flush(t, st);
    // Dynamic against static: cached, re-queried only when stale.
    for (const std::int32_t a : dynamics_) {
      if (!t.active(a)) continue;  // sleeping: its static pairs are inactive pairs
      const auto sa = static_cast<std::size_t>(a);
      std::vector<std::int32_t>& cache = cache_[sa];
      if (cache_epoch_[sa] != epoch_) {
        cache.clear();
        ++st.static_queries;
        const Aabb<S>& box = t.box[sa];
        traverse(
            static_tree_,
            [&](const Aabb<S>& bv) {
              ++st.bv_tests;
              return overlap(bv, box);
            },
            [&](std::int32_t k) {
              const std::int32_t b = static_slots_[static_cast<std::size_t>(k)];
              if (detail::test_pair(t, a, b, st)) cache.push_back(b);
              return true;
            });
        cache_epoch_[sa] = epoch_;
      }
      for (const std::int32_t b : cache) {
        ++st.pairs_found;
        if (!visit(a, b)) return false;
      }
    }
    // Dynamic against dynamic.
    return dyn_.self_pairs(
        [&](std::int32_t a, std::int32_t b) {
          if (!t.active(a) && !t.active(b)) return true;
          if (!detail::test_pair(t, a, b, st)) return true;
          ++st.pairs_found;
          return bool(visit(a, b));
        },
        st);
  }

  const DynamicTree<S>& dynamic_tree() const { return dyn_; }
  const Bvh<Aabb<S>>& static_tree() const { return static_tree_; }

 private:
  void grow(std::int32_t slot) {
    const auto n = static_cast<std::size_t>(slot) + 1;
    if (n > leaf_.size()) {
      leaf_.resize(n, DynamicTree<S>::null);
      dyn_pos_.resize(n, -1);
      moved_flag_.resize(n, 0);
      cache_.resize(n);
      cache_epoch_.resize(n, 0);
    }
  }

  void flush(const ObjectTable<S>& t, BroadPhaseStats& st) {
    for (const std::int32_t slot : moved_) {
      const auto s = static_cast<std::size_t>(slot);
      moved_flag_[s] = 0;
      const std::int32_t leaf = leaf_[s];
      if (leaf == DynamicTree<S>::null) continue;  // removed (or now static) since it moved
      ++st.refits;
      if (dyn_.update(leaf, t.box[s])) ++st.reinserts;
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
        centers.push_back(t.box[static_cast<std::size_t>(i)].center());
      }
    BuildConfig cfg;
    cfg.leaf_size = static_leaf_size_;
    static_tree_ = build_top_down<Aabb<S>>(
        centers,
        [&](const std::int32_t* ids, std::size_t n) {
          Aabb<S> b;
          for (std::size_t k = 0; k < n; ++k) b.extend(t.box[static_cast<std::size_t>(static_slots_[static_cast<std::size_t>(ids[k])])]);
          return b;
        },
        cfg);
    static_dirty_ = false;
    ++epoch_;
  }

  DynamicTree<S> dyn_;
  int static_leaf_size_;
  Bvh<Aabb<S>> static_tree_;
  std::vector<std::int32_t> static_slots_;  // static tree primitive id -> slot
  bool static_dirty_ = false;
  std::vector<std::int32_t> leaf_;       // slot -> dynamic tree leaf
  std::vector<std::int32_t> dyn_pos_;    // slot -> index in dynamics_
  std::vector<std::int32_t> dynamics_;   // dynamic slots
  std::vector<std::uint8_t> moved_flag_;
  std::vector<std::int32_t> moved_;
  std::vector<std::vector<std::int32_t>> cache_;  // dynamic slot -> overlapping static slots
  std::vector<std::uint32_t> cache_epoch_;
  std::uint32_t epoch_ = 1;
};

}  // namespace impact
