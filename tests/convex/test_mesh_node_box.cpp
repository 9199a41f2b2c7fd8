// SPDX-License-Identifier: MIT
// The box the mesh–convex node tests put about an oriented box (detail::obb_hull_box in
// convex/mesh_convex.hpp) must hold the oriented box exactly, whatever the rounding: each corner
// centre + sum(+-half_i axis_i), computed in long double, lies in the box, for random rotations,
// centres far from the origin, tiny, huge and zero half extents, float and double; the box is at
// most a few ulps of |c| + r larger than the exact one; an invalid box gives the empty box.
#include "impact/convex/mesh_convex.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

using impact::test::Rng;

template <class S>
void node_box_holds_the_obb(std::uint64_t seed) {
  using V = Eigen::Matrix<S, 3, 1>;
  using LV = Eigen::Matrix<long double, 3, 1>;
  Rng rng(seed);
  const int n = IMPACT_TEST_SANITIZED ? 2000 : 20000;
  constexpr S eps = std::numeric_limits<S>::epsilon();
  for (int i = 0; i < n; ++i) {
    impact::Obb<S> b;
    b.axes = rng.rotation().cast<S>();
    const double cscale = std::pow(10.0, rng.uniform(-3, std::is_same_v<S, float> ? 5 : 8));
    const double hscale = std::pow(10.0, rng.uniform(-6, 3));
    b.center = (cscale * rng.vec(-1, 1)).cast<S>();
    b.half = (hscale * rng.vec(0, 1)).cast<S>();
    if (i % 7 == 0) b.half[i % 3] = S(0);  // flat
    if (i % 11 == 0) b.axes = impact::Mat3<S>::Identity();
    const impact::Aabb<S> box = impact::detail::obb_hull_box(b);
    LV r_exact = LV::Zero();
    for (int c = 0; c < 8; ++c) {
      LV corner = b.center.template cast<long double>();
      for (int k = 0; k < 3; ++k)
        corner += ((c >> k) & 1 ? 1.0L : -1.0L) * (long double)b.half[k] * b.axes.col(k).template cast<long double>();
      for (int k = 0; k < 3; ++k) {
        ASSERT_LE((long double)box.min[k], corner[k]) << "corner below the box, sample " << i;
        ASSERT_GE((long double)box.max[k], corner[k]) << "corner above the box, sample " << i;
        r_exact[k] = std::max(r_exact[k], std::abs(corner[k] - (long double)b.center[k]));
      }
    }
    // not much larger than the exact box: 16 ulps of |c| + r
    for (int k = 0; k < 3; ++k) {
      const long double slack = 16.0L * eps * (std::abs((long double)b.center[k]) + r_exact[k]) + std::numeric_limits<S>::denorm_min();
      EXPECT_LE((long double)b.center[k] - r_exact[k] - (long double)box.min[k], slack);
      EXPECT_LE((long double)box.max[k] - ((long double)b.center[k] + r_exact[k]), slack);
    }
  }
  impact::Obb<S> bad;
  bad.axes.setIdentity();
  bad.center = V::Zero();
  bad.half = V(S(1), S(-1), S(1));
  EXPECT_TRUE(impact::detail::obb_hull_box(bad).empty());
}

TEST(MeshNodeBox, HoldsTheOrientedBoxDouble) { node_box_holds_the_obb<double>(81); }
TEST(MeshNodeBox, HoldsTheOrientedBoxFloat) { node_box_holds_the_obb<float>(82); }

}  // namespace
