// SPDX-License-Identifier: MIT
/// \file
/// StaticCandidates: the dynamic-against-static half of a broad phase as a cache, shared by the
/// static/dynamic split (static_dynamic.hpp) and the hierarchical broad phase (hierarchical.hpp).
/// Per dynamic object it keeps
///   - its *candidates*: the static objects the filter accepts whose boxes overlap the object's
///     fat box (its leaf box in the dynamic tree), found by one query of the static structure;
///     valid while the fat box is unchanged and nothing invalidated them (invalidate, or
///     invalidate_all for every object);
///   - its *hits*: the candidates whose boxes overlap the object's tight box, recomputed from the
///     candidates only when the object moved (moved) or its candidates were found again.
/// update() brings both up to date for the active objects (queries in Morton order of the objects'
/// centres, so that consecutive queries walk the same part of the static structure; on `threads`
/// threads, each object writing only its own lists); pairs() then reports the hits, reading only.
/// Sleeping objects keep their lists untouched until they wake.
#pragma once

#include "impact/broad/broad_phase.hpp"
#include "impact/core/parallel.hpp"
#include "impact/detail/morton.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace impact {

namespace detail {
/// 30-bit Morton code of p quantised to 10 bits per axis by (p - lo) * scale (clamped).
template <class S>
inline std::uint32_t morton_code(const Vec3<S>& p, const Vec3<S>& lo, const Vec3<S>& scale) {
  std::uint32_t c[3];
  for (int k = 0; k < 3; ++k) {
    const S q = (p[k] - lo[k]) * scale[k];
    c[k] = q > S(0) ? std::uint32_t(std::min(q, S(1023))) : 0u;
  }
  return static_cast<std::uint32_t>(spread_bits_3(c[0]) | (spread_bits_3(c[1]) << 1) | (spread_bits_3(c[2]) << 2));
}

/// body(k, stats) for k in [0, n), on `threads` threads when n is large enough to pay; the
/// counters of every chunk added to st (integer sums: the same totals for any thread count).
template <class Body>
inline void for_chunks(std::size_t n, int threads, BroadPhaseStats& st, Body&& body) {
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
}  // namespace detail

/// The broad phase's dynamic objects, each at a position in a list kept dense by swap-removal
/// (add, remove, pos_of), with its lists stored at that position, so that the per-step passes
/// over the dynamic objects read consecutive entries instead of one scattered slot record each.
template <class S>
class StaticCandidates {
 public:
  /// Dynamic object `slot` is appended at position size(), with no lists yet.
  void add(std::int32_t slot, bool active) {
    const auto s = static_cast<std::size_t>(slot);
    if (s >= pos_.size()) pos_.resize(s + 1, -1);
    pos_[s] = static_cast<std::int32_t>(slots_.size());
    slots_.push_back(slot);
    cand_.emplace_back();
    hits_.emplace_back();
    cand_epoch_.push_back(0);
    stale_.push_back(1);
    active_.push_back(active);
  }
  /// Dynamic object `slot` is removed and the last one takes its position.
  void remove(std::int32_t slot) {
    const auto pos = pos_of(slot);
    const std::size_t last = cand_.size() - 1;
    if (pos != last) {
      slots_[pos] = slots_[last];
      pos_[static_cast<std::size_t>(slots_[pos])] = static_cast<std::int32_t>(pos);
      cand_[pos].swap(cand_[last]);
      hits_[pos].swap(hits_[last]);
      cand_epoch_[pos] = cand_epoch_[last];
      stale_[pos] = stale_[last];
      active_[pos] = active_[last];
    }
    pos_[static_cast<std::size_t>(slot)] = -1;
    slots_.pop_back();
    cand_.pop_back();
    hits_.pop_back();
    cand_epoch_.pop_back();
    stale_.pop_back();
    active_.pop_back();
  }
  /// The position of dynamic object `slot`.
  std::size_t pos_of(std::int32_t slot) const { return static_cast<std::size_t>(pos_[static_cast<std::size_t>(slot)]); }
  std::size_t size() const { return cand_.size(); }
  /// The slot of the dynamic object at position pos.
  std::int32_t slot(std::size_t pos) const { return slots_[pos]; }
  /// Whether the object at position pos is active (awake).
  bool active(std::size_t pos) const { return active_[pos]; }
  /// The object is active (awake) or not: its pairs are reported, its lists kept up to date.
  void set_active(std::size_t pos, bool active) { active_[pos] = active; }
  /// The object's candidates must be found again (its fat box or filter changed, or a static
  /// object near it changed).
  void invalidate(std::size_t pos) { cand_epoch_[pos] = 0; }
  /// Every object's candidates must be found again.
  void invalidate_all() { ++epoch_; }
  /// The object's tight box changed: its hits must be recomputed.
  void moved(std::size_t pos) { stale_[pos] = 1; }

