// SPDX-License-Identifier: MIT
/// \file
/// StaticCandidates: the dynamic-against-static half of a broad phase as a cache, shared by the
/// static/dynamic split (static_dynamic.hpp) and the hierarchical broad phase (dynamic_tree.hpp).
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

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

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

template <class S>
class StaticCandidates {
 public:
  /// Room for slots [0, n).
  void grow(std::size_t n) {
    if (n <= cand_.size()) return;
    cand_.resize(n);
    hits_.resize(n);
    cand_epoch_.resize(n, 0);
    stale_.resize(n, 1);
  }
  /// A dynamic object was added or removed at this slot: no lists.
  void reset(std::int32_t slot) {
    const auto s = static_cast<std::size_t>(slot);
    cand_[s].clear();
    hits_[s].clear();
    cand_epoch_[s] = 0;
    stale_[s] = 1;
  }
  /// The object's candidates must be found again (its fat box or filter changed, or a static
  /// object near it changed).
  void invalidate(std::int32_t slot) { cand_epoch_[static_cast<std::size_t>(slot)] = 0; }
  /// Every object's candidates must be found again.
  void invalidate_all() { ++epoch_; }
  /// The object's tight box changed: its hits must be recomputed.
  void moved(std::int32_t slot) { stale_[static_cast<std::size_t>(slot)] = 1; }

  /// Brings the lists of the active objects of `dynamics` up to date. `bounds`: a box around the
  /// static objects (for the Morton order; null when there are none). query(a, cand, stats)
  /// appends to cand the static objects the filter accepts whose boxes overlap a's fat box
  /// (counting its node tests and filtered pairs in stats). Counts static_queries and, for the
  /// tight-box tests, pairs_tested.
  template <class Query>
  void update(const ObjectTable<S>& t, const std::vector<std::int32_t>& dynamics, const Aabb<S>* bounds, int threads,
              BroadPhaseStats& st, Query&& query) {
    need_.clear();
    for (const std::int32_t a : dynamics)
      if (t.active(a) && cand_epoch_[static_cast<std::size_t>(a)] != epoch_) need_.push_back({0u, a});
    if (!need_.empty() && bounds) {
      const Vec3<S> scale =
          Vec3<S>::Constant(S(1023)).cwiseQuotient((bounds->max - bounds->min).cwiseMax(Vec3<S>::Constant(S(1e-30))));
      for (auto& q : need_) q.first = detail::morton_code<S>(t.box(q.second).center(), bounds->min, scale);
      std::sort(need_.begin(), need_.end());
    }
    detail::for_chunks(need_.size(), threads, st, [&](std::size_t k, BroadPhaseStats& cs) {
      const std::int32_t a = need_[k].second;
      const auto sa = static_cast<std::size_t>(a);
      cand_[sa].clear();
      ++cs.static_queries;
      if (bounds) query(a, cand_[sa], cs);
      cand_epoch_[sa] = epoch_;
      stale_[sa] = 1;
    });
    // Hits from the tight box, recomputed only for active objects that moved (sleeping ones'
    // static pairs are inactive pairs: they wait until the object wakes).
    stale_list_.clear();
    for (const std::int32_t a : dynamics)
      if (t.active(a) && stale_[static_cast<std::size_t>(a)]) stale_list_.push_back(a);
    detail::for_chunks(stale_list_.size(), threads, st, [&](std::size_t k, BroadPhaseStats& cs) {
      const std::int32_t a = stale_list_[k];
      const auto sa = static_cast<std::size_t>(a);
      std::vector<std::int32_t>& hits = hits_[sa];
      hits.clear();
      const Aabb<S>& box = t.box(a);
      for (const std::int32_t b : cand_[sa]) {
        ++cs.pairs_tested;
        if (overlap(box, t.box(b))) hits.push_back(b);
      }
      stale_[sa] = 0;
    });
  }

  /// Reports the hits of the active objects of dynamics[begin, end) as visit(a, b); false when
  /// visit stopped it.
  template <class Visit>
  bool pairs(const ObjectTable<S>& t, const std::vector<std::int32_t>& dynamics, std::size_t begin, std::size_t end, Visit& visit,
             BroadPhaseStats& st) const {
    for (std::size_t p = begin; p < end; ++p) {
      const std::int32_t a = dynamics[p];
      if (!t.active(a)) continue;
      for (const std::int32_t b : hits_[static_cast<std::size_t>(a)]) {
        ++st.pairs_found;
        if (!visit(a, b)) return false;
      }
    }
    return true;
  }

 private:
  std::vector<std::vector<std::int32_t>> cand_;               // dynamic slot -> accepted static slots overlapping its fat box
  std::vector<std::vector<std::int32_t>> hits_;               // dynamic slot -> those overlapping its tight box
  std::vector<std::uint32_t> cand_epoch_;                     // cand_ valid when equal to epoch_
  std::vector<std::uint8_t> stale_;                           // hits_ must be recomputed from cand_
  std::vector<std::pair<std::uint32_t, std::int32_t>> need_;  // (Morton code, slot) to query (update's scratch)
  std::vector<std::int32_t> stale_list_;                      // active slots whose hits update recomputes (update's scratch)
  std::uint32_t epoch_ = 1;
};

}  // namespace impact
