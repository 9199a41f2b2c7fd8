// SPDX-License-Identifier: MIT
// split_direction_bound (cloth/detail/hull_proofs.hpp): the separating-direction proof that a
// moving vertex-face or edge-edge pair stays farther than `need` apart, on the pieces of a
// bisection of the step. Checked against the pair's distance from closest points at many times
// of the step (an upper bound on its smallest distance): a proof may never claim more than a
// sampled distance, and a pair sampled closer than `need` must never be proved apart. The
// sliding pairs below are proved only on pieces of the step and only by their directions (the
// relative-motion bound switched off with m = infinity), so a wrong piece (wrong midpoint
// positions, a piece skipped, a direction not from its piece's ends) is caught.
#include "impact/cloth/detail/hull_proofs.hpp"
#include "impact/narrow/closest_point.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

namespace {

using impact::Segment;
using impact::Triangle;
using impact::Vec3;
using impact::detail::cloth::PairSample;
using impact::detail::cloth::split_direction_bound;

using Quad = std::array<Vec3<double>, 4>;

// Distance and direction (second primitive's closest point to the first's) of the pair at
// positions x (vertex 0 against face 1-2-3, or edge 0-1 against edge 2-3), from closest points.
PairSample sample_of(const Vec3<double>* x, bool ee) {
  Vec3<double> d;
  if (ee) {
    const auto r = impact::closest_points_segment_segment(Segment<double>(x[0], x[1]), Segment<double>(x[2], x[3]));
    d = ((1 - r.s) * x[0] + r.s * x[1]) - ((1 - r.t) * x[2] + r.t * x[3]);
  } else {
    d = x[0] - impact::closest_point_on_triangle(x[0], Triangle<double>(x[1], x[2], x[3])).point;
  }
  PairSample s;
  s.dist = d.norm();
  if (s.dist > 0) s.n = d / s.dist;
  return s;
}

double distance_at(const Quad& x0, const Quad& x1, bool ee, double t) {
  Quad x;
  for (int k = 0; k < 4; ++k) x[std::size_t(k)] = (1 - t) * x0[std::size_t(k)] + t * x1[std::size_t(k)];
  return sample_of(x.data(), ee).dist;
}

// The smallest sampled distance over the step (1,001 times): at least the pair's true smallest.
double sampled_min(const Quad& x0, const Quad& x1, bool ee) {
  double m = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= 1000; ++k) m = std::min(m, distance_at(x0, x1, ee, k / 1000.0));
  return m;
}

// The largest relative displacement of a vertex of the first primitive against one of the
// second: the distance changes by at most that times the time between two samples.
double relative_motion(const Quad& x0, const Quad& x1, bool ee) {
  double m = 0;
  const int split = ee ? 2 : 1;
  for (int i = 0; i < split; ++i)
    for (int j = split; j < 4; ++j)
      m = std::max(m, ((x1[std::size_t(i)] - x0[std::size_t(i)]) - (x1[std::size_t(j)] - x0[std::size_t(j)])).norm());
  return m;
}

// The proof with the pair's own relative motion, or with directions alone (m = infinity).
double bound(const Quad& x0, const Quad& x1, bool ee, double need, int depth, bool directions_only = false) {
  const double m = directions_only ? std::numeric_limits<double>::infinity() : relative_motion(x0, x1, ee);
  return split_direction_bound(x0.data(), x1.data(), ee, need, m, depth, sample_of(x0.data(), ee), sample_of(x1.data(), ee),
                               [&](double, const Vec3<double>* x) { return sample_of(x, ee); });
}

TEST(ClothHullProofs, SlidingVertexOverTiltingFaceNeedsPieces) {
  // A vertex slides 6 units along x at height 1.3 over a face that tilts by 0.4 about the x axis
  // and back in z (its far corner rises): the pair stays above 1 throughout, but no single
  // direction separates the start and end offsets by 1 over the whole step.
  const Quad x0 = {Vec3<double>(-3, 0, 1.3), Vec3<double>(-4, -3, 0), Vec3<double>(4, -3, 0), Vec3<double>(0, 3, 0)};
  const Quad x1 = {Vec3<double>(3, 0.2, 1.3), Vec3<double>(-4, -3, -0.6), Vec3<double>(4, -3, -0.6), Vec3<double>(0.5, 3, 0.6)};
  const double need = 1, truth = sampled_min(x0, x1, false);
  ASSERT_GT(truth, need);
  EXPECT_EQ(bound(x0, x1, false, need, 0, true), -std::numeric_limits<double>::infinity());
  const double b = bound(x0, x1, false, need, 4, true);
  EXPECT_GT(b, need);
  EXPECT_LE(b, truth);
}

