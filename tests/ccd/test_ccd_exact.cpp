// SPDX-License-Identifier: MIT
// Generated and adversarial CCD queries with exact ground truth, in float and double:
//  - constructed contacts (exact by construction: all positions are integers and the contact
//    point is an exact dyadic combination at a dyadic time t*), covering the traps: coplanar
//    motion (axis plane and tilted plane), parallel and collinear edges, shared vertices,
//    zero-length edges, degenerate triangles, zero motion, grazing contacts at a corner or an edge
//    (a double root of the coplanarity cubic: 0 vs 2 roots), contacts on the boundary, and
//    near-touching contacts at coordinate scale 2^-50 (about 1e-15). The test must report a hit
//    with toi <= t*;
//  - random small-integer queries (full of exact degeneracies) and near-touching perturbations of
//    the contacts: whenever the test answers "no hit", the exact reference (support/exact_ccd.hpp)
//    must prove that there is no contact. False positives the reference proves are counted and
//    bounded by the counts measured with these seeds (0 random, 16 and 22 perturbed; see random_queries).
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "support/exact_ccd.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <utility>

#include "support/sanitizer.hpp"

namespace {

// Sanitizer builds (CI runs ASan + UBSan) are about 10x slower: run a quarter of the queries.
constexpr int kCountDivisor = IMPACT_TEST_SANITIZED ? 4 : 1;

using impact::test::ExactAnswer;
using impact::test::IntCcdQuery;
using IV = std::array<std::int64_t, 3>;

IV add(IV a, const IV& b) {
  for (int i = 0; i < 3; ++i) a[std::size_t(i)] += b[std::size_t(i)];
  return a;
}
IV sub(IV a, const IV& b) {
  for (int i = 0; i < 3; ++i) a[std::size_t(i)] -= b[std::size_t(i)];
  return a;
}
IV mul(IV a, std::int64_t m) {
  for (auto& x : a) x *= m;
  return a;
}
IV divexact(IV a, std::int64_t m) {
  for (auto& x : a) {
    EXPECT_EQ(x % m, 0);
    x /= m;
  }
  return a;
}

/// A query with a known contact at t* = tnum / 16.
struct Constructed {
  IntCcdQuery q;
  std::int64_t tnum = 0;  ///< contact at tnum / 16
  std::vector<IV> directions;
  const char* trap = "";
  bool interior = false;  ///< the contact is inside the parameter domain, not on its boundary
};

enum class Trap {
  Generic,
  CoplanarAxis,
  CoplanarTilted,
  Degenerate,
  Shared,
  ZeroMotion,
  Boundary,
  Grazing,
  Parallel,
  ZeroLength,
  Count
};

const char* trap_name(Trap t) {
  static const char* names[] = {"generic",     "coplanar-axis", "coplanar-tilted", "degenerate", "shared",
                                "zero-motion", "boundary",      "grazing",         "parallel",   "zero-length"};
  return names[int(t)];
}

class Generator {
 public:
  Generator(std::uint64_t seed, std::int64_t range) : rng_(seed), range_(range) {}

  std::int64_t rint(std::int64_t lo, std::int64_t hi) { return std::uniform_int_distribution<std::int64_t>(lo, hi)(rng_); }
  /// Random integer vector, each coordinate a multiple of 16 in [-range, range].
  IV rv() {
    return {16 * rint(-range_ / 16, range_ / 16), 16 * rint(-range_ / 16, range_ / 16), 16 * rint(-range_ / 16, range_ / 16)};
  }
  IV small(std::int64_t r) { return {rint(-r, r), rint(-r, r), rint(-r, r)}; }

  /// Positions `at` (the 4 points at time t* = tnum/16) and velocities w: start = at - t* w,
  /// end = at + (1 - t*) w. Velocities are multiples of 16 so that everything stays integer.
  static IntCcdQuery from_motion(const IV (&at)[4], const IV (&w)[4], std::int64_t tnum, bool vf) {
    IntCcdQuery q;
    q.vertex_face = vf;
    for (std::size_t k = 0; k < 4; ++k) {
      q.points[k] = sub(at[k], divexact(mul(w[k], tnum), 16));
      q.points[k + 4] = add(at[k], divexact(mul(w[k], 16 - tnum), 16));
    }
    return q;
  }

