// SPDX-License-Identifier: MIT
/// \file
/// The common ground of the broad phases: the object table they read (one slot per scene object:
/// world AABB, body type, sleeping flag, filter), the pair rule they all implement, their
/// work counters, and the interface every implementation offers.
///
/// The pair rule (identical for every broad phase, so their results can be compared as sets):
/// slots a != b form a pair when
///   1. at least one of them is *active* (alive, dynamic and awake): static–static,
///      static–sleeping and sleeping–sleeping pairs are never tested;
///   2. the filter accepts them: (group_a & mask_b) != 0, (group_b & mask_a) != 0 and the pair is not
///      on the ignore list (checked before the pair's own AABB test and any narrow-phase test;
///      only tree-node tests, which concern many objects at once, come earlier);
///   3. their world AABBs overlap (closed boxes, impact::overlap). These are the boxes the scene
///      computes (Scene::bounds): exact for spheres, particles and boxes, conservative for meshes.
///
/// Interface of a broad phase `B` over scalar S (checked at compile time by the scene, no virtual
/// calls; the scene holds one of them in a std::variant and dispatches once per call):
///   void insert(std::int32_t slot, const ObjectTable<S>&)      a new object
///   void remove(std::int32_t slot, const ObjectTable<S>&)      before the slot is freed
///   void moved(std::int32_t slot, const ObjectTable<S>&)       tight box changed (deferred)
///   void activity_changed(std::int32_t slot, const ObjectTable<S>&)  sleeping flag toggled
///   void filter_changed(std::int32_t slot, const ObjectTable<S>&)    filter or ignore list changed
///   void update(const ObjectTable<S>&, BroadPhaseStats&, int threads)
///        applies what the edits above deferred (refits, rebuilds, cached candidates); the scene
///        calls it once after edits, before the next query. May use `threads` threads.
///   bool find_pairs(const ObjectTable<S>&, Visit&&, BroadPhaseStats&) const
///        calls visit(slot_a, slot_b) -> bool for every pair of the rule, each once; stops and
///        returns false when visit returns false. Requires update() since the last edit.
///   std::vector<PairTask> split_pairs(const ObjectTable<S>&, std::size_t want) const
///   bool find_pairs_part(const ObjectTable<S>&, const PairTask&, Visit&&, BroadPhaseStats&) const
///        find_pairs cut into independent parts (about `want`, fewer for small scenes): running
///        find_pairs_part on each task in order visits exactly find_pairs' pairs in find_pairs'
///        order, with the same work counters summed, so parts can run on different threads and
///        their outputs be joined in task order (the scene's parallel queries).
///
/// Thread safety: edits and update() mutate; the const calls only read the broad phase and the
/// object table, so any number of threads may run them at once between edits.
#pragma once

#include "impact/core/config.hpp"
#include "impact/geometry/aabb.hpp"

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <unordered_set>
#include <utility>
#include <vector>

namespace impact {

/// Which broad phase a scene uses. All three return the same pair sets.
enum class BroadPhaseKind : std::uint8_t {
  AllPairs,       ///< O(active * n) reference (all_pairs.hpp)
  StaticDynamic,  ///< static tree built once, cached static candidates, dynamic tree with cached pairs (static_dynamic.hpp)
  Hierarchical,   ///< incremental AABB trees for static and dynamic objects, cached static candidates and dynamic pairs (hierarchical.hpp)
};

/// Group/mask filter: objects a and b may collide only when (a.group & b.mask) and
/// (b.group & a.mask) are both non-zero.
struct CollisionFilter {
  std::uint32_t group = 1;
  std::uint32_t mask = 0xffffffffu;
};

/// Work counters of one broad-phase (and narrow-phase) call. Tests use them to check that work a
/// scene does not need is skipped.
struct BroadPhaseStats {
  std::uint64_t bv_tests = 0;               ///< node–node and node–box tests inside trees
  std::uint64_t pairs_tested = 0;           ///< object pairs whose tight AABBs were compared
  std::uint64_t inactive_pairs_tested = 0;  ///< of those, pairs with no active object (always 0)
  std::uint64_t pairs_filtered = 0;         ///< pairs dropped by group/mask or the ignore list
  std::uint64_t pairs_found = 0;            ///< pairs handed to the caller
  std::uint64_t refits = 0;                 ///< objects whose bound in a tree was updated
  std::uint64_t reinserts = 0;              ///< leaves moved in a tree (fattened bound left behind)
  std::uint64_t static_queries = 0;         ///< dynamic objects queried against the static tree
  std::uint64_t rebuilds = 0;               ///< whole-tree rebuilds
  std::uint64_t narrow_tests = 0;           ///< exact shape–shape tests (narrow phase)
  std::uint64_t contacts = 0;               ///< contacts generated (narrow phase)
  std::uint64_t solver_limits = 0;          ///< narrow tests an iteration bound stopped (convex shapes' solvers)

