// SPDX-License-Identifier: MIT
// relax_contacts (cloth/detail/relax_contacts.hpp) against a reference written here: the
// Gauss-Seidel relaxation as it is specified, with every impulse re-listing, through a vertex ->
// constraint index, each constraint through a vertex it moved that is not waiting in the current
// round. The library lists the next round's constraints by visit stamps instead (and only once per
// round); the two must visit the same constraints in the same order, so every impulse, round
// count, verdict and final position is compared exactly, on random contact sets (shared vertices,
// pinned vertices, duplicate constraints), on a stack of sheets resting on a floor, and with small
// round budgets (unconverged runs).
#include "impact/cloth/detail/relax_contacts.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

namespace {

using impact::ZoneConstraint;
using impact::detail::cloth::relax_contacts;
using impact::detail::cloth::RelaxStats;

// Positions along one axis per vertex; a constraint's gap is sum_j a_j x_j (n = +x).
struct RelaxSystem {
  std::vector<double> x, w;
  std::vector<ZoneConstraint> set;
};

double relax_gap(const RelaxSystem& s, const ZoneConstraint& k) {
  double g = 0;
  for (int j = 0; j < k.count; ++j) g += k.a[j] * k.n.x() * s.x[static_cast<std::size_t>(k.v[j])];
  return g;
}

// An inelastic impulse meeting the constraint exactly; the movable vertices move.
bool relax_apply(RelaxSystem& s, const ZoneConstraint& k) {
  const double g = relax_gap(s, k);
  if (g >= k.b) return false;
  double denom = 0;
  for (int j = 0; j < k.count; ++j) denom += k.a[j] * k.a[j] * s.w[static_cast<std::size_t>(k.v[j])];
  if (!(denom > 0)) return false;
  const double lam = (k.b - g) / denom;
  for (int j = 0; j < k.count; ++j) s.x[static_cast<std::size_t>(k.v[j])] += s.w[static_cast<std::size_t>(k.v[j])] * k.a[j] * k.n.x() * lam;
  return true;
}

// The library's side of an impulse: the movable vertices move by w_j a_j dl along n.
void relax_move(RelaxSystem& s, const ZoneConstraint& k, double dl) {
  for (int j = 0; j < k.count; ++j) s.x[static_cast<std::size_t>(k.v[j])] += s.w[static_cast<std::size_t>(k.v[j])] * k.a[j] * k.n.x() * dl;
}

// The reference: pending flags, every impulse lists the constraints through its movable vertices
// that are not pending; each round's list sorted.
RelaxStats relax_reference(RelaxSystem& s, double tol, int max_rounds, std::vector<std::uint8_t>& acted, std::vector<std::uint32_t>& order) {
  RelaxStats r;
  const std::size_t m = s.set.size(), nv = s.w.size();
  if (m == 0 || max_rounds <= 0) return r;
  std::vector<std::vector<std::uint32_t>> through(nv);
  for (std::size_t c = 0; c < m; ++c)
    for (int j = 0; j < s.set[c].count; ++j)
      if (s.w[static_cast<std::size_t>(s.set[c].v[j])] > 0) through[static_cast<std::size_t>(s.set[c].v[j])].push_back(static_cast<std::uint32_t>(c));
  std::vector<std::uint32_t> cur(m), next;
  std::iota(cur.begin(), cur.end(), 0u);
  std::vector<std::uint8_t> pending(m, 1);
  while (r.rounds < max_rounds && !cur.empty()) {
    ++r.rounds;
    next.clear();
    for (const auto c : cur) {
      pending[c] = 0;
      const ZoneConstraint& k = s.set[c];
      if (k.b - relax_gap(s, k) <= tol) continue;
      if (!relax_apply(s, k)) continue;
      order.push_back(c);  // the impulses, in order
      ++r.impulses;
      acted[c] = 1;
      for (int j = 0; j < k.count; ++j) {
        if (!(s.w[static_cast<std::size_t>(k.v[j])] > 0)) continue;
        for (const auto q : through[static_cast<std::size_t>(k.v[j])])
          if (q != c && !pending[q]) pending[q] = 1, next.push_back(q);
      }
    }
    std::sort(next.begin(), next.end());
    std::swap(cur, next);
  }
  r.converged = cur.empty();
  return r;
}

void expect_same_relaxation(const RelaxSystem& start, double tol, int rounds) {
  RelaxSystem a = start, b = start;
  std::vector<std::uint8_t> acted_a(start.set.size(), 0), acted_b(start.set.size(), 0);
  std::vector<std::uint32_t> order_a, order_b;
  const RelaxStats ra = relax_reference(a, tol, rounds, acted_a, order_a);
  const RelaxStats rb = relax_contacts(
      b.set, b.w, tol, rounds, [&](const ZoneConstraint& k) { return relax_gap(b, k); },
      [&](const ZoneConstraint& k, double dl, double) {
        order_b.push_back(static_cast<std::uint32_t>(&k - b.set.data()));
        relax_move(b, k, dl);
        return true;
      },
      &acted_b);
  EXPECT_EQ(ra.rounds, rb.rounds);
  EXPECT_EQ(ra.impulses, rb.impulses);
  EXPECT_EQ(ra.converged, rb.converged);
  EXPECT_EQ(acted_a, acted_b);
  EXPECT_EQ(order_a, order_b);  // the same constraints reach the impulse, in the same order
  EXPECT_EQ(a.x, b.x);          // so bit for bit the same positions
}

// Random contact sets: n vertices (a share pinned), m constraints of 2-4 vertices with random
// weights of both signs, bounds above the current gaps (all start short).
RelaxSystem random_relax_system(std::mt19937& rng, int n, int m, int dup_every) {
  RelaxSystem s;
  std::uniform_real_distribution<double> u(-1, 1), pos(0, 1);
  std::uniform_int_distribution<int> vi(0, n - 1), cnt(2, 4);
  s.x.resize(static_cast<std::size_t>(n));
  s.w.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    s.x[std::size_t(i)] = u(rng);
    s.w[std::size_t(i)] = pos(rng) < 0.15 ? 0.0 : 0.5 + pos(rng);
  }
  for (int c = 0; c < m; ++c) {
    if (dup_every > 0 && c > 0 && c % dup_every == 0) {
      s.set.push_back(s.set[std::size_t(c - 1)]);
      continue;
    }
    ZoneConstraint k;
    k.count = cnt(rng);
    std::vector<int> vs;
    while (int(vs.size()) < k.count) {
      const int v = vi(rng);
      if (std::find(vs.begin(), vs.end(), v) == vs.end()) vs.push_back(v);
    }
    for (int j = 0; j < k.count; ++j) k.v[j] = vs[std::size_t(j)], k.a[j] = u(rng);
    k.n = impact::Vec3<double>(pos(rng) < 0.5 ? 1.0 : -1.0, 0, 0);
    RelaxSystem probe;
    probe.x = s.x;
    k.b = relax_gap(probe, k) + 0.2 * pos(rng);
    s.set.push_back(k);
  }
  return s;
}

