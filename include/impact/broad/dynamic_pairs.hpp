// SPDX-License-Identifier: MIT
/// \file
/// DynamicPairs: the dynamic–dynamic half of a broad phase as a cache of pairs, shared by the
/// static/dynamic split (static_dynamic.hpp) and the hierarchical broad phase (hierarchical.hpp).
/// Per dynamic object, at its position in StaticCandidates' dense list, it keeps the positions of
/// the dynamic objects whose *fat* boxes (their leaf boxes in the dynamic tree) overlap its own,
/// awake or asleep, each pair stored on both sides. A fat box changes only when its object is
/// inserted or reinserted, so only those objects' pairs can change: the broad phase drops the
/// pairs of each one (drop) and marks its leaf fresh; update() then adds the pairs the tree finds
/// for its fresh leaves (DynamicTree::fresh_pairs, one query per fresh leaf). As Bullet keeps its
/// pair cache, this replaces the traversal of the whole dynamic tree against itself on every call
/// (74,000 node tests per step in impact-scene-bench at 10^5 objects, for 860 reinserted objects
/// out of 10,000) by queries of the objects that left their fat boxes (19,000). pairs() reports,
/// for the active objects in a range of positions, the cached pairs that pass the pair rule's
/// filter and tight-box test, reading only.
#pragma once

#include "impact/broad/broad_phase.hpp"
#include "impact/broad/dynamic_tree.hpp"
#include "impact/broad/static_candidates.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace impact {

template <class S>
class DynamicPairs {
 public:
  /// A dynamic object was appended at position size(), with no pairs yet.
  void add() { near_.emplace_back(); }
  /// The dynamic object at position pos is removed and the last one takes its position (as in
  /// StaticCandidates::remove, which must follow).
  void remove(std::size_t pos) {
    drop(pos);
    const std::size_t last = near_.size() - 1;
    if (pos != last) {
      const auto from = static_cast<std::int32_t>(last), to = static_cast<std::int32_t>(pos);
      for (const std::int32_t q : near_[last]) std::replace(near_[std::size_t(q)].begin(), near_[std::size_t(q)].end(), from, to);
      near_[pos].swap(near_[last]);
    }
    near_.pop_back();
  }
  /// The fat box of the object at position pos changed: forgets its pairs (on both sides).
  void drop(std::size_t pos) {
    const auto self = static_cast<std::int32_t>(pos);
    for (const std::int32_t q : near_[pos]) {
      std::vector<std::int32_t>& other = near_[std::size_t(q)];
      other.erase(std::find(other.begin(), other.end(), self));
    }
    near_[pos].clear();
  }
  /// Adds the pairs of the tree's fresh leaves (whose objects were dropped or added since the
  /// last update), which unmarks them. `cand` gives the objects' positions. The tree's queries
  /// run on `threads` threads; the pairs are added in the same order for every count.
  void update(DynamicTree<S>& tree, const StaticCandidates<S>& cand, BroadPhaseStats& st, int threads = 1) {
    tree.fresh_pairs(
        [&](std::int32_t a, std::int32_t b) {
          const auto pa = static_cast<std::int32_t>(cand.pos_of(a)), pb = static_cast<std::int32_t>(cand.pos_of(b));
          near_[std::size_t(pa)].push_back(pb);
          near_[std::size_t(pb)].push_back(pa);
          return true;
        },
        st, threads);
  }

  /// Reports, for the active objects at positions [begin, end), their cached pairs that the
  /// pair rule accepts, as visit(a, b) on slots: a pair of two active objects from the smaller
  /// position, a pair with a sleeping object from the active one. False when visit stopped it.
  template <class Visit>
  bool pairs(std::size_t begin, std::size_t end, const StaticCandidates<S>& cand, const ObjectTable<S>& t, Visit& visit,
             BroadPhaseStats& st) const {
    for (std::size_t p = begin; p < end; ++p) {
      if (near_[p].empty() || !cand.active(p)) continue;
      const std::int32_t a = cand.slot(p);
      for (const std::int32_t q : near_[p]) {
        const auto qs = static_cast<std::size_t>(q);
        if (qs < p && cand.active(qs)) continue;  // reported from q
        const std::int32_t b = cand.slot(qs);
        if (!detail::test_pair(t, a, b, st)) continue;
        ++st.pairs_found;
        if (!visit(a, b)) return false;
      }
    }
    return true;
  }

 private:
  std::vector<std::vector<std::int32_t>> near_;  // position -> positions of the dynamic objects whose fat boxes overlap its own
};

/// The pairs of a broad phase that splits its objects into static and dynamic ones and caches them
/// in a StaticCandidates and a DynamicPairs (static_dynamic.hpp, hierarchical.hpp): for the
/// dynamic objects at positions [begin, end), their static hits (kind 0) or their dynamic pairs
/// (kind 1), or both for the whole list (find_split_pairs). Read only.
template <class S, class Visit>
bool find_split_pairs_part(const StaticCandidates<S>& cand, const DynamicPairs<S>& dyn, const ObjectTable<S>& t,
                           const PairTask& task, Visit& visit, BroadPhaseStats& st) {
  if (task.kind == 0) return cand.pairs(task.begin, task.end, visit, st);
  return dyn.pairs(task.begin, task.end, cand, t, visit, st);
}
template <class S, class Visit>
bool find_split_pairs(const StaticCandidates<S>& cand, const DynamicPairs<S>& dyn, const ObjectTable<S>& t, Visit& visit,
                      BroadPhaseStats& st) {
  return find_split_pairs_part(cand, dyn, t, PairTask{0, 0, cand.size()}, visit, st) &&
         find_split_pairs_part(cand, dyn, t, PairTask{1, 0, cand.size()}, visit, st);
}
/// The parts of find_split_pairs over n dynamic objects for about `want` workers: ranges of at
/// least 64 objects' static hits, then of their dynamic pairs.
inline std::vector<PairTask> split_pair_tasks(std::size_t n, std::size_t want) {
  std::vector<PairTask> tasks;
  const std::size_t chunk = std::max<std::size_t>(64, n / std::max<std::size_t>(want, 1));
  for (std::uint8_t kind : {0, 1})
    for (std::size_t b = 0; b < n; b += chunk) tasks.push_back({kind, b, std::min(n, b + chunk)});
  return tasks;
}

}  // namespace impact
