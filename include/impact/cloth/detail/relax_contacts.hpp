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
/// moved). `gap(k)` is the constraint's current sum_j a_j n . x1_j; `apply(k)` applies its impulse
/// and returns whether it moved anything. A constraint gets an impulse when b - gap > tolerance;
/// at most `max_rounds` rounds. `acted` (optional, set.size() entries) marks the constraints that
/// got an impulse. Cost: O(w.size() + set.size()) to index, then per round the constraints visited.
template <class Gap, class Apply>
RelaxStats relax_contacts(const std::vector<ZoneConstraint>& set, const std::vector<double>& w, double tolerance, int max_rounds, Gap&& gap,
                          Apply&& apply, std::vector<std::uint8_t>* acted = nullptr) {
  RelaxStats r;
  const std::size_t m = set.size(), nv = w.size();
  if (m == 0 || max_rounds <= 0) return r;
  auto movable = [&](std::int32_t v) { return w[static_cast<std::size_t>(v)] > 0; };
  // vertex -> constraints through it (movable vertices only), CSR
  std::vector<std::uint32_t> off(nv + 1, 0), idx;
  for (const auto& k : set)
    for (int j = 0; j < k.count; ++j)
      if (movable(k.v[j])) ++off[static_cast<std::size_t>(k.v[j]) + 1];
  for (std::size_t v = 0; v < nv; ++v) off[v + 1] += off[v];
  idx.resize(off[nv]);
  {
    std::vector<std::uint32_t> fill(off.begin(), off.end() - 1);
    for (std::size_t c = 0; c < m; ++c)
      for (int j = 0; j < set[c].count; ++j)
        if (movable(set[c].v[j])) idx[fill[static_cast<std::size_t>(set[c].v[j])]++] = static_cast<std::uint32_t>(c);
  }
  std::vector<std::uint32_t> cur(m), next;
  std::iota(cur.begin(), cur.end(), 0u);
  std::vector<std::uint8_t> pending(m, 1);  // in this round's list (not visited yet) or the next's
  while (r.rounds < max_rounds && !cur.empty()) {
    ++r.rounds;
    next.clear();
    for (const auto c : cur) {
      pending[c] = 0;
      const ZoneConstraint& k = set[c];
      if (k.b - gap(k) <= tolerance || !apply(k)) continue;
      ++r.impulses;
      if (acted) (*acted)[c] = 1;
      for (int j = 0; j < k.count; ++j) {
        if (!movable(k.v[j])) continue;
        const std::size_t v = static_cast<std::size_t>(k.v[j]);
        for (std::uint32_t q = off[v]; q < off[v + 1]; ++q)
          if (idx[q] != c && !pending[idx[q]]) pending[idx[q]] = 1, next.push_back(idx[q]);
      }
    }
    // In index order: a constraint is pending now iff it is in `next`, so when `next` is a large
    // share of the set a scan of the flags lists it in order, cheaper than sorting it.
    if (next.size() * 16 >= m) {
      next.clear();
      for (std::size_t c = 0; c < m; ++c)
        if (pending[c]) next.push_back(static_cast<std::uint32_t>(c));
    } else {
      std::sort(next.begin(), next.end());
    }
    std::swap(cur, next);
  }
  r.converged = cur.empty();
  return r;
}

}  // namespace impact::detail::cloth
