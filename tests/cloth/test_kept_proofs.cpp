// SPDX-License-Identifier: MIT
// proof_key / proof_holds (cloth/detail/kept_proofs.hpp), the rule by which a candidate's proof
// survives later moves of its vertices' end positions within a step: checked on static pairs
// (x1 = x0, so the step's distance is the pair's distance) whose vertices then move, against the
// moved pair's distance from closest points. A side translated towards the other along the
// pair's normal loses exactly its move, so a rule that keeps a proof whose vertices moved beyond
// its slack leaves a pair closer than `need` here, and the test fails.
#include "impact/cloth/detail/kept_proofs.hpp"
#include "impact/narrow/closest_point.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

namespace {

using impact::Segment;
using impact::Triangle;
using impact::Vec3;
using impact::detail::cloth::proof_holds;
using impact::detail::cloth::proof_key;

using Quad = std::array<Vec3<double>, 4>;

// Distance and unit normal (from the second primitive towards the first) of a static pair: the
// vertex 0 against the face 1-2-3, or the edge 0-1 against the edge 2-3.
double pair_distance(const Quad& x, bool ee, Vec3<double>* n = nullptr) {
  Vec3<double> d;
  if (ee) {
    const auto r = impact::closest_points_segment_segment(Segment<double>(x[0], x[1]), Segment<double>(x[2], x[3]));
    d = ((1 - r.s) * x[0] + r.s * x[1]) - ((1 - r.t) * x[2] + r.t * x[3]);
  } else {
    d = x[0] - impact::closest_point_on_triangle(x[0], Triangle<double>(x[1], x[2], x[3])).point;
  }
  if (n) *n = d.normalized();
  return d.norm();
}

TEST(ClothKeptProofs, VertexAboveFace) {
  // A vertex 3 above a face in z = 0 (a static step: distance 3 throughout), need = 1: slack 2.
  const Quad x = {Vec3<double>(0.1, 0.1, 3), Vec3<double>(-2, -2, 0), Vec3<double>(2, -2, 0), Vec3<double>(0, 2, 0)};
  const double need = 1, slack = pair_distance(x, false) - need;
  ASSERT_DOUBLE_EQ(slack, 2.0);
  const double before = 0.37 + 1.5 + 0.25 + 4;  // the four path lengths at the proof
  const double key = proof_key(before, slack);
  auto moved = [&](double a, double b) {  // the vertex down by a, the face up by b
    Quad y = x;
    y[0].z() -= a;
    for (int k = 1; k < 4; ++k) y[k].z() += b;
    return pair_distance(y, false);
  };
  // The vertex by 1.8 and one face vertex by 0.1: kept, and the pair stays >= need apart.
  EXPECT_TRUE(proof_holds(before + 1.8 + 0.1, key));
  EXPECT_GE(moved(1.8, 0), need);
  // The vertex by more than the slack: dropped (it is then closer than need).
  EXPECT_FALSE(proof_holds(before + 2.001, key));
  EXPECT_LT(moved(2.001, 0), need);
  // Vertex and face by 0.5 each (2 in the sum of the four): kept; the pair loses only 1 (the
  // face's three moves count once), so the rule is conservative there.
  EXPECT_TRUE(proof_holds(before + 0.5 + 3 * 0.5 - 1e-9, key));
  EXPECT_DOUBLE_EQ(moved(0.5, 0.5), 2.0);
  EXPECT_FALSE(proof_holds(before + 0.6 + 3 * 0.5, key));
  // No proof (key -1) never holds.
  EXPECT_FALSE(proof_holds(0.0, -1.0));
}

// Random static pairs (vertex-face and edge-edge), random path lengths before the proof (up to
// 10^3 times the pair's size, so that the rounding margins matter), random moves. Translations of
// each side towards the other along the pair's normal, the moves summed over the four vertices
// as their path growth: the proof is kept iff that sum is within the slack (away from the
// boundary), and a kept proof leaves the pair at least need apart. Then random moves of each
// vertex in a random direction: every kept proof leaves the pair at least need apart.
TEST(ClothKeptProofs, KeptProofsLeaveThePairApart) {
  std::mt19937_64 rng(20261204);
  std::uniform_real_distribution<double> unit(0, 1), coord(-1, 1);
  int kept = 0, dropped = 0, kept_random = 0;
  for (int it = 0; it < 4000; ++it) {
    const bool ee = it % 2 == 1;
    const int split = ee ? 2 : 1;
    Quad x;
    for (auto& p : x) p = Vec3<double>(coord(rng), coord(rng), coord(rng));
    for (int k = 0; k < split; ++k) x[std::size_t(k)].z() += 0.2 + 2 * unit(rng);
    Vec3<double> n;
    const double L = pair_distance(x, ee, &n);
    if (!(L > 1e-3)) continue;
    const double need = L * (0.2 + 0.7 * unit(rng)), slack = L - need;
    double before = 0;
    for (int k = 0; k < 4; ++k) before += 1e3 * unit(rng);
    const double key = proof_key(before, slack);
    // translations: each side by its own length, in all below L
    const double ga = 0.3 * L * unit(rng), gb = 0.2 * L * unit(rng);
    Quad y = x;
    for (int k = 0; k < 4; ++k) y[std::size_t(k)] += (k < split ? -ga : gb) * n;
    const double growth = split * ga + (4 - split) * gb;
    const bool keep = proof_holds(before + growth, key);
    if (std::abs(growth - slack) > 1e-9 * (before + L)) {
      EXPECT_EQ(keep, growth <= slack) << "it " << it;
    }
    if (keep) {
      EXPECT_GE(pair_distance(y, ee), need * (1 - 1e-12)) << "it " << it << " L " << L << " need " << need;
    }
    (keep ? kept : dropped)++;
    // random moves, each vertex its own length and direction
    Quad z = x;
    double sum = 0;
    for (int k = 0; k < 4; ++k) {
      const double g = 0.5 * slack * unit(rng);
      z[std::size_t(k)] += g * Vec3<double>(coord(rng), coord(rng), coord(rng)).normalized();
      sum += g;
    }
    if (proof_holds(before + sum, key)) {
      ++kept_random;
      EXPECT_GE(pair_distance(z, ee), need * (1 - 1e-12)) << "it " << it;
    }
  }
  EXPECT_GT(kept, 500);
  EXPECT_GT(dropped, 500);
  EXPECT_GT(kept_random, 500);
}

}  // namespace
