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
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/core/parallel.hpp"

#include <algorithm>

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

  /// Applies the edits since the last update: refits and reinsertions of moved objects, rebuilds;
  /// then the static-tree queries of the objects whose fat box changed (on `threads` threads,
  /// each object writing only its own candidates) and the tight-box re-tests of those that moved.
  void update(const ObjectTable<S>& t, BroadPhaseStats& st, int threads) {
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
    for_chunks(need_.size(), threads, st, [&](std::size_t k, BroadPhaseStats& cs) { query_static(t, need_[k].second, cs); });
    // Hits from the tight box, recomputed only for active objects that moved (sleeping ones'
    // static pairs are inactive pairs: they wait until the object wakes).
    stale_list_.clear();
    for (const std::int32_t a : dynamics_)
      if (t.active(a) && stale_[static_cast<std::size_t>(a)]) stale_list_.push_back(a);
    for_chunks(stale_list_.size(), threads, st, [&](std::size_t k, BroadPhaseStats& cs) {
      const std::int32_t a = stale_list_[k];
      const auto sa = static_cast<std::size_t>(a);
      std::vector<std::int32_t>& hits = hits_[sa];
      hits.clear();
      const Aabb<S>& box = t.box(sa);
      for (const std::int32_t b : cand_[sa]) {
        ++cs.pairs_tested;
        if (overlap(box, t.box(b))) hits.push_back(b);
      }
      stale_[sa] = 0;
    });
  }

  template <class Visit>
  bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) const {
    if (!static_pairs(t, 0, dynamics_.size(), visit, st)) return false;
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
    if (task.kind == 0) return static_pairs(t, task.begin, task.end, visit, st);
    return dyn_.self_pairs_from({task.i, task.j, task.pre_bv_tests}, pair_filter(t, visit, st), st);
  }

  const DynamicTree<S>& dynamic_tree() const { return dyn_; }
  const Bvh<Aabb<S>>& static_tree() const { return static_tree_; }

 private:
  /// The cached static pairs of dynamics_[begin, end) (active ones).
  template <class Visit>
  bool static_pairs(const ObjectTable<S>& t, std::size_t begin, std::size_t end, Visit& visit, BroadPhaseStats& st) const {
    for (std::size_t p = begin; p < end; ++p) {
      const std::int32_t a = dynamics_[p];
      if (!t.active(a)) continue;
      for (const std::int32_t b : hits_[static_cast<std::size_t>(a)]) {
        ++st.pairs_found;
        if (!visit(a, b)) return false;
      }
    }
    return true;
  }

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
  void query_static(const ObjectTable<S>& t, std::int32_t a, BroadPhaseStats& st) {
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

  /// body(k, stats) for k in [0, n), on `threads` threads when n is large enough to pay; the
  /// counters of every chunk added to st (integer sums: the same totals for any thread count).
  template <class Body>
  static void for_chunks(std::size_t n, int threads, BroadPhaseStats& st, Body&& body) {
    constexpr std::size_t grain = 64;
    if (threads <= 1 || n < 2 * grain) {
      for (std::size_t k = 0; k < n; ++k) body(k, st);
      return;
    }
    std::vector<BroadPhaseStats> chunk_stats((n + grain - 1) / grain);
    parallel_for_ranges(n, grain, threads, [&](std::size_t b, std::size_t e) {
      BroadPhaseStats& cs = chunk_stats[b / grain];
      for (std::size_t k = b; k < e; ++k) body(k, cs);
    });
    for (const auto& cs : chunk_stats) st += cs;
  }

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
  std::vector<std::pair<std::uint32_t, std::int32_t>> need_;  // (Morton code, slot) to query (update's scratch)
  std::vector<std::int32_t> stale_list_;                      // active slots whose hits_ update recomputes (update's scratch)
  std::uint32_t epoch_ = 1;
};

}  // namespace impact