  Constructed vertex_face(Trap trap) {
    Constructed c;
    c.trap = trap_name(trap);
    c.tnum = rint(0, 16);
    IV at[4], w[4];
    for (int k = 1; k < 4; ++k) at[k] = mul(rv(), 8);
    for (auto& x : w) x = mul(rv(), 2);
    std::int64_t a = rint(0, 8), b = rint(0, 8 - a);
    IV plane_b1{0, 0, 0}, plane_b2{0, 0, 0};
    switch (trap) {
      case Trap::CoplanarAxis:
        for (int k = 0; k < 4; ++k) at[k][2] = w[k][2] = 0;
        c.directions.push_back({0, 0, 1});
        break;
      case Trap::CoplanarTilted: {
        const IV n = {rint(1, 3), rint(-3, 3), rint(1, 3)};
        // Two integer vectors orthogonal to n span the plane through the origin.
        plane_b1 = {n[1], -n[0], 0};
        plane_b2 = {n[0] * n[2], n[1] * n[2], -(n[0] * n[0] + n[1] * n[1])};
        auto in_plane = [&](std::int64_t s) { return add(mul(plane_b1, s * rint(-8, 8)), mul(plane_b2, s * rint(-8, 8))); };
        for (int k = 1; k < 4; ++k) at[k] = in_plane(128);
        for (auto& x : w) x = in_plane(16);
        c.directions.push_back(n);
        break;
      }
      case Trap::Degenerate:
        if (rint(0, 1)) {  // collinear triangle for all t
          at[3] = sub(mul(at[2], 2), at[1]);
          w[3] = sub(mul(w[2], 2), w[1]);
        } else {  // two coincident vertices for all t
          at[2] = at[1];
          w[2] = w[1];
        }
        break;
      case Trap::Shared:  // the vertex is a vertex of the triangle for all t
        a = b = 0;
        w[0] = w[1];
        break;
      case Trap::ZeroMotion:
        for (auto& x : w) x = {0, 0, 0};
        break;
      case Trap::Boundary: {
        const int which = int(rint(0, 2));
        if (which == 0)
          b = 8 - a;  // on edge f1-f2
        else if (which == 1)
          a = 0;  // on edge f0-f2
        else
          b = 0;  // on edge f0-f1
        break;
      }
      case Trap::Grazing: {
        // Coplanar (z = 0) triangle f0 = 0, f1 = s x, f2 = s y, static; the point moves along a
        // line that touches the triangle only at the corner f1 (t*) or only at f0.
        const std::int64_t s = 16 * rint(1, range_ / 16);
        at[1] = {0, 0, 0};
        at[2] = {s, 0, 0};
        at[3] = {0, s, 0};
        for (int k = 1; k < 4; ++k) w[k] = {0, 0, 0};
        const std::int64_t sp = 16 * rint(1, 8);
        if (rint(0, 1)) {
          a = 8, b = 0;  // at f1 = (s, 0, 0), moving along (1, 1): outside before and after
          w[0] = {sp, sp, 0};
        } else {
          a = b = 0;  // at f0, moving along (1, -1) and crossing the plane: z changes
          w[0] = {sp, -sp, sp};
        }
        break;
      }
      default:
        break;
    }
    // at[0] = f0 + (a (f1 - f0) + b (f2 - f0)) / 8; positions are multiples of 128 so this is exact.
    at[0] = add(at[1], divexact(add(mul(sub(at[2], at[1]), a), mul(sub(at[3], at[1]), b)), 8));
    c.q = from_motion(at, w, c.tnum, true);
    c.interior = c.tnum > 0 && c.tnum < 16 && a > 0 && b > 0 && a + b < 8;
    return c;
  }