TEST(ClothHullProofs, EdgeSlidingOverTiltingEdgeNeedsPieces) {
  // An edge along x at height 1.3 slides 4 along y over an edge along y that tilts (its ends go
  // to -0.9 and 0.9), towards the end that sinks: above 1 throughout, but the mean of the start
  // offsets to its far end and the end offsets to its sunk end is 0.85 from the origin.
  const Quad x0 = {Vec3<double>(-2, 2, 1.3), Vec3<double>(2, 2, 1.3), Vec3<double>(0, -3, 0), Vec3<double>(0, 3, 0)};
  const Quad x1 = {Vec3<double>(-2, -2, 1.3), Vec3<double>(2, -2, 1.3), Vec3<double>(0, -3, -0.9), Vec3<double>(0, 3, 0.9)};
  const double need = 1, truth = sampled_min(x0, x1, true);
  ASSERT_GT(truth, need);
  EXPECT_EQ(bound(x0, x1, true, need, 0, true), -std::numeric_limits<double>::infinity());
  const double b = bound(x0, x1, true, need, 5, true);
  EXPECT_GT(b, need);
  EXPECT_LE(b, truth);
}

TEST(ClothHullProofs, DipInTheMiddleIsNeverProved) {
  // The vertex passes 0.9 above the face's plane at mid-step, far above it at both ends: each
  // end alone is far apart, the middle is not.
  const Quad x0 = {Vec3<double>(-1, 0, 4), Vec3<double>(-1, -1, 0), Vec3<double>(1, -1, 0), Vec3<double>(0, 1, 0)};
  Quad x1 = x0;
  x1[0] = Vec3<double>(1, 0.1, -2.2);  // at t = 0.5: (0, 0.05, 0.9)
  const double need = 1;
  ASSERT_LT(sampled_min(x0, x1, false), need);
  for (int depth = 0; depth <= 8; ++depth) {
    EXPECT_EQ(bound(x0, x1, false, need, depth), -std::numeric_limits<double>::infinity()) << depth;
    EXPECT_EQ(bound(x0, x1, false, need, depth, true), -std::numeric_limits<double>::infinity()) << depth;
  }
}

TEST(ClothHullProofs, RandomMovingPairsAgainstSampledDistances) {
  // Random pairs sliding and turning near contact, vertex-face and edge-edge: a proof never
  // exceeds the sampled smallest distance (so never accepts a pair that comes closer than
  // need), and the bisection proves some that the whole step's directions do not.
  std::mt19937 rng(20261204);
  std::uniform_real_distribution<double> u(-1, 1);
  const double need = 1;
  int proved = 0, only_split = 0, close = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const bool ee = trial % 2 == 1;
    Quad x0, x1;
    // the first primitive at height z over the second, sliding by up to 3 sideways; the second
    // tilting (its end heights change with its position, by up to 0.3 per unit), both jittered
    const double z = 0.9 + 0.25 * (u(rng) + 1);
    const Vec3<double> slide(3 * u(rng), 3 * u(rng), 0.1 * u(rng));
    const double tx = 0.3 * u(rng), ty = 0.3 * u(rng);
    for (int k = 0; k < 4; ++k) {
      const bool first = k < (ee ? 2 : 1);
      Vec3<double> p(2 * u(rng), 2 * u(rng), 0.1 * u(rng));
      if (first) p.z() += z;
      x0[std::size_t(k)] = p;
      Vec3<double> q = first ? Vec3<double>(p + slide) : p;
      q.z() += tx * q.x() + ty * q.y();
      x1[std::size_t(k)] = q + 0.1 * Vec3<double>(u(rng), u(rng), u(rng));
    }
    const double truth = sampled_min(x0, x1, ee);
    const double whole = bound(x0, x1, ee, need, 0, true), split = bound(x0, x1, ee, need, 6, true), both = bound(x0, x1, ee, need, 6);
    if (truth <= need) {
      ++close;
      EXPECT_EQ(split, -std::numeric_limits<double>::infinity()) << trial;
      EXPECT_EQ(both, -std::numeric_limits<double>::infinity()) << trial;
    }
    if (whole > need) {
      EXPECT_LE(whole, truth + 1e-12) << trial;
    }
    if (both > need) {
      EXPECT_LE(both, truth + 1e-12) << trial;
    }
    if (split > need) {
      ++proved;
      EXPECT_LE(split, truth + 1e-12) << trial;
      if (!(whole > need)) ++only_split;
    }
  }
  EXPECT_GT(close, 25);
  EXPECT_GT(proved, 100);
  EXPECT_GT(only_split, 20);
}

}  // namespace
