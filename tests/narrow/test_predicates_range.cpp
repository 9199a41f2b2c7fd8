// SPDX-License-Identifier: MIT
// orient3d, orient2d and triangles_intersect over the whole floating-point range (issue 12, D8):
// near-degenerate integer configurations, scaled by 2^k for every k that keeps them exactly
// representable (subnormal to the largest exponent), scaled by a different power of two on each
// axis (mixing magnitudes from 2^-1074 to 2^1000 in one call), and translated, keep the sign of the
// exact __int128 determinant and the answer of the exact integer separating-axis test: per-axis
// positive scaling and translation preserve both. Float and double inputs. The big-integer stage
// is also compared directly with the integer oracle on unscaled inputs.
#include "impact/narrow/predicates.hpp"
#include "impact/narrow/triangle_triangle.hpp"
#include "int_oracle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

#include <cmath>
#include <limits>
#include <type_traits>

using namespace impact;
using namespace impact::test;

namespace {

// Fewer configurations under the sanitizers (the big-integer stage is slow there).
constexpr int kDivisor = IMPACT_TEST_SANITIZED ? 6 : 1;

/// Near-coplanar integer quadruple with coordinates in [-4r, 4r]: d = a + i (b - a) + j (c - a) + e.
std::array<IPoint, 4> near_coplanar(Rng& rng, std::int64_t r, int it) {
  std::array<IPoint, 4> q;
  for (int k = 0; k < 3; ++k) q[0][k] = rng.integer(r), q[1][k] = rng.integer(r), q[2][k] = rng.integer(r);
  const std::int64_t i = rng.integer(1), j = rng.integer(1);
  for (int k = 0; k < 3; ++k) q[3][k] = q[0][k] + i * (q[1][k] - q[0][k]) + j * (q[2][k] - q[0][k]) + rng.integer(it % 3);
  return q;
}

/// The exponent range in which integers below 2^bits times 2^k are exact in S: k from the
/// smallest subnormal's exponent to the one that keeps them below the largest finite value.
template <class S> int k_min() { return std::is_same_v<S, double> ? -1074 : -149; }
template <class S> int k_max(int bits) { return std::numeric_limits<S>::max_exponent - bits - 1; }

/// p scaled by 2^ks[axis] on each axis and translated by t (integers, so exact when the sums fit).
template <class S> Vec3<S> place(const IPoint& p, const int* ks, const IPoint& t) {
  return Vec3<S>(S(std::ldexp(double(p[0] + t[0]), ks[0])), S(std::ldexp(double(p[1] + t[1]), ks[1])),
                 S(std::ldexp(double(p[2] + t[2]), ks[2])));
}

template <class S> void run_orient3d_scaled(std::uint64_t seed) {
  Rng rng(seed);
  const std::int64_t r = std::int64_t(1) << 18;  // coordinates below 2^21, translated below 2^22
  const int lo = k_min<S>(), hi = k_max<S>(23);
  int wrong = 0, cases = 0, zero = 0;
  for (int it = 0; it < 120 / kDivisor; ++it) {
    const auto q = near_coplanar(rng, r, it);
    const int expect = orient3d_int(q[0], q[1], q[2], q[3]);
    zero += expect == 0;
    IPoint t{0, 0, 0};
    if (it % 2) t = {rng.integer(r), rng.integer(r), rng.integer(r)};
    for (int k = lo; k <= hi; k += 3 + (it % 13)) {
      int ks[3] = {k, k, k};
      if (it % 3 == 2) ks[1] = lo + (hi - k), ks[2] = lo + int(rng.index(std::uint64_t(hi - lo + 1)));  // mixed magnitudes
      const Vec3<S> a = place<S>(q[0], ks, t), b = place<S>(q[1], ks, t), c = place<S>(q[2], ks, t), d = place<S>(q[3], ks, t);
      const int got = orient3d(a, b, c, d);
      wrong += got != expect;
      wrong += orient3d(b, a, c, d) != -expect;
      wrong += OrientPlane(a, b, c).orient(d) != expect;
      ++cases;
    }
  }
  EXPECT_EQ(wrong, 0) << "of " << cases << " scaled configurations";
  EXPECT_GT(zero, 10 / kDivisor) << "the configurations should include exactly coplanar ones";
}

TEST(PredicatesRange, Orient3dDoubleEveryScale) { run_orient3d_scaled<double>(11); }
TEST(PredicatesRange, Orient3dFloatEveryScale) { run_orient3d_scaled<float>(12); }

template <class S> void run_orient2d_scaled(std::uint64_t seed) {
  Rng rng(seed);
  const std::int64_t r = std::int64_t(1) << 20;
  const int lo = k_min<S>(), hi = k_max<S>(23);
  int wrong = 0, cases = 0, zero = 0;
  for (int it = 0; it < 300 / kDivisor; ++it) {
    const std::int64_t ax = rng.integer(r), ay = rng.integer(r), bx = rng.integer(r), by = rng.integer(r);
    const std::int64_t num = rng.integer(4);
    const std::int64_t cx = ax + num * (bx - ax) / 4 + rng.integer(it % 2), cy = ay + num * (by - ay) / 4 + rng.integer(it % 2);
    if (std::llabs(cx) >= (std::int64_t(1) << 23) || std::llabs(cy) >= (std::int64_t(1) << 23)) continue;
    const int expect = orient2d_int(ax, ay, bx, by, cx, cy);
    zero += expect == 0;
    for (int k = lo; k <= hi; k += 1 + (it % 11)) {
      const int kx = k, ky = it % 3 == 2 ? lo + (hi - k) : k;
      auto v = [&](std::int64_t x, std::int64_t y) { return Vec2<S>(S(std::ldexp(double(x), kx)), S(std::ldexp(double(y), ky))); };
      wrong += orient2d(v(ax, ay), v(bx, by), v(cx, cy)) != expect;
      wrong += orient2d(v(bx, by), v(ax, ay), v(cx, cy)) != -expect;
      ++cases;
    }
  }
  EXPECT_EQ(wrong, 0) << "of " << cases << " scaled configurations";
  EXPECT_GT(zero, 10 / kDivisor);
}

TEST(PredicatesRange, Orient2dDoubleEveryScale) { run_orient2d_scaled<double>(13); }
TEST(PredicatesRange, Orient2dFloatEveryScale) { run_orient2d_scaled<float>(14); }

// The big-integer stage on its own, on inputs of every kind (large integers near coplanar,
// scaled into the subnormal range), against the integer oracle.
TEST(PredicatesRange, BigIntegerStageMatchesIntegerOracle) {
  Rng rng(15);
  int wrong = 0;
  for (int it = 0; it < 20000 / kDivisor; ++it) {
    const auto q = near_coplanar(rng, std::int64_t(1) << 38, it);
    const int expect = orient3d_int(q[0], q[1], q[2], q[3]);
    const int k = it % 2 ? -1074 : 0;
    double p[4][3];
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) p[i][j] = std::ldexp(double(q[i][j]), k);
    if (it % 2 && std::llabs(q[0][0]) >= (std::int64_t(1) << 52)) continue;
    wrong += detail::bigint::orient3d(p[0], p[1], p[2], p[3]) != expect;
    wrong += detail::bigint::orient2d(p[0][0], p[0][1], p[1][0], p[1][1], p[2][0], p[2][1]) !=
             orient2d_int(q[0][0], q[0][1], q[1][0], q[1][1], q[2][0], q[2][1]);
  }
  EXPECT_EQ(wrong, 0);
  // the extremes: the largest and the smallest doubles in one determinant
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  const double a[3] = {0, 0, 0}, b[3] = {big, 0, 0}, c[3] = {0, big, 0}, d[3] = {tiny, tiny, tiny}, e[3] = {tiny, tiny, -tiny};
  EXPECT_EQ(orient3d(Vec3<double>(a[0], a[1], a[2]), Vec3<double>(b[0], b[1], b[2]), Vec3<double>(c[0], c[1], c[2]),
                     Vec3<double>(d[0], d[1], d[2])),
            1);
  EXPECT_EQ(detail::bigint::orient3d(a, b, c, e), -1);
  EXPECT_EQ(detail::orient3d_double(a, b, c, e), -1);
  // differences that overflow: -max to max
  const double f[3] = {-big, -big, 0}, g[3] = {big, -big, 0}, h[3] = {-big, big, 0}, up[3] = {0, 0, tiny};
  EXPECT_EQ(detail::orient3d_double(f, g, h, up), 1);
  EXPECT_EQ(detail::orient2d_double(-big, -big, big, -big, -big, big), 1);
  EXPECT_EQ(detail::orient2d_double(-big, -big, big, big, tiny, tiny), 0);
}