  Constructed edge_edge(Trap trap) {
    Constructed c;
    c.trap = trap_name(trap);
    c.tnum = rint(0, 16);
    IV at[4], w[4];
    at[0] = mul(rv(), 8);
    at[1] = mul(rv(), 8);
    for (auto& x : w) x = mul(rv(), 2);
    std::int64_t a = rint(0, 8);
    switch (trap) {
      case Trap::CoplanarAxis:
        at[0][2] = at[1][2] = 0;
        for (auto& x : w) x[2] = 0;
        c.directions.push_back({0, 0, 1});
        break;
      case Trap::Parallel:
        break;  // handled below
      case Trap::Shared:
        a = 0;
        w[2] = w[0];
        break;
      case Trap::ZeroLength:
        at[1] = at[0];
        w[1] = w[0];
        break;
      case Trap::ZeroMotion:
        for (auto& x : w) x = {0, 0, 0};
        break;
      case Trap::Boundary:
        a = rint(0, 1) ? 0 : 8;
        break;
      default:
        break;
    }
    const IV P = add(at[0], divexact(mul(sub(at[1], at[0]), a), 8));
    if (trap == Trap::Parallel) {
      // Edge b on the line of edge a at t*, overlapping it at P; translating edges stay parallel.
      const IV dir = divexact(sub(at[1], at[0]), 8);
      at[2] = add(P, mul(dir, rint(-8, 0)));
      at[3] = add(P, mul(dir, rint(0, 8)));
      if (rint(0, 1)) {
        w[1] = w[0];
        w[3] = w[2];
      }
    } else if (trap == Trap::Shared) {
      at[2] = at[0];
      at[3] = mul(rv(), 8);
    } else if (trap == Trap::ZeroLength && rint(0, 1)) {
      at[2] = P;  // both edges degenerate and coincident at t*
      at[3] = P;
      w[3] = w[2];
    } else {
      // b0 random, b1 = b0 + 2 (P - b0) (contact at v = 1/2), or P at an end point.
      at[2] = mul(rv(), 8);
      if (trap == Trap::CoplanarAxis) at[2][2] = 0;
      const int which = trap == Trap::Boundary ? int(rint(1, 2)) : int(rint(0, 2));
      c.interior = c.tnum > 0 && c.tnum < 16 && a > 0 && a < 8 && which == 0;
      if (which == 0)
        at[3] = sub(mul(P, 2), at[2]);
      else if (which == 1)
        at[3] = P;
      else {
        at[3] = at[2];
        at[2] = P;
      }
    }
    c.q = from_motion(at, w, c.tnum, false);
    return c;
  }