  BroadPhaseStats& operator+=(const BroadPhaseStats& o) {
    bv_tests += o.bv_tests;
    pairs_tested += o.pairs_tested;
    inactive_pairs_tested += o.inactive_pairs_tested;
    pairs_filtered += o.pairs_filtered;
    pairs_found += o.pairs_found;
    refits += o.refits;
    reinserts += o.reinserts;
    static_queries += o.static_queries;
    rebuilds += o.rebuilds;
    narrow_tests += o.narrow_tests;
    contacts += o.contacts;
    solver_limits += o.solver_limits;
    return *this;
  }
};

/// Per-slot object data the broad phases read. Owned by the scene; slots of removed objects are
/// dead (alive == 0) until reused. One 64-byte record per slot (for double), aligned to a cache
/// line: the broad phases read the box, flags and filter of random slots together, and a record
/// straddling two lines would cost two misses.
template <class S>
struct ObjectTable {
  enum Flags : std::uint8_t { Alive = 1, Static = 2, Sleeping = 4 };

  struct alignas(sizeof(S) == 8 ? 64 : 8) Record {
    Aabb<S> box;  ///< world AABB of the object itself (never fattened)
    CollisionFilter filter;
    std::uint32_t ignore_count = 0;  ///< entries of the ignore list naming this slot
    std::uint8_t flags = 0;          ///< Flags
  };
  std::vector<Record> records;
  std::unordered_set<std::uint64_t> ignored;  ///< pair_key of ignored slot pairs

  std::int32_t size() const { return static_cast<std::int32_t>(records.size()); }
  void push_back() { records.emplace_back(); }
  const Aabb<S>& box(std::int32_t i) const { return records[static_cast<std::size_t>(i)].box; }
  Aabb<S>& box(std::int32_t i) { return records[static_cast<std::size_t>(i)].box; }
  std::uint8_t flags(std::int32_t i) const { return records[static_cast<std::size_t>(i)].flags; }
  std::uint8_t& flags(std::int32_t i) { return records[static_cast<std::size_t>(i)].flags; }
  const CollisionFilter& filter(std::int32_t i) const { return records[static_cast<std::size_t>(i)].filter; }
  CollisionFilter& filter(std::int32_t i) { return records[static_cast<std::size_t>(i)].filter; }
  std::uint32_t ignore_count(std::int32_t i) const { return records[static_cast<std::size_t>(i)].ignore_count; }
  std::uint32_t& ignore_count(std::int32_t i) { return records[static_cast<std::size_t>(i)].ignore_count; }

  bool alive(std::int32_t i) const { return flags(i) & Alive; }
  bool is_static(std::int32_t i) const { return flags(i) & Static; }
  bool sleeping(std::int32_t i) const { return flags(i) & Sleeping; }
  /// Alive, dynamic and awake.
  bool active(std::int32_t i) const { return flags(i) == Alive; }

