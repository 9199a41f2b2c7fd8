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
#pragma once

#include "impact/broad/dynamic_tree.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/traverse.hpp"

namespace impact {

namespace detail {
/// Spreads the low 10 bits of v so that there are two zero bits between consecutive ones.
inline std::uint32_t spread_bits3(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}
/// 30-bit Morton code of p quantised to 10 bits per axis by (p - lo) * scale (clamped).
template <class S>
inline std::uint32_t morton_code(const Vec3<S>& p, const Vec3<S>& lo, const Vec3<S>& scale) {
  std::uint32_t c[3];
  for (int k = 0; k < 3; ++k) {
    const S q = (p[k] - lo[k]) * scale[k];
    c[k] = q > S(0) ? std::uint32_t(std::min(q, S(1023))) : 0u;
  }
  return spread_bits3(c[0]) | (spread_bits3(c[1]) << 1) | (spread_bits3(c[2]) << 2);
}
}  // namespace detail

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
    cand_epoch_[s] = 0;
    cand_[s].clear();
    hits_[s].clear();
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
    const std::int32_t last = dynamics_.back();
    dynamics_[static_cast<std::size_t>(pos)] = last;
    dyn_pos_[static_cast<std::size_t>(last)] = pos;
    dynamics_.pop_back();
    dyn_pos_[s] = -1;
    cand_[s].clear();
    hits_[s].clear();
    cand_epoch_[s] = 0;
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
    dyn_.set_active(leaf_[static_cast<std::size_t>(slot)], t.active(slot));
  }
  void filter_changed(std::int32_t slot, const ObjectTable<S>& t) {
    if (t.is_static(slot))
      ++epoch_;  // every candidate list may name it
    else
      cand_epoch_[static_cast<std::size_t>(slot)] = 0;
  }

  template <class Visit>
  bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) {
    flush(t, st);
    // Dynamic against static. Objects whose fat box changed query the static tree, in Morton
    // order of their centres so that consecutive queries walk the same part of the tree (the
    // static tree is large: this is what keeps its nodes in cache).
    need_.clear();
    for (const std::int32_t a : dynamics_)
      if (t.active(a) && cand_epoch_[static_cast<std::size_t>(a)] != epoch_) need_.push_back({0u, a});
    if (!need_.empty() && !static_tree_.empty()) {
      const Aabb<S>& root = static_tree_.root().bv;
      const Vec3<S> scale = Vec3<S>::Constant(S(1023)).cwiseQuotient((root.max - root.min).cwiseMax(Vec3<S>::Constant(S(1e-30))));
      for (auto& [code, a] : need_) code = detail::morton_code<S>(t.box(a).center(), root.min, scale);
      std::sort(need_.begin(), need_.end());
    }
    for (const auto& item : need_) {
      const std::int32_t a = item.second;
      const auto sa = static_cast<std::size_t>(a);
      std::vector<std::int32_t>& cand = cand_[sa];
      cand.clear();
      ++st.static_queries;
      const Aabb<S>& fat = dyn_.box(leaf_[sa]);
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
      cand_epoch_[sa] = epoch_;
      stale_[sa] = 1;
    }
    // Hits from the tight box, recomputed only for objects that moved.
    for (const std::int32_t a : dynamics_) {
      if (!t.active(a)) continue;  // sleeping: its static pairs are inactive pairs
      const auto sa = static_cast<std::size_t>(a);
      std::vector<std::int32_t>& hits = hits_[sa];
      if (stale_[sa]) {
        hits.clear();
        const Aabb<S>& box = t.box(sa);
        for (const std::int32_t b : cand_[sa]) {
          ++st.pairs_tested;
          if (overlap(box, t.box(b))) hits.push_back(b);
        }
        stale_[sa] = 0;
      }
      for (const std::int32_t b : hits) {
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
      cand_.resize(n);
      hits_.resize(n);
      cand_epoch_.resize(n, 0);
      stale_.resize(n, 1);
    }
  }

  void flush(const ObjectTable<S>& t, BroadPhaseStats& st) {
    for (const std::int32_t slot : moved_) {
      const auto s = static_cast<std::size_t>(slot);
      moved_flag_[s] = 0;
      const std::int32_t leaf = leaf_[s];
      if (leaf == DynamicTree<S>::null) continue;  // removed (or now static) since it moved
      ++st.refits;
      stale_[s] = 1;
      if (dyn_.update(leaf, t.box(s))) {
        ++st.reinserts;
        cand_epoch_[s] = 0;  // the fat box changed: query the static tree again
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
    ++epoch_;
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
  std::vector<std::vector<std::int32_t>> cand_;               // dynamic slot -> accepted static slots overlapping its fat box
  std::vector<std::vector<std::int32_t>> hits_;               // dynamic slot -> those overlapping its tight box
  std::vector<std::uint32_t> cand_epoch_;                     // cand_ valid when equal to epoch_
  std::vector<std::uint8_t> stale_;                           // hits_ must be recomputed from cand_
  std::vector<std::pair<std::uint32_t, std::int32_t>> need_;  // (Morton code, slot) to query
  std::uint32_t epoch_ = 1;
};

}  // namespace impact
