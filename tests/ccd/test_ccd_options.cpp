// SPDX-License-Identifier: MIT
// Behaviour of the CCD options: minimum separation, t_max, tolerance, budget exhaustion (a
// conservative hit at the earliest time not yet excluded), toi never later than the true time,
// and the contact parameters. Float and double.
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace {

template <class S>
using V = impact::Vec3<S>;

template <class S>
class CcdOptionsTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(CcdOptionsTest, Scalars);

// Static unit triangle in z = 0; the point falls from z = 1 - 2 c ... through the plane at time c.
template <class S>
impact::CcdResult<S> falling_point(S x, S y, S z0, S z1, const impact::CcdOptions& o) {
  const V<S> f0(0, 0, 0), f1(1, 0, 0), f2(0, 1, 0);
  return impact::vertex_face_ccd(V<S>(x, y, z0), f0, f1, f2, V<S>(x, y, z1), f0, f1, f2, o);
}

TYPED_TEST(CcdOptionsTest, VertexFaceBasic) {
  using S = TypeParam;
  impact::CcdOptions o;
  // Through the plane at t = 0.5, inside the triangle.
  auto r = falling_point<S>(S(0.25), S(0.25), S(1), S(-1), o);
  ASSERT_TRUE(r.hit);
  EXPECT_LE(r.toi, S(0.5));
  EXPECT_GE(r.toi, S(0.5) - S(1e-5));
  EXPECT_NEAR(r.u, S(0.25), S(1e-4));
  EXPECT_NEAR(r.v, S(0.25), S(1e-4));
  // Through the plane outside the triangle.
  r = falling_point<S>(S(0.75), S(0.75), S(1), S(-1), o);
  EXPECT_FALSE(r.hit);
  EXPECT_EQ(r.toi, S(1));
}

TYPED_TEST(CcdOptionsTest, MinimumSeparation) {
  using S = TypeParam;
  impact::CcdOptions o;
  // Sliding parallel to the triangle at height 0.01: no contact, but within d = 0.02.
  auto r = falling_point<S>(S(0.2), S(0.2), S(0.01), S(0.01), o);
  EXPECT_FALSE(r.hit);
  o.min_separation = 0.02;
  r = falling_point<S>(S(0.2), S(0.2), S(0.01), S(0.01), o);
  EXPECT_TRUE(r.hit);
  EXPECT_EQ(r.toi, S(0));
  o.min_separation = 0.005;
  r = falling_point<S>(S(0.2), S(0.2), S(0.01), S(0.01), o);
  EXPECT_FALSE(r.hit);
  // Falling from 1 to -1 through the plane at t = 0.5 comes within d = 0.1 at t = 0.45.
  o.min_separation = 0.1;
  r = falling_point<S>(S(0.25), S(0.25), S(1), S(-1), o);
  ASSERT_TRUE(r.hit);
  EXPECT_LE(r.toi, S(0.45));
  EXPECT_GE(r.toi, S(0.45) - S(1e-4));
  // Passing beside the triangle's edge x = 0 at distance 0.05 (outside the plane's triangle).
  r = falling_point<S>(S(-0.05), S(0.5), S(1), S(-1), o);
  EXPECT_TRUE(r.hit);
  o.min_separation = 0.04;
  r = falling_point<S>(S(-0.05), S(0.5), S(1), S(-1), o);
  EXPECT_FALSE(r.hit);
  // Edge-edge: crossing edges at height 0.03 apart, parallel planes.
  const V<S> a0(-1, 0, 0), a1(1, 0, 0), b0(0, -1, S(0.03)), b1(0, 1, S(0.03));
  o.min_separation = 0.02;
  EXPECT_FALSE(impact::edge_edge_ccd(a0, a1, b0, b1, a0, a1, b0, b1, o).hit);
  o.min_separation = 0.04;
  EXPECT_TRUE(impact::edge_edge_ccd(a0, a1, b0, b1, a0, a1, b0, b1, o).hit);
}

TYPED_TEST(CcdOptionsTest, TimeWindow) {
  using S = TypeParam;
  impact::CcdOptions o;
  o.t_max = 0.4;
  auto r = falling_point<S>(S(0.25), S(0.25), S(1), S(-1), o);
  EXPECT_FALSE(r.hit);
  EXPECT_EQ(r.toi, S(0.4));
  o.t_max = 0.6;
  r = falling_point<S>(S(0.25), S(0.25), S(1), S(-1), o);
  EXPECT_TRUE(r.hit);
  EXPECT_LE(r.toi, S(0.5));
}

TYPED_TEST(CcdOptionsTest, BudgetGivesConservativeHit) {
  using S = TypeParam;
  impact::CcdOptions o;
  o.max_iterations = 1;
  o.recheck_iterations = 0;
  // A clear miss that needs a few boxes to exclude: reported as a hit at the earliest time not
  // excluded, flagged.
  auto r = falling_point<S>(S(0.6), S(0.6), S(1), S(-1), o);
  EXPECT_TRUE(r.hit);
  EXPECT_TRUE(r.budget_exhausted);
  EXPECT_EQ(r.toi, S(0));
  EXPECT_EQ(r.iterations, 1);
  // The re-check of that hit, with its own budget, proves the miss; with too small a budget
  // of its own the conservative hit stands.
  o.recheck_iterations = 1;
  r = falling_point<S>(S(0.6), S(0.6), S(1), S(-1), o);
  EXPECT_TRUE(r.hit);
  EXPECT_TRUE(r.budget_exhausted);
  o.recheck_iterations = 1000;
  r = falling_point<S>(S(0.6), S(0.6), S(1), S(-1), o);
  EXPECT_FALSE(r.hit);
  EXPECT_FALSE(r.budget_exhausted);
  EXPECT_GT(r.recheck_iterations, 1);
  // With enough budget the same query is a miss.
  o.max_iterations = 100000;
  r = falling_point<S>(S(0.6), S(0.6), S(1), S(-1), o);
  EXPECT_FALSE(r.hit);
  EXPECT_FALSE(r.budget_exhausted);
  // A budget-limited answer on a real contact never has toi later than the contact.
  for (std::int64_t budget : {1, 2, 5, 10, 30, 100}) {
    o.max_iterations = budget;
    r = falling_point<S>(S(0.25), S(0.25), S(1), S(-1), o);
    EXPECT_TRUE(r.hit);
    EXPECT_LE(r.toi, S(0.5));
  }
}

TYPED_TEST(CcdOptionsTest, RecheckSeparatesNearMisses) {
  using S = TypeParam;
  impact::CcdOptions plain, checked;
  plain.recheck_iterations = 0;
  // Near misses, each closer than the tolerance: through the plane 2^-60 outside the edge x = 0
  // (far below double rounding of the search), and 2^-23 and one ulp outside the hypotenuse
  // x + y = 1. The search alone reports hits; the re-check proves the misses.
  const S ulp_half = std::numeric_limits<S>::epsilon() / 2;  // ulp(0.5)
  const S cases[3][2] = {{-std::ldexp(S(1), -60), S(0.25)}, {S(0.5) + std::ldexp(S(1), -23), S(0.5)}, {S(0.5) + ulp_half, S(0.5)}};
  for (const auto& c : cases) {
    auto r = falling_point<S>(c[0], c[1], S(1), S(-1), plain);
    EXPECT_TRUE(r.hit) << c[0] << " " << c[1];
    r = falling_point<S>(c[0], c[1], S(1), S(-1), checked);
    EXPECT_FALSE(r.hit) << c[0] << " " << c[1];
    EXPECT_FALSE(r.budget_exhausted);
    EXPECT_EQ(r.toi, S(1));
  }
  // Exact contacts stay hits: through the edge x = 0, the hypotenuse, and a vertex.
  const S contacts[3][2] = {{S(0), S(0.25)}, {S(0.5), S(0.5)}, {S(1), S(0)}};
  for (const auto& c : contacts) {
    const auto r = falling_point<S>(c[0], c[1], S(1), S(-1), checked);
    EXPECT_TRUE(r.hit) << c[0] << " " << c[1];
    EXPECT_LE(r.toi, S(0.5));
  }
}

TYPED_TEST(CcdOptionsTest, ToleranceTightensToi) {
  using S = TypeParam;
  for (double tol : {1e-2, 1e-4, 1e-6}) {
    impact::CcdOptions o;
    o.tolerance = tol;
    const auto r = falling_point<S>(S(0.25), S(0.25), S(1), S(-1), o);
    ASSERT_TRUE(r.hit);
    EXPECT_LE(r.toi, S(0.5));
    // At toi the point is within 2 tolerance L of the triangle, L = 2 the query's extent (z from
    // 1 to -1): |z(toi)| = 2 (0.5 - toi).
    EXPECT_LE(2 * (0.5 - double(r.toi)), 2 * tol * 2 + 1e-6);
  }
}

TYPED_TEST(CcdOptionsTest, ToiNeverLateRandom) {
  using S = TypeParam;
  // A point falling on a random static triangle in z = 0 from random heights: the first contact is
  // exactly when it crosses z = 0 (if it is above the triangle then).
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const S z0 = S(std::ldexp(std::floor(U(rng) * 1024), -10) + 0.001);
    const S z1 = -S(std::ldexp(std::floor(U(rng) * 1024), -10) + 0.001);
    const double tc = double(z0) / (double(z0) - double(z1));
    const auto r = falling_point<S>(S(0.25), S(0.5), z0, z1, {});
    ASSERT_TRUE(r.hit);
    EXPECT_LE(double(r.toi), tc);
  }
}

