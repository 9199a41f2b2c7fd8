// SPDX-License-Identifier: MIT
// ObbSlabs: the slabs of a point set along the ten diagonal directions of a box's axes hold every
// point for the exact values of the stored axes and centre (checked in long double), are tight
// within their rounding pad, and are invalid for no points or non-finite ones; float and double.
#include "impact/geometry/obb_slabs.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

using namespace impact;
using namespace impact::test;

template <class S> class ObbSlabsTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ObbSlabsTest, Scalars);

TYPED_TEST(ObbSlabsTest, HoldEveryPointAndAreTight) {
  using S = TypeParam;
  using L = long double;
  Rng rng(17001);
  int checked = 0;
  for (double scale : {1e-3, 1.0, 1e4}) {
    for (int trial = 0; trial < 20; ++trial) {
      // a rotated frame far from the origin, points spread unequally along its axes
      const RigidTransform<double> frame = random_pose(rng, Eigen::Vector3d::Constant(-1e3 * scale), Eigen::Vector3d::Constant(1e3 * scale));
      Obb<S> box;
      box.center = frame.t.cast<S>();
      box.axes = frame.R.cast<S>();
      std::vector<S> pts;
      for (int k = 0; k < 200; ++k) {
        const Eigen::Vector3d local(rng.uniform(-3, 3) * scale, rng.uniform(-1, 1) * scale, rng.uniform(-0.2, 0.2) * scale);
        const Eigen::Vector3d p = frame.R * local + frame.t;
        for (int i = 0; i < 3; ++i) pts.push_back(S(p[i]));
      }
      const ObbSlabs<S> s = fit_obb_slabs(box, pts.data(), pts.size() / 3);
      ASSERT_TRUE(s.valid);
      EXPECT_EQ(s.center, box.center);
      EXPECT_EQ(s.axes, box.axes);
      for (int m = 0; m < kObbSlabDirections; ++m) {
        const auto k = static_cast<std::size_t>(m);
        L lo = std::numeric_limits<L>::infinity(), hi = -lo;
        for (std::size_t q = 0; q < pts.size() / 3; ++q) {
          L v = 0;  // d_m . (p - c) with the stored axes, in long double (exact to far below the pad)
          for (int i = 0; i < 3; ++i)
            for (int r = 0; r < 3; ++r)
              v += L(kObbSlabCoefficients[m][i]) * L(box.axes(r, i)) * (L(pts[3 * q + static_cast<std::size_t>(r)]) - L(box.center[r]));
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
        EXPECT_LE(L(s.lo[k]), lo) << "direction " << m;
        EXPECT_GE(L(s.hi[k]), hi) << "direction " << m;
        // tight: the pad is a few hundred ulps of the coordinates, far below the points' spread
        const L ulp = L(std::numeric_limits<S>::epsilon()) * L(1e3 * scale);
        EXPECT_LE(lo - L(s.lo[k]), 1e3 * ulp) << "direction " << m;
        EXPECT_LE(L(s.hi[k]) - hi, 1e3 * ulp) << "direction " << m;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 3 * 20 * kObbSlabDirections);
}

TYPED_TEST(ObbSlabsTest, InvalidWithoutFinitePoints) {
  using S = TypeParam;
  const Obb<S> box;
  EXPECT_FALSE(fit_obb_slabs<S>(box, nullptr, 0).valid);
  const S bad[6] = {S(0), S(1), S(2), std::numeric_limits<S>::quiet_NaN(), S(0), S(0)};
  EXPECT_FALSE(fit_obb_slabs<S>(box, bad, 2).valid);
  const S inf[3] = {std::numeric_limits<S>::infinity(), S(0), S(0)};
  EXPECT_FALSE(fit_obb_slabs<S>(box, inf, 1).valid);
  const S one[3] = {S(1), S(2), S(3)};
  const ObbSlabs<S> s = fit_obb_slabs<S>(box, one, 1);
  ASSERT_TRUE(s.valid);
  EXPECT_LE(s.lo[0], S(3));  // (1, 1, 0) . (1, 2, 3)
  EXPECT_GE(s.hi[0], S(3));
  EXPECT_LE(s.lo[9], S(2));  // (1, -1, -1) . (1, 2, 3) = -4
  EXPECT_GE(s.hi[9], S(-4));
  EXPECT_LE(s.lo[9], S(-4));
}

TYPED_TEST(ObbSlabsTest, SeparatesAlongADiagonalOnly) {
  using S = TypeParam;
  // A: points at the corners (+-1, +-1, +-1) of a unit-axes box of half extents 1 and the origin
  // (1, 1, 1) direction's slab [-3, 3]... then only the octahedron-like points: slabs along
  // (1, 1, 1) [-1, 1] while the box is [-1, 1]^3. B: a small box (half 0.1) centred on the
  // diagonal: its box overlaps A's box but lies beyond A's slab along (1, 1, 1) from a distance on.
  const S pts[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  Obb<S> a;
  a.half = Vec3<S>::Ones();
  const ObbSlabs<S> sa = fit_obb_slabs<S>(a, pts, 6);
  const Mat3<S> R = Mat3<S>::Identity();
  const Vec3<S> eb = Vec3<S>::Constant(S(0.1));
  const S inf = std::numeric_limits<S>::infinity();
  // B's lowest point along (1, 1, 1) is at 3 c - 0.3: apart from A's slab (<= 1) when c > 1.3 / 3
  for (double c : {0.40, 0.43, 0.44, 0.6, 0.9}) {
    const Vec3<S> tb = Vec3<S>::Constant(S(c));
    const bool sep = obb_slabs_separate<S>(a.half, R, tb, eb, S(0), S(0), inf, inf, S(0), &sa, nullptr);
    EXPECT_EQ(sep, c > 1.3 / 3 + 1e-3) << c;
    // the same from B's side: B's slabs are A's, B's box is A's; the small box is A now
    EXPECT_EQ(obb_slabs_separate<S>(eb, R, Vec3<S>(-tb), a.half, S(0), S(0), inf, inf, S(0), nullptr, &sa), sep) << c;
    // a rounding bound as large as the gap keeps them together
    EXPECT_FALSE(obb_slabs_separate<S>(a.half, R, tb, eb, S(c) * 3, S(0), inf, inf, S(0), &sa, &sa)) << c;
  }
  EXPECT_FALSE(obb_slabs_separate<S>(a.half, R, Vec3<S>::Constant(S(0.9)), eb, S(0), S(0), inf, inf, S(0), nullptr, nullptr));
}