 private:
  std::mt19937_64 rng_;
  std::int64_t range_;
};

/// The query in scalar S, scaled by 2^-shift; checks the conversion is exact.
template <class S>
std::array<impact::Vec3<S>, 8> to_points(const IntCcdQuery& q, int shift) {
  std::array<impact::Vec3<S>, 8> p;
  for (std::size_t k = 0; k < 8; ++k)
    for (std::size_t i = 0; i < 3; ++i) {
      const S x = static_cast<S>(std::ldexp(static_cast<double>(q.points[k][i]), -shift));
      EXPECT_EQ(std::ldexp(static_cast<long double>(x), shift), static_cast<long double>(q.points[k][i])) << "inexact conversion";
      p[k][int(i)] = x;
    }
  return p;
}

template <class S>
impact::CcdResult<S> run(const IntCcdQuery& q, int shift, const impact::CcdOptions& o = {}) {
  const auto p = to_points<S>(q, shift);
  if (q.vertex_face) return impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
  return impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
}

/// The contact proof of the hit check (detail/contact_proof.hpp) from the hit of the search
/// without re-check; false when that search reports no hit.
template <class S> bool proves_contact(const IntCcdQuery& q, int shift) {
  impact::CcdOptions plain;
  plain.recheck_iterations = 0;
  const auto r = run<S>(q, shift, plain);
  if (!r.hit) return false;
  const auto p = to_points<S>(q, shift);
  double a[4][3], b[4][3];
  impact::detail::ccd_load(p[0], p[1], p[2], p[3], a);
  impact::detail::ccd_load(p[4], p[5], p[6], p[7], b);
  if (q.vertex_face) return impact::detail::ccd_prove_contact<true>(a, b, plain, r.toi, r.u, r.v);
  return impact::detail::ccd_prove_contact<false>(a, b, plain, r.toi, r.u, r.v);
}

std::string describe(const IntCcdQuery& q) {
  std::string s = q.vertex_face ? "vertex-face" : "edge-edge";
  for (const auto& p : q.points) s += " (" + std::to_string(p[0]) + "," + std::to_string(p[1]) + "," + std::to_string(p[2]) + ")";
  return s;
}

/// Constructed contacts: hit with toi <= t*. `range` bounds the integer coordinates, `shift`
/// scales them into S (float needs range < 2^24).
template <class S>
void constructed_contacts(std::int64_t range, int shift, int per_trap, std::uint64_t seed) {
  Generator g(seed, range);
  const Trap vf_traps[] = {Trap::Generic, Trap::CoplanarAxis, Trap::CoplanarTilted, Trap::Degenerate,
                           Trap::Shared,  Trap::ZeroMotion,   Trap::Boundary,       Trap::Grazing};
  const Trap ee_traps[] = {Trap::Generic,    Trap::CoplanarAxis, Trap::Parallel, Trap::Shared,
                           Trap::ZeroLength, Trap::ZeroMotion,   Trap::Boundary};
  int checked = 0, generic = 0, proved = 0;
  per_trap = std::max(1, per_trap / kCountDivisor);
  for (int vf = 0; vf < 2; ++vf)
    for (const Trap t : vf ? std::vector<Trap>(std::begin(vf_traps), std::end(vf_traps))
                           : std::vector<Trap>(std::begin(ee_traps), std::end(ee_traps)))
      for (int i = 0; i < per_trap; ++i) {
        const Constructed c = vf ? g.vertex_face(t) : g.edge_edge(t);
        // The construction is exact: F vanishes at (t*, u*, v*) (checked through the reference
        // on the time alone: the exact search must not be able to exclude the contact).
        const auto r = run<S>(c.q, shift);
        const double tstar = double(c.tnum) / 16.0;
        ASSERT_TRUE(r.hit) << "missed contact, trap " << c.trap << ": " << describe(c.q);
        ASSERT_LE(double(r.toi), tstar) << "toi later than the contact, trap " << c.trap << ": " << describe(c.q);
        ++checked;
        if (t == Trap::Generic && c.interior) {
          ++generic;
          proved += proves_contact<S>(c.q, shift);
        }
      }
  EXPECT_GT(checked, 0);
  // Generic contacts inside the domain are transversal (simple roots of F): the contact proof
  // settles them, so that their hits skip the re-check.
  std::printf("[exact] constructed generic contacts inside the domain: %d of %d proved\n", proved, generic);
  EXPECT_GT(generic, 0);
  EXPECT_EQ(proved, generic);
}

TEST(CcdExact, ConstructedContactsDouble) { constructed_contacts<double>(1 << 12, 10, 300, 1); }
TEST(CcdExact, ConstructedContactsFloat) { constructed_contacts<float>(1 << 12, 10, 300, 2); }
// Coordinates up to 2^52 scaled by 2^-50: contacts resolved at about 1e-15.
TEST(CcdExact, ConstructedContactsFineScaleDouble) { constructed_contacts<double>(std::int64_t(1) << 45, 50, 150, 3); }
// Coordinates up to 2^20 (float has 24 bits) scaled by 2^-20.
TEST(CcdExact, ConstructedContactsFineScaleFloat) { constructed_contacts<float>(std::int64_t(1) << 16, 20, 150, 4); }

TEST(CcdExact, ConstructionIsExact) {
  // Sanity check of the generator: the contact is exactly at t* with dyadic (u, v) for a few
  // generic cases (found by scanning u, v over multiples of 1/8, the construction's grid).
  Generator g(7, 1 << 10);
  for (int i = 0; i < 50; ++i) {
    const Constructed c = g.vertex_face(Trap::Generic);
    bool found = false;
    for (std::int64_t u = 0; u <= 8 && !found; ++u)
      for (std::int64_t v = 0; v + u <= 8 && !found; ++v) found = impact::test::exact_contact_at(c.q, c.tnum, 4, u, 3, v, 3);
    EXPECT_TRUE(found) << describe(c.q);
  }
}

/// Random queries (and perturbed contacts): every "no hit" must be proven by the reference, and at
/// most `max_proven_fp` hits may be false positives the reference proves contact-free (the counts
/// measured with these seeds: 0 for random queries, 16 (double) and 22 (float) for perturbed
/// contacts, whose gaps of one unit at 2^-50 are near misses the re-check's budget cannot always
/// separate. The counts grow as the reference gets better at proving near misses: 2 and 2 before
/// it searched the triangle as a collapsed square and split along its most promising direction).
template <class S>
void random_queries(std::int64_t range, int shift, int count, std::uint64_t seed, bool perturb_contacts, int max_proven_fp) {
  Generator g(seed, range);
  count = std::max(2, count / kCountDivisor);
  int no_hit = 0, hits = 0, proven_fp = 0, proofs = 0;
  for (int i = 0; i < count; ++i) {
    const bool vf = i % 2 == 0;
    IntCcdQuery q;
    std::vector<IV> dirs;
    if (perturb_contacts) {
      // A contact moved by one unit (2^-shift) along a random axis: touching within an ulp-scale gap.
      const int trap_count = vf ? 8 : 7;
      const Trap vf_traps[] = {Trap::Generic, Trap::CoplanarAxis, Trap::CoplanarTilted, Trap::Degenerate,
                               Trap::Shared,  Trap::ZeroMotion,   Trap::Boundary,       Trap::Grazing};
      const Trap ee_traps[] = {Trap::Generic,    Trap::CoplanarAxis, Trap::Parallel, Trap::Shared,
                               Trap::ZeroLength, Trap::ZeroMotion,   Trap::Boundary};
      const Trap t = vf ? vf_traps[g.rint(0, trap_count - 1)] : ee_traps[g.rint(0, trap_count - 1)];
      Constructed c = vf ? g.vertex_face(t) : g.edge_edge(t);
      q = c.q;
      dirs = std::move(c.directions);
      const std::size_t k = std::size_t(g.rint(0, 7)), ax = std::size_t(g.rint(0, 2));
      q.points[k][ax] += g.rint(0, 1) ? 1 : -1;
      if (g.rint(0, 1)) q.points[(k + 4) % 8][ax] += g.rint(-1, 1);
    } else {
      q.vertex_face = vf;
      for (auto& p : q.points) p = g.small(range);
    }
    const auto r = run<S>(q, shift);
    if (!r.hit) {
      ++no_hit;
      const auto proof = impact::test::certify_no_contact(q, dirs, 2000000);
      ASSERT_EQ(proof, ExactAnswer::NoContact)
          << "no hit reported but the exact reference cannot exclude a contact: " << describe(q);
    } else {
      ++hits;
      if (impact::test::certify_no_contact(q, dirs, 400) == ExactAnswer::NoContact) ++proven_fp;
    }
    // A contact proof must never be given for a query the reference proves contact-free.
    if (proves_contact<S>(q, shift)) {
      ++proofs;
      ASSERT_NE(impact::test::certify_no_contact(q, dirs, 200000), ExactAnswer::NoContact)
          << "contact proved for a contact-free query: " << describe(q);
    }
  }
  std::printf("[exact] %s: %d queries, %d no-hit (all proven), %d hits of which %d proven false positives, %d proved contacts\n",
              perturb_contacts ? "perturbed contacts" : "random", count, no_hit, hits, proven_fp, proofs);
  ::testing::Test::RecordProperty("proven_false_positives", proven_fp);
  EXPECT_LE(proven_fp, max_proven_fp);
  EXPECT_GT(hits, 0);
}

// The reference must prove quickly that a point just past the face's edge f1-f2 misses it, and
// must not exclude the same point moved onto that edge. When the reference searched (t, u, v),
// each of the misses took ~10^6 boxes (one took 52 s in a fuzz build: the CI timeout of fuzz-ccd,
// input regressions/ccd/double-point-past-degenerate-face-edge-slow-proof).
TEST(CcdExact, ReferenceProvesPointsPastTheSlantedEdge) {
  const std::int64_t r = std::int64_t(1) << 19;
  // A triangle at rest in z = 0; the point starts in its plane, `past` units beyond the edge f1-f2
  // along x, and leaves along z.
  auto flat = [&](std::int64_t past) {
    IntCcdQuery q;
    q.points = {IV{r / 2 + past, r / 2, 0}, IV{0, 0, 0}, IV{r, 0, 0}, IV{0, r, 0},
                IV{r / 2 + past, r / 2, r}, IV{0, 0, 0}, IV{r, 0, 0}, IV{0, r, 0}};
    return q;
  };
  // The fuzz input: a degenerate face (f1 = f2 throughout) and a point one unit past f1 on the
  // line f0-f1 at t = 0; everything then moves apart.
  auto degenerate = [&](std::int64_t past) {
    IntCcdQuery q;
    const std::int64_t a = -121916, b = -524288;
    q.points = {IV{a - past, a, a}, IV{-78652, a, a}, IV{a, a, a}, IV{a, a, a},
                IV{a, -177143, -128509}, IV{b, b, b}, IV{b, b, b}, IV{b, b, b}};
    return q;
  };
  // The face's vertices in every order: the coincident pair as f1 f2, f0 f1 and f0 f2 (the search
  // reorders them; the contact on the edge must survive every order).
  auto rotated = [](IntCcdQuery q, int turns) {
    for (int k = 0; k < turns; ++k)
      for (std::size_t e = 0; e < 8; e += 4) std::rotate(&q.points[1 + e], &q.points[2 + e], &q.points[4 + e]);
    return q;
  };
  for (const std::int64_t past : {1, 2, 3}) {
    EXPECT_EQ(impact::test::certify_no_contact(flat(past), {}, 20000), ExactAnswer::NoContact) << past;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(impact::test::certify_no_contact(rotated(degenerate(past), k), {}, 20000), ExactAnswer::NoContact) << past << " " << k;
    }
  }
  // On the edge: a contact at t = 0 that no budget may exclude.
  EXPECT_EQ(impact::test::certify_no_contact(flat(0), {}, 20000), ExactAnswer::Unknown);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(impact::test::certify_no_contact(rotated(degenerate(0), k), {}, 20000), ExactAnswer::Unknown) << k;
  }
  EXPECT_TRUE(impact::test::exact_contact_at(flat(0), 0, 0, 1, 1, 1, 1));
  EXPECT_TRUE(impact::test::exact_contact_at(degenerate(0), 0, 0, 1, 0, 0, 0));
}

TEST(CcdExact, RandomSmallIntegersDouble) { random_queries<double>(3, 0, 4000, 11, false, 0); }
TEST(CcdExact, RandomSmallIntegersFloat) { random_queries<float>(3, 0, 4000, 12, false, 0); }
TEST(CcdExact, RandomWiderIntegersDouble) { random_queries<double>(1000, 8, 4000, 13, false, 0); }
TEST(CcdExact, PerturbedContactsDouble) { random_queries<double>(std::int64_t(1) << 45, 50, 1500, 14, true, 16); }
TEST(CcdExact, PerturbedContactsFloat) { random_queries<float>(std::int64_t(1) << 16, 20, 1500, 15, true, 22); }

}  // namespace