TYPED_TEST(CcdOptionsTest, EdgeEdgeBasic) {
  using S = TypeParam;
  // Edge b sweeps down through edge a at t = 0.25.
  const V<S> a0(-1, 0, 0), a1(1, 0, 0);
  const V<S> b00(S(0.5), -1, S(0.25)), b10(S(0.5), 1, S(0.25)), b01(S(0.5), -1, S(-0.75)), b11(S(0.5), 1, S(-0.75));
  const auto r = impact::edge_edge_ccd(a0, a1, b00, b10, a0, a1, b01, b11);
  ASSERT_TRUE(r.hit);
  EXPECT_LE(r.toi, S(0.25));
  EXPECT_GE(r.toi, S(0.25) - S(1e-5));
  EXPECT_NEAR(r.u, S(0.75), S(1e-4));
  EXPECT_NEAR(r.v, S(0.5), S(1e-4));
  // Shifted beyond the end of a: a miss.
  const V<S> s(S(1.5), 0, 0);
  EXPECT_FALSE(impact::edge_edge_ccd(a0, a1, V<S>(b00 + s), V<S>(b10 + s), a0, a1, V<S>(b01 + s), V<S>(b11 + s)).hit);
}

}  // namespace

namespace {

// The dev set's last false positive (erleben-cube-cliff-edges/vertex-face/data_0_0.csv, query
// 123): a still vertex at (0, 1/2, 1) and a face whose z coordinates are all 1 or 1 - 2^-53. Exact
// arithmetic (rational, outside this library) puts the closest approach over [0, 1] at t = 1,
// 1.64e-32 from the face's plane with the vertex inside the triangle (u = 1.48e-16, v = 0.222):
// the contact would come at t = 1 + 1.48e-16, after the step. Error bounds relative to the
// coordinates' magnitude (2^-94 * 1.5 = 9e-29 in double-double) could never separate that gap,
// whatever the re-check budget; relative to the query's extent around a reference point
// (2^-94 * 2^-53 in z) the re-check proves the miss.
TEST(CcdRecheck, CliffEdgesQuery123IsAMiss) {
  using V = impact::Vec3<double>;
  const V p[8] = {V(0x0.0p+0, 0x1.0000000000000p-1, 0x1.0000000000000p+0),
                  V(0x1.2dd09ec3fef69p-54, 0x1.075adf7b1a9d2p-1, 0x1.fffffffffffffp-1),
                  V(0x1.0000000000000p+0, 0x1.83ad6fbd8d4e9p+0, 0x1.fffffffffffffp-1),
                  V(-0x1.031462598eaffp-56, 0x1.83ad6fbd8d4e8p+0, 0x1.fffffffffffffp-1),
                  V(0x0.0p+0, 0x1.0000000000000p-1, 0x1.0000000000000p+0),
                  V(-0x1.60a2909c8caaap-53, 0x1.1c4a18930a7fap-2, 0x1.0000000000000p+0),
                  V(0x1.0000000000000p+0, 0x1.47128624c29ffp+0, 0x1.fffffffffffffp-1),
                  V(-0x1.2ba6d303b4eb8p-53, 0x1.47128624c29fep+0, 0x1.0000000000000p+0)};
  impact::CcdOptions o;
  o.recheck_iterations = 0;  // the double search alone cannot separate it
  auto r = impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
  EXPECT_TRUE(r.hit);
  o = {};  // the default re-check proves the miss
  r = impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
  EXPECT_FALSE(r.hit);
  EXPECT_FALSE(r.budget_exhausted);
  EXPECT_GT(r.recheck_iterations, 0);
  EXPECT_LT(r.recheck_iterations, o.recheck_iterations);
  // The same time reversed and with the face's vertices rotated.
  EXPECT_FALSE(impact::vertex_face_ccd(p[4], p[5], p[6], p[7], p[0], p[1], p[2], p[3]).hit);
  EXPECT_FALSE(impact::vertex_face_ccd(p[0], p[2], p[3], p[1], p[4], p[6], p[7], p[5]).hit);
}

}  // namespace
