// SPDX-License-Identifier: MIT
// The longer twisting runs (label "long": skipped by the sanitizer pass): a full turn with dense
// self-contact, both zone methods, float and double, and two thousand steps of two relative turns;
// zero intersections and at least h at every verified state, every step collision-free.
#include "twist_run.hpp"

namespace {

TEST(ClothTwistLong, FullTurnHarmonDouble) {
  const auto r = cloth_test::twist_run<double>(8, 120, 1.0, impact::ZoneMethod::Harmon, 10);
  EXPECT_EQ(r.steps_run, 120);
  EXPECT_EQ(r.not_collision_free, 0);
  EXPECT_EQ(r.intersections_seen, 0u);
  EXPECT_GT(r.zones, 0u);  // the run reaches self-contact that needs zones
}

TEST(ClothTwistLong, FullTurnRigidFloat) {
  const auto r = cloth_test::twist_run<float>(8, 120, 1.0, impact::ZoneMethod::Rigid, 10);
  EXPECT_EQ(r.not_collision_free, 0);
  EXPECT_EQ(r.intersections_seen, 0u);
}

// Thousands of steps (the long run): a 4 x 4 sheet twisted by two relative turns over
// 2,000 steps, checked exactly every 20 steps. About 15 s of one core in Release.
TEST(ClothTwistLong, TwoThousandStepsTwoTurnsHarmonDouble) {
  const auto r = cloth_test::twist_run<double>(4, 2000, 2.0, impact::ZoneMethod::Harmon, 20);
  EXPECT_EQ(r.steps_run, 2000);
  EXPECT_EQ(r.not_collision_free, 0);
  EXPECT_EQ(r.intersections_seen, 0u);
  EXPECT_GT(r.zones, 0u);
}

}  // namespace
