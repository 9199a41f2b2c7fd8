// SPDX-License-Identifier: MIT
// Swept AABB and swept sphere: they hold every point of the moving primitive at every sampled time,
// grown by the minimum separation.
#include "impact/ccd/swept_volume.hpp"

#include <gtest/gtest.h>

#include <random>

namespace {

template <class S>
class SweptVolumeTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(SweptVolumeTest, Scalars);

TYPED_TEST(SweptVolumeTest, ContainsSweptTriangle) {
  using S = TypeParam;
  using V = impact::Vec3<S>;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-10.0, 10.0), T(0.0, 1.0);
  for (int it = 0; it < 200; ++it) {
    V a[3], b[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = V(S(U(rng)), S(U(rng)), S(U(rng)));
      b[k] = a[k] + V(S(U(rng)), S(U(rng)), S(U(rng))) * S(0.1);
    }
    const S d = S(0.05);
    const auto box = impact::swept_aabb(a, b, d);
    const auto ball = impact::swept_sphere(a, b, d);
    for (int s = 0; s < 50; ++s) {
      const S t = S(T(rng)), u = S(T(rng)), v = S(T(rng)) * (S(1) - u);
      V p[3];
      for (int k = 0; k < 3; ++k) p[k] = a[k] + t * (b[k] - a[k]);
      const V x = (S(1) - u - v) * p[0] + u * p[1] + v * p[2];
      // Offset by d in a random direction: still inside both volumes (up to float rounding of x).
      V dir(S(U(rng)), S(U(rng)), S(U(rng)));
      dir.normalize();
      const V y = x + dir * (d * S(0.999));
      const S slack = S(1e-5) * (std::is_same_v<S, float> ? S(10) : S(1e-6));
      EXPECT_TRUE(((y.array() >= box.min.array() - slack).all() && (y.array() <= box.max.array() + slack).all()));
      EXPECT_TRUE(ball.contains(y, slack));
    }
  }
}

TYPED_TEST(SweptVolumeTest, VertexBox) {
  using S = TypeParam;
  using V = impact::Vec3<S>;
  const auto box = impact::swept_aabb(V(0, 0, 0), V(1, -2, 3), S(0.5));
  EXPECT_LE(box.min[0], S(-0.5));
  EXPECT_LE(box.min[1], S(-2.5));
  EXPECT_GE(box.max[2], S(3.5));
  EXPECT_GE(box.max[0], S(1.5));
}

}  // namespace
