// SPDX-License-Identifier: MIT
// A short twisting run (twist_run.hpp): every step collision-free, every verified state free of
// exact intersections and at least h apart. The longer runs are in test_twist_long.cpp.
#include "twist_run.hpp"

namespace {

TEST(ClothTwist, ShortRunHarmonDouble) {
  const auto r = cloth_test::twist_run<double>(6, 40, 0.5, impact::ZoneMethod::Harmon, 5);
  EXPECT_EQ(r.not_collision_free, 0);
  EXPECT_EQ(r.intersections_seen, 0u);
}

}  // namespace
