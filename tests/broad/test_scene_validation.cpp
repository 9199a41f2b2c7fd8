// SPDX-License-Identifier: MIT
// Scene options and edits outside their ranges (issue 12): an unknown broad phase used to fall
// back silently to AllPairs, a static leaf size of 0 or NaN tree margins went unchecked, and
// translations or sizes beyond the coordinate range (core/validate.hpp) were accepted. Each throws
// InvalidInput naming the argument, and a rejected edit leaves the scene unchanged.
#include "impact/broad/scene.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace impact {
namespace {

template <class F> void expect_invalid(F&& f, const char* needle) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected InvalidInput mentioning " << needle;
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(SceneValidation, OptionsOutsideTheirRangesThrow) {
  auto with = [](auto set) {
    SceneOptions o;
    set(o);
    return o;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_invalid([&] { Scene<double>{with([](SceneOptions& o) { o.broad_phase = static_cast<BroadPhaseKind>(7); })}; }, "options.broad_phase");
  expect_invalid([&] { Scene<double>{with([](SceneOptions& o) { o.static_leaf_size = 0; })}; }, "options.static_leaf_size");
  expect_invalid([&] { Scene<float>{with([&](SceneOptions& o) { o.tree.fat_fraction = nan; })}; }, "options.tree.fat_fraction");
  expect_invalid([&] { Scene<float>{with([&](SceneOptions& o) { o.tree.fat_margin = -1; })}; }, "options.tree.fat_margin");
  expect_invalid([&] { Scene<double>{with([&](SceneOptions& o) { o.tree.predict = nan; })}; }, "options.tree.predict");
  expect_invalid([&] { Scene<double>{with([&](SceneOptions& o) { o.tree.rebuild_ratio = 0.5; })}; }, "options.tree.rebuild_ratio");
  EXPECT_NO_THROW((Scene<double>{with([](SceneOptions& o) { o.static_leaf_size = 1, o.tree.rebuild_ratio = 1; })}));
}

template <class S> void run_range() {
  Scene<S> s;
  s.add(1, Shape<S>::sphere(S(1)), RigidTransform<S>());
  const S big = CoordinateRange<S>::max * S(2);
  expect_invalid([&] { s.add(2, Shape<S>::sphere(S(1)), RigidTransform<S>(Mat3<S>::Identity(), Vec3<S>(big, 0, 0))); }, "pose of object 2.t");
  expect_invalid([&] { s.add(3, Shape<S>::sphere(big), RigidTransform<S>()); }, "radius");
  expect_invalid([&] { s.add(4, Shape<S>::box(Vec3<S>(1, big, 1)), RigidTransform<S>()); }, "half extent");
  expect_invalid([&] { s.set_pose(1, RigidTransform<S>(Mat3<S>::Identity(), Vec3<S>(0, 0, -big))); }, "pose of object 1.t");
  EXPECT_EQ(s.size(), 1u);
  EXPECT_EQ(s.pose(1).t, Vec3<S>::Zero());
}

TEST(SceneValidation, CoordinatesBeyondTheRangeThrowFloat) { run_range<float>(); }
TEST(SceneValidation, CoordinatesBeyondTheRangeThrowDouble) { run_range<double>(); }

}  // namespace
}  // namespace impact
