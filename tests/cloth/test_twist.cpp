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

// The gathering's walk of the swept tree against itself goes on from the last step's front (the
// node pairs where it stopped): it must find the same triangle pairs in the same order as a walk
// from the root, so a run whose front is dropped before every step ends bit-identical after the
// same work.
TEST(ClothTwist, FrontWalkSameAsWalkFromTheRoot) {
  const auto front = cloth_test::twist_run<double>(8, 40, 0.5, impact::ZoneMethod::Harmon, 40);
  const auto root = cloth_test::twist_run<double>(8, 40, 0.5, impact::ZoneMethod::Harmon, 40, 1, /*walk_from_root=*/true);
  EXPECT_GT(front.front_steps, 30);
  EXPECT_EQ(root.front_steps, 0);
  EXPECT_GT(front.collisions, 0u);
  EXPECT_EQ(front.ccd_tests, root.ccd_tests);
  EXPECT_EQ(front.collisions, root.collisions);
  ASSERT_EQ(front.final_x.size(), root.final_x.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < front.final_x.size(); ++i) differ += front.final_x[i] != root.final_x[i];
  EXPECT_EQ(differ, 0u);
}

}  // namespace
