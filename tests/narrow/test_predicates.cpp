// SPDX-License-Identifier: MIT
// orient3d / orient2d against exact __int128 determinants on integer (and power-of-two scaled)
// inputs chosen nearly coplanar / collinear, where a naive floating-point determinant gets the
// sign wrong; the test checks that such cases are actually generated. Float and double inputs.
#include "impact/narrow/predicates.hpp"
#include "int_oracle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace impact;
using namespace impact::test;

namespace {

template <class S> int naive3(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c, const Vec3<S>& d) {
  const S v = (d - a).dot((b - a).cross(c - a));
  return v > 0 ? 1 : (v < 0 ? -1 : 0);
}

/// Near-coplanar integer quadruples: d = a + i (b - a) + j (c - a) + small perturbation.
template <class S> void run_orient3d(std::int64_t r, std::uint64_t seed) {
  Rng rng(seed);
  int naive_wrong = 0, wrong = 0;
  const double scale = std::is_same_v<S, float> ? 1.0 : 0x1p-30;
  for (int it = 0; it < 100000; ++it) {
    IPoint a, b, c, d;
    for (int k = 0; k < 3; ++k) a[k] = rng.integer(r), b[k] = rng.integer(r), c[k] = rng.integer(r);
    const std::int64_t i = rng.integer(1), j = rng.integer(1);
    for (int k = 0; k < 3; ++k) d[k] = a[k] + i * (b[k] - a[k]) + j * (c[k] - a[k]) + rng.integer(it % 3);
    const int expect = orient3d_int(a, b, c, d);
    auto v = [&](const IPoint& p) { return Vec3<S>(S(double(p[0]) * scale), S(double(p[1]) * scale), S(double(p[2]) * scale)); };
    const int got = orient3d(v(a), v(b), v(c), v(d));
    wrong += got != expect;
    naive_wrong += naive3(v(a), v(b), v(c), v(d)) != expect;
    // permutation symmetry
    wrong += orient3d(v(b), v(a), v(c), v(d)) != -expect;
    wrong += orient3d(v(d), v(a), v(b), v(c)) != -expect;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(naive_wrong, 100) << "the test should contain cases where naive evaluation fails";
}

TEST(Predicates, Orient3dDoubleNearCoplanar) { run_orient3d<double>(std::int64_t(1) << 38, 1); }
TEST(Predicates, Orient3dFloatNearCoplanar) { run_orient3d<float>(std::int64_t(1) << 21, 2); }

template <class S> void run_orient2d(std::int64_t r, std::uint64_t seed) {
  Rng rng(seed);
  int naive_wrong = 0, wrong = 0;
  for (int it = 0; it < 100000; ++it) {
    const std::int64_t ax = rng.integer(r), ay = rng.integer(r), bx = rng.integer(r), by = rng.integer(r);
    // c near the line ab: a + t (b - a) with t = 1/2^k style rational rounded, perturbed
    const std::int64_t num = rng.integer(64), sh = 6;
    std::int64_t cx = ax + ((bx - ax) >> sh) * num, cy = ay + ((by - ay) >> sh) * num;
    cx += rng.integer(it % 2), cy += rng.integer(it % 2);
    if (std::llabs(cx) > 4 * r || std::llabs(cy) > 4 * r) continue;
    const int expect = orient2d_int(ax, ay, bx, by, cx, cy);
    const Vec2<S> a{static_cast<S>(ax), static_cast<S>(ay)}, b{static_cast<S>(bx), static_cast<S>(by)}, c{static_cast<S>(cx), static_cast<S>(cy)};
    wrong += orient2d(a, b, c) != expect;
    wrong += orient2d(b, c, a) != expect;
    wrong += orient2d(b, a, c) != -expect;
    const S naive = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    naive_wrong += (naive > 0 ? 1 : (naive < 0 ? -1 : 0)) != expect;
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GT(naive_wrong, 20);
}

TEST(Predicates, Orient2dDoubleNearCollinear) { run_orient2d<double>(std::int64_t(1) << 50, 3); }
TEST(Predicates, Orient2dFloatNearCollinear) { run_orient2d<float>(std::int64_t(1) << 22, 4); }

TEST(Predicates, ExactZeroAndSimpleSigns) {
  using V = Vec3<double>;
  EXPECT_EQ(orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, 1)), 1);
  EXPECT_EQ(orient3d(V(0, 0, 0), V(0, 1, 0), V(1, 0, 0), V(0, 0, 1)), -1);
  EXPECT_EQ(orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(3, 7, 0)), 0);
  EXPECT_EQ(orient3d(V(0.1, 0.2, 0.3), V(0.1, 0.2, 0.3), V(0, 1, 0), V(3, 7, 0)), 0);
  // 0.1 + 0.2 != 0.3 in double: tiny nonzero volumes must come out with their exact sign
  EXPECT_EQ(orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0.5, 0.5, 1e-300 * 1e-10)), 1);
  EXPECT_EQ(orient2d(Vec2<double>(0, 0), Vec2<double>(1, 1), Vec2<double>(0.5, 0.5)), 0);
  EXPECT_EQ(orient2d(Vec2<double>(0, 0), Vec2<double>(1, 1), Vec2<double>(0.5, std::nextafter(0.5, 1.0))), 1);
  OrientPlane plane(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0));
  EXPECT_EQ(plane.orient(V(0.3, 0.3, -1e-200)), -1);
}

}  // namespace