TEST(RelaxContacts, SameAsReferenceOnRandomContactSets) {
  std::mt19937 rng(20261203);
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 4 + trial % 40, m = 1 + (trial * 37) % 300;
    const RelaxSystem s = random_relax_system(rng, n, m, trial % 3 == 0 ? 7 : 0);
    for (const int rounds : {1, 2, 5, 500}) expect_same_relaxation(s, 1e-9, rounds);
  }
}

// A stack of K sheets of n vertices (a chain per column; each vertex against the two nearest of
// the layer below, an edge-like pair) over a floor of pinned vertices, every sheet 0.68 below
// where its constraints hold it (pulled down by gravity): each gap starts short.
RelaxSystem relax_stack(int K, int n) {
  RelaxSystem s;
  for (int v = 0; v < n; ++v) s.x.push_back(0.0), s.w.push_back(0.0);  // the floor
  for (int k = 1; k <= K; ++k)
    for (int v = 0; v < n; ++v) s.x.push_back(1.1 * k - 0.68), s.w.push_back(1.0);
  for (int k = 1; k <= K; ++k)
    for (int v = 0; v < n; ++v)
      for (int dv = 0; dv <= 1; ++dv) {
        const int lo = (k - 1) * n + std::min(n - 1, v + dv), hi = k * n + v;
        ZoneConstraint c;
        c.count = 2;
        c.v[0] = hi, c.v[1] = lo, c.a[0] = 1, c.a[1] = -1;
        c.n = impact::Vec3<double>(1, 0, 0);
        c.b = 1.1;
        s.set.push_back(c);
      }
  return s;
}

// The stack (relax_stack) of 10 sheets: the relaxation needs many rounds, most of them touching
// few constraints (the incidence path) and the first touching all (the scan).
TEST(RelaxContacts, SameAsReferenceOnAStackOnAFloor) {
  for (const int rounds : {3, 40, 2000}) {
    const RelaxSystem s = relax_stack(10, 30);
    expect_same_relaxation(s, 1e-6, rounds);
  }
}

}  // namespace