// The case: two triangles a gap apart stay apart, and touching ones keep touching, at
// every scale and with mixed per-axis scales, float and double.
template <class S> void run_triangles_scaled(std::uint64_t seed) {
  Rng rng(seed);
  const std::int64_t r = 1 << 10;
  const int lo = k_min<S>(), hi = k_max<S>(23);
  int wrong = 0, cases = 0, hits = 0, misses = 0;
  for (int it = 0; it < 100 / kDivisor; ++it) {
    std::array<IPoint, 3> P, Q;
    for (auto& p : P)
      for (auto& x : p) x = rng.integer(r);
    // Q: a vertex on P's plane (touching, or one unit off it), or a random triangle near P
    const int mode = it % 3;
    for (auto& p : Q)
      for (auto& x : p) x = rng.integer(r);
    if (mode < 2) {
      // Q's first vertex on a vertex of P (touching), or one unit off it (usually apart)
      Q[0] = P[it % 3];
      if (mode == 1) Q[0][it % 3 == 0 ? 2 : 0] += (it % 2 ? 1 : -1);
    }
    const bool expect = triangles_intersect_int(P, Q);
    hits += expect, misses += !expect;
    for (int k = lo; k <= hi; k += 7 + (it % 17)) {
      int ks[3] = {k, k, k};
      if (it % 4 == 3) ks[0] = lo + (hi - k), ks[2] = lo + int(rng.index(std::uint64_t(hi - lo + 1)));
      const IPoint t{0, 0, 0};
      const Triangle<S> a(place<S>(P[0], ks, t), place<S>(P[1], ks, t), place<S>(P[2], ks, t));
      const Triangle<S> b(place<S>(Q[0], ks, t), place<S>(Q[1], ks, t), place<S>(Q[2], ks, t));
      wrong += triangles_intersect(a, b) != expect;
      wrong += triangles_intersect(b, a) != expect;
      ++cases;
    }
  }
  EXPECT_EQ(wrong, 0) << "of " << cases;
  EXPECT_GT(hits, 25 / kDivisor);
  EXPECT_GT(misses, 25 / kDivisor);
}

TEST(PredicatesRange, TrianglesDoubleEveryScale) { run_triangles_scaled<double>(16); }
TEST(PredicatesRange, TrianglesFloatEveryScale) { run_triangles_scaled<float>(17); }

}  // namespace
