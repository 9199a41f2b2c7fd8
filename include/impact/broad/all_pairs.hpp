// SPDX-License-Identifier: MIT
/// \file
/// AllPairsBroadPhase: the O(active * n) reference. Every active object is compared with every
/// other object (active pairs once); static–static and sleeping pairs never are. No tree: the
/// oracle the other broad phases are checked against. Its only state, the lists of active and of
/// inactive live slots (in slot order), is rebuilt by update() after insertions, removals and
/// sleeping changes, so that find_pairs only reads (safe from many threads between edits).
#pragma once

#include "impact/broad/broad_phase.hpp"

#include <algorithm>

namespace impact {

template <class S>
class AllPairsBroadPhase {
 public:
  void insert(std::int32_t, const ObjectTable<S>&) { lists_dirty_ = true; }
  void remove(std::int32_t, const ObjectTable<S>&) { lists_dirty_ = true; }
  void moved(std::int32_t, const ObjectTable<S>&) {}
  void activity_changed(std::int32_t, const ObjectTable<S>&) { lists_dirty_ = true; }
  void filter_changed(std::int32_t, const ObjectTable<S>&) {}

  /// Rebuilds the active and inactive lists when objects came, went, slept or woke. O(n).
  void update(const ObjectTable<S>& t, BroadPhaseStats&, int /*threads*/) {
    if (!lists_dirty_) return;
    active_.clear();
    inactive_.clear();
    for (std::int32_t i = 0; i < t.size(); ++i) {
      if (!t.alive(i)) continue;
      (t.active(i) ? active_ : inactive_).push_back(i);
    }
    lists_dirty_ = false;
  }

  /// Visits every pair of the pair rule (broad_phase.hpp) once. O(active * n).
  template <class Visit>
  bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) const {
    return pairs_of(t, 0, active_.size(), visit, st);
  }

  /// Parts of find_pairs: ranges of the active list (the work of an object falls with its
  /// position, so the ranges are many and small).
  std::vector<PairTask> split_pairs(const ObjectTable<S>&, std::size_t want) const {
    std::vector<PairTask> tasks;
    const std::size_t n = active_.size();
    const std::size_t chunk = std::max<std::size_t>(8, n / std::max<std::size_t>(want, 1));
    for (std::size_t b = 0; b < n; b += chunk) tasks.push_back({0, b, std::min(n, b + chunk)});
    return tasks;
  }
  template <class Visit>
  bool find_pairs_part(const ObjectTable<S>& t, const PairTask& task, Visit&& visit, BroadPhaseStats& st) const {
    return pairs_of(t, task.begin, task.end, visit, st);
  }

 private:
  /// The pairs whose first member is active_[p], p in [begin, end).
  template <class Visit>
  bool pairs_of(const ObjectTable<S>& t, std::size_t begin, std::size_t end, Visit& visit, BroadPhaseStats& st) const {
    for (std::size_t p = begin; p < end; ++p) {
      const std::int32_t a = active_[p];
      for (std::size_t q = p + 1; q < active_.size(); ++q)
        if (detail::test_pair(t, a, active_[q], st)) {
          ++st.pairs_found;
          if (!visit(a, active_[q])) return false;
        }
      for (const std::int32_t b : inactive_)
        if (detail::test_pair(t, a, b, st)) {
          ++st.pairs_found;
          if (!visit(a, b)) return false;
        }
    }
    return true;
  }

  std::vector<std::int32_t> active_, inactive_;
  bool lists_dirty_ = false;
};

}  // namespace impact