  static std::uint64_t pair_key(std::int32_t a, std::int32_t b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
  }
  /// Rule 2 of the pair rule: group/mask and the ignore list.
  bool accepts(std::int32_t a, std::int32_t b) const {
    const Record& ra = records[static_cast<std::size_t>(a)];
    const Record& rb = records[static_cast<std::size_t>(b)];
    if (!(ra.filter.group & rb.filter.mask) || !(rb.filter.group & ra.filter.mask)) return false;
    if (IMPACT_UNLIKELY(ra.ignore_count && rb.ignore_count) && ignored.count(pair_key(a, b))) return false;
    return true;
  }
};

/// One independent part of a broad phase's find_pairs (see split_pairs above): a range [begin,
/// end) of positions in one of the broad phase's lists of objects, the list named by `kind` (what
/// the broad phase that made it says).
struct PairTask {
  std::uint8_t kind = 0;
  std::size_t begin = 0, end = 0;
};

namespace detail {

/// Asks the processor to bring in the cache line at p (a hint; nothing where the compiler offers
/// none). The broad phases' passes over scattered records (the moved objects, their candidates)
/// issue it a few iterations ahead, so that several misses are under way at once.
inline void prefetch(const void* p) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

/// Rules 2 and 3 for a pair whose activity (rule 1) the caller has established, with counting.
/// Returns true when the pair is to be reported.
template <class S>
inline bool test_pair(const ObjectTable<S>& t, std::int32_t a, std::int32_t b, BroadPhaseStats& st) {
  if (!t.accepts(a, b)) {
    ++st.pairs_filtered;
    return false;
  }
  ++st.pairs_tested;
  const auto& ra = t.records[static_cast<std::size_t>(a)];
  const auto& rb = t.records[static_cast<std::size_t>(b)];
  st.inactive_pairs_tested += (ra.flags != ObjectTable<S>::Alive) & (rb.flags != ObjectTable<S>::Alive);
  return overlap(ra.box, rb.box);
}

template <class B, class S, class = void>
struct is_broad_phase : std::false_type {};
template <class B, class S>
struct is_broad_phase<
    B, S,
    std::void_t<decltype(std::declval<B&>().insert(std::int32_t{}, std::declval<const ObjectTable<S>&>())),
                decltype(std::declval<B&>().remove(std::int32_t{}, std::declval<const ObjectTable<S>&>())),
                decltype(std::declval<B&>().moved(std::int32_t{}, std::declval<const ObjectTable<S>&>())),
                decltype(std::declval<B&>().activity_changed(std::int32_t{}, std::declval<const ObjectTable<S>&>())),
                decltype(std::declval<B&>().filter_changed(std::int32_t{}, std::declval<const ObjectTable<S>&>())),
                decltype(std::declval<B&>().update(std::declval<const ObjectTable<S>&>(), std::declval<BroadPhaseStats&>(), int{})),
                decltype(bool(std::declval<const B&>().find_pairs(std::declval<const ObjectTable<S>&>(),
                                                                  std::declval<bool (&)(std::int32_t, std::int32_t)>(),
                                                                  std::declval<BroadPhaseStats&>()))),
                decltype(std::vector<PairTask>(std::declval<const B&>().split_pairs(std::declval<const ObjectTable<S>&>(), std::size_t{}))),
                decltype(bool(std::declval<const B&>().find_pairs_part(std::declval<const ObjectTable<S>&>(), std::declval<const PairTask&>(),
                                                                       std::declval<bool (&)(std::int32_t, std::int32_t)>(),
                                                                       std::declval<BroadPhaseStats&>())))>> : std::true_type {};

}  // namespace detail

/// True when B offers the broad-phase interface described at the top of this file (the C++17
/// stand-in for a concept; the scene static_asserts it for every implementation it holds).
template <class B, class S>
inline constexpr bool is_broad_phase_v = detail::is_broad_phase<B, S>::value;

}  // namespace impact