  /// Brings the lists of the active objects up to date. `bounds`: a box around the static objects (for the Morton order; null when
  /// there are none). query(a, cand, stats) appends to cand the static objects the filter accepts
  /// whose boxes overlap slot a's fat box (counting its node tests and filtered pairs in stats).
  /// Counts static_queries and, for the tight-box tests, pairs_tested.
  template <class Query>
  void update(const ObjectTable<S>& t, const Aabb<S>* bounds, int threads,
              BroadPhaseStats& st, Query&& query) {
    need_.clear();
    const std::size_t n = cand_.size();
    for (std::size_t p = 0; p < n; ++p)
      if (active_[p] && cand_epoch_[p] != epoch_) need_.push_back({0u, static_cast<std::uint32_t>(p)});
    if (!need_.empty() && bounds) {
      const Vec3<S> scale =
          Vec3<S>::Constant(S(1023)).cwiseQuotient((bounds->max - bounds->min).cwiseMax(Vec3<S>::Constant(S(1e-30))));
      for (auto& q : need_) q.first = detail::morton_code<S>(t.box(slots_[q.second]).center(), bounds->min, scale);
      std::sort(need_.begin(), need_.end());
    }
    detail::for_chunks(need_.size(), threads, st, [&](std::size_t k, BroadPhaseStats& cs) {
      const std::size_t p = need_[k].second;
      cand_[p].clear();
      ++cs.static_queries;
      if (bounds) query(slots_[p], cand_[p], cs);
      cand_epoch_[p] = epoch_;
      stale_[p] = 1;
    });
    // Hits from the tight box, recomputed only for active objects that moved (sleeping ones'
    // static pairs are inactive pairs: they wait until the object wakes).
    stale_list_.clear();
    for (std::size_t p = 0; p < n; ++p)
      if (active_[p] && stale_[p]) stale_list_.push_back(static_cast<std::uint32_t>(p));
    const std::size_t ns = stale_list_.size();
    detail::for_chunks(ns, threads, st, [&](std::size_t k, BroadPhaseStats& cs) {
      if (k + 8 < ns) {  // the records of the object 8 ahead, and of the candidates of the one 4 ahead
        const std::size_t f = stale_list_[k + 8];
        detail::prefetch(&t.box(slots_[f]));
        detail::prefetch(cand_[f].data());
      }
      if (k + 4 < ns)
        for (const std::int32_t b : cand_[stale_list_[k + 4]]) detail::prefetch(&t.box(b));
      const std::size_t p = stale_list_[k];
      std::vector<std::int32_t>& hits = hits_[p];
      hits.clear();
      const Aabb<S>& box = t.box(slots_[p]);
      for (const std::int32_t b : cand_[p]) {
        ++cs.pairs_tested;
        if (overlap(box, t.box(b))) hits.push_back(b);
      }
      stale_[p] = 0;
    });
  }

  /// Reports the hits of the active objects at positions [begin, end) as visit(a, b); false when
  /// visit stopped it.
  template <class Visit>
  bool pairs(std::size_t begin, std::size_t end, Visit& visit, BroadPhaseStats& st) const {
    for (std::size_t p = begin; p < end; ++p) {
      if (!active_[p]) continue;
      const std::int32_t a = slots_[p];
      for (const std::int32_t b : hits_[p]) {
        ++st.pairs_found;
        if (!visit(a, b)) return false;
      }
    }
    return true;
  }

 private:
  std::vector<std::int32_t> slots_;                            // position -> dynamic slot
  std::vector<std::int32_t> pos_;                              // slot -> position (-1: none)
  std::vector<std::vector<std::int32_t>> cand_;                // position -> accepted static slots overlapping its fat box
  std::vector<std::vector<std::int32_t>> hits_;                // position -> those overlapping its tight box
  std::vector<std::uint32_t> cand_epoch_;                      // cand_ valid when equal to epoch_
  std::vector<std::uint8_t> stale_;                            // hits_ must be recomputed from cand_
  std::vector<std::uint8_t> active_;                           // the object is awake
  std::vector<std::pair<std::uint32_t, std::uint32_t>> need_;  // (Morton code, position) to query (update's scratch)
  std::vector<std::uint32_t> stale_list_;                      // active positions whose hits update recomputes (update's scratch)
  std::uint32_t epoch_ = 1;
};

}  // namespace impact
