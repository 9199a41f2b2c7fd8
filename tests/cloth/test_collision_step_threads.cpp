// SPDX-License-Identifier: MIT
// The collision step's thread count never changes its result: a twisting run (dense self-contact,
// every stage active) with 1 and with 2 threads ends in bit-identical positions after the same
// work. Label "concurrency": it also runs under ThreadSanitizer.
#include "twist_run.hpp"

namespace {

TEST(ClothStepThreads, TwistIsIdenticalForOneAndTwoThreads) {
  for (auto method : {impact::ZoneMethod::Harmon, impact::ZoneMethod::Rigid}) {
    const auto one = cloth_test::twist_run<double>(6, 30, 0.5, method, 10, 1);
    const auto two = cloth_test::twist_run<double>(6, 30, 0.5, method, 10, 2);
    EXPECT_EQ(one.not_collision_free, 0);
    EXPECT_GT(one.collisions, 0u);  // the run has contacts for the threads to share
    EXPECT_EQ(one.ccd_tests, two.ccd_tests);
    EXPECT_EQ(one.collisions, two.collisions);
    EXPECT_EQ(one.zones, two.zones);
    ASSERT_EQ(one.final_x.size(), two.final_x.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < one.final_x.size(); ++i) differ += one.final_x[i] != two.final_x[i];
    EXPECT_EQ(differ, 0u);
  }
}

}  // namespace
