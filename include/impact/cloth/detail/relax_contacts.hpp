// SPDX-License-Identifier: MIT
/// \file
/// relax_contacts: Gauss-Seidel relaxation of a set of contact constraints by inelastic impulses,
/// the proximity stage of cloth_collision_step (cloth/collision_step.hpp). Each constraint
/// sum_j a_j n . x1_j >= b (a ZoneConstraint on end positions) whose gap falls short of b by more
/// than a tolerance gets one impulse that meets it exactly (with friction: `apply` decides); an
/// impulse moves its constraint's movable vertices, so the constraints sharing one of them are
/// checked again, later in the same round when they come later in the set, else in the next
/// round. Rounds run in index order until one applies nothing (converged) or the budget ends.
///
/// Why rounds: in a stack of sheets resting on a floor, one pass cannot stop the stack (stopping
/// the lowest pair makes the pair above it approach again, whatever the order); each round
/// carries the stop one layer further (at 10^5 vertices and ten landing layers, 30-210 rounds to
/// 1e-3 h). Each impulse is equal and opposite on the pair (weights a_j, inverse masses), so the
/// linear momentum of free vertices is kept; only constraints with a movable vertex are ever
/// rechecked, so a round costs in proportion to the constraints it touches. Not thread-safe
/// (it moves the positions `apply` writes).
#pragma once

#include "impact/cloth/zone_projection.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace impact::detail::cloth {

/// What relax_contacts did.
struct RelaxStats {
  int rounds = 0;            ///< rounds run (a round visits every constraint still to check)
  std::size_t impulses = 0;  ///< impulses applied
  bool converged = true;     ///< the last round applied nothing: every gap >= b - tolerance
};

/// Relaxes `set` (constraints over vertices 0..w.size()-1; `w` the inverse masses, 0 = never
/// moved). `gap(k)` is the constraint's current sum_j a_j n . x1_j; `apply(k, dl, dn)` moves the
/// constraint's movable vertices by w_j a_j dl n, which changes its gap by dn = dl sum_j a_j^2 w_j
/// (> 0: a push, which may add friction), and returns whether it moved anything.
/// A constraint whose gap falls short of b by more than `tolerance` gets dl = (b - gap) / denom,
/// which meets it exactly (one-sided: nothing is ever pulled back). In a stack of K sheets on a
/// floor this needs O(K^2) rounds. (Impulses accumulated per constraint, which a constraint
/// pushed past b gives back, i.e. projected Gauss-Seidel or over-relaxation on the complementarity
/// problem, were tried, also warm-started from the last step: on the layers scene they did not
/// converge within 500 rounds where this does; see docs/cloth-history.md.)
/// At most `max_rounds` rounds. `acted` (optional, set.size() entries) marks the constraints that
/// got an impulse. Cost: O(w.size() + set.size()) to index, then per round the constraints visited
/// and the listing of the next round's: a scan of every constraint when the vertices the round
/// moved lie on many of them, else their constraints through the vertex -> constraint index,
/// once per moved vertex (not once per impulse: in a resting stack a vertex lies on tens of
/// constraints and most of them act in a round).
template <class Gap, class Apply>
RelaxStats relax_contacts(const std::vector<ZoneConstraint>& set, const std::vector<double>& w, double tolerance, int max_rounds, Gap&& gap,
                          Apply&& apply, std::vector<std::uint8_t>* acted = nullptr) {
  RelaxStats r;
  const std::size_t m = set.size(), nv = w.size();
  if (m == 0 || max_rounds <= 0) return r;
  auto movable = [&](std::int32_t v) { return w[static_cast<std::size_t>(v)] > 0; };
  // Times count constraint visits. moved_at[v]: the visit whose impulse last moved vertex v;
  // visited_at[c]: constraint c's last visit. A constraint is checked again iff one of its movable
  // vertices was moved after its last visit: by a constraint visited later in the same round (its
  // own impulse moves them at its own visit's time, which does not count), or in a round it was
  // not visited in. Listing the next round's constraints by these stamps once per round, not
  // through the constraints of every vertex at every impulse, gives the same lists.
  std::vector<std::uint64_t> moved_at(nv, 0), visited_at(m, 0);
  std::uint64_t now = 0;
  // vertex -> constraints through it (movable vertices only), CSR: the counts now, the entries
  // when a round first lists its successors through them
  std::vector<std::uint32_t> off(nv + 1, 0), idx;
  for (const auto& k : set)
    for (int j = 0; j < k.count; ++j)
      if (movable(k.v[j])) ++off[static_cast<std::size_t>(k.v[j]) + 1];
  for (std::size_t v = 0; v < nv; ++v) off[v + 1] += off[v];
  auto index = [&]() {
    if (!idx.empty() || off[nv] == 0) return;
    idx.resize(off[nv]);
    std::vector<std::uint32_t> fill(off.begin(), off.end() - 1);
    for (std::size_t c = 0; c < m; ++c)
      for (int j = 0; j < set[c].count; ++j)
        if (movable(set[c].v[j])) idx[fill[static_cast<std::size_t>(set[c].v[j])]++] = static_cast<std::uint32_t>(c);
  };
  auto stale = [&](std::size_t c) {
    const ZoneConstraint& k = set[c];
    for (int j = 0; j < k.count; ++j)
      if (moved_at[static_cast<std::size_t>(k.v[j])] > visited_at[c]) return true;  // immovable vertices keep 0
    return false;
  };
  std::vector<std::uint32_t> cur(m), next, moved;
  std::iota(cur.begin(), cur.end(), 0u);
  std::vector<std::uint32_t> listed;  // round in which a constraint was last listed (incidence path)
  while (r.rounds < max_rounds && !cur.empty()) {
    ++r.rounds;
    const std::uint64_t round_start = now + 1;
    moved.clear();
    std::size_t reach = 0;  // entries of the incidence lists of the moved vertices
    for (const auto c : cur) {
      visited_at[c] = ++now;
      const ZoneConstraint& k = set[c];
      const double short_by = k.b - gap(k);
      if (short_by <= tolerance) continue;
      double denom = 0;
      for (int j = 0; j < k.count; ++j) denom += k.a[j] * k.a[j] * w[static_cast<std::size_t>(k.v[j])];
      if (!(denom > 0)) continue;
      if (!apply(k, short_by / denom, short_by)) continue;
      ++r.impulses;
      if (acted) (*acted)[c] = 1;
      for (int j = 0; j < k.count; ++j) {
        if (!movable(k.v[j])) continue;
        const std::size_t v = static_cast<std::size_t>(k.v[j]);
        if (moved_at[v] < round_start) moved.push_back(static_cast<std::uint32_t>(v)), reach += off[v + 1] - off[v];
        moved_at[v] = now;
      }
    }
    // The next round's list, in index order: by a scan of every constraint when the moved
    // vertices reach many of them, else through their incidence lists (then sorted).
    next.clear();
    if (2 * reach >= m) {
      for (std::size_t c = 0; c < m; ++c)
        if (stale(c)) next.push_back(static_cast<std::uint32_t>(c));
    } else {
      index();
      if (listed.empty()) listed.assign(m, 0);
      const auto mark = static_cast<std::uint32_t>(r.rounds);
      for (const auto v : moved)
        for (std::uint32_t q = off[v]; q < off[v + 1]; ++q) {
          const std::uint32_t c = idx[q];
          if (listed[c] != mark && stale(c)) listed[c] = mark, next.push_back(c);
        }
      std::sort(next.begin(), next.end());
    }
    std::swap(cur, next);
  }
  r.converged = cur.empty();
  return r;
}

}  // namespace impact::detail::cloth
