// SPDX-License-Identifier: MIT
/// \file
/// AllPairsBroadPhase: the O(active * n) reference. Every active object is compared with every
/// other object (active pairs once); static–static and sleeping pairs never are. No tree, no state
/// beyond the object table: the oracle the other broad phases are checked against.
#pragma once

#include "impact/broad/broad_phase.hpp"

namespace impact {

template <class S>
class AllPairsBroadPhase {
 public:
  void insert(std::int32_t, const ObjectTable<S>&) {}
  void remove(std::int32_t, const ObjectTable<S>&) {}
  void moved(std::int32_t, const ObjectTable<S>&) {}
  void activity_changed(std::int32_t, const ObjectTable<S>&) {}
  void filter_changed(std::int32_t, const ObjectTable<S>&) {}

  /// Visits every pair of the pair rule (broad_phase.hpp) once. O(active * n).
  template <class Visit>
  bool find_pairs(const ObjectTable<S>& t, Visit&& visit, BroadPhaseStats& st) {
    active_.clear();
    inactive_.clear();
    for (std::int32_t i = 0; i < t.size(); ++i) {
      if (!t.alive(i)) continue;
      (t.active(i) ? active_ : inactive_).push_back(i);
    }
    for (std::size_t p = 0; p < active_.size(); ++p) {
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

 private:
  std::vector<std::int32_t> active_, inactive_;
};

}  // namespace impact
