// SPDX-License-Identifier: MIT
// The collision step on the relative motions that stacked cloth makes, against the all-pairs CCD
// and sampled-distance oracles (cloth_oracles.hpp): a stack falling together (every sheet's swept
// box covers the sheets below, while relative to each other they barely move), sheets moving
// against each other (shearing past, and meeting head-on), and a sheet stopped by the floor
// while the sheet above keeps falling with it until it lands. These are the cases a broad phase
// that tests pairs in relative motion (docs/cloth-history.md, 2026-12-07) must keep right: the
// pairs it drops while sheets move together, and those whose relative motion changes within
// the step.
#include "cloth_oracles.hpp"
#include "impact/cloth/collision_step.hpp"
#include "scenes.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace {

using namespace impact;
using cloth_test::combine;

template <class S>
class RelativeMotions : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(RelativeMotions, Scalars);

/// Sheets of n x n cells over [-0.5, 0.5]^2 at heights z, one mesh, all movable.
template <class S>
struct Stack {
  TriangleMesh<S> m;
  Eigen::Matrix<S, Eigen::Dynamic, 1> w;
  Stack(int n, const std::vector<double>& z) : m(cloth_test::layers<S>(n, z)) { w = Eigen::Matrix<S, Eigen::Dynamic, 1>::Ones(m.V.rows()); }
};

// Six sheets 1.5 h apart fall 20 h together and drift 3 h sideways (each vertex's displacement off
// the common one by up to 0.05 h): every sheet's swept box covers the sheets below, while in
// relative motion only neighbouring sheets are near (and the jitter makes some of them approach).
// The oracles find nothing within h.
TYPED_TEST(RelativeMotions, StackFallingTogether) {
  using S = TypeParam;
  const double h = 1e-3;
  Stack<S> st(5, {0, 1.5 * h, 3 * h, 4.5 * h, 6 * h, 7.5 * h});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1, 1);
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  const Vertices<S> x0 = st.m.V;
  Vertices<S> x1 = x0;
  for (Eigen::Index i = 0; i < x1.rows(); ++i) {
    x1(i, 0) += S(3 * h + 0.05 * h * U(rng));
    x1(i, 1) += S(0.05 * h * U(rng));
    x1(i, 2) += S(-20 * h + 0.05 * h * U(rng));
  }
  const auto falling = cloth_collision_step(st.m.F, st.w, x0, x1, ClothObstacles<S>{}, o);
  EXPECT_TRUE(falling.collision_free);
  EXPECT_GT(falling.candidates_vf + falling.candidates_ee, 0u);
  const auto c = combine(st.m.F, x0, x1, ClothObstacles<S>{});
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c, 16, 2 * h), h);
}

// Sheets moving against each other: two sheets 1.5 h apart shear past each other in opposite
// directions (a cell and a half each way), and two sheets 12 h apart move 8 h towards each other
// (they would pass through each other). In relative motion both sweep far; every pair that comes
// within h must be found: the step ends collision-free by the oracles.
TYPED_TEST(RelativeMotions, OppositeMotionsAreFound) {
  using S = TypeParam;
  const double h = 1e-3;
  for (int scene = 0; scene < 2; ++scene) {
    const double gap = scene == 0 ? 1.5 * h : 12 * h;
    Stack<S> st(5, {0, gap});
    const Eigen::Index half = st.m.V.rows() / 2;
    std::mt19937 rng(5 + scene);
    std::uniform_real_distribution<double> U(-1, 1);
    ClothCollisionOptions<S> o;
    o.thickness = S(h);
    const Vertices<S> x0 = st.m.V;
    Vertices<S> x1 = x0;
    for (Eigen::Index i = 0; i < x1.rows(); ++i) {
      const double sign = i < half ? 1 : -1;
      if (scene == 0) {
        x1(i, 0) += S(sign * 0.3 + 0.1 * h * U(rng));
        x1(i, 1) += S(-sign * 0.1 + 0.1 * h * U(rng));
      } else {
        x1(i, 2) += S(sign * 8 * h + 0.1 * h * U(rng));
      }
    }
    const auto stats = cloth_collision_step(st.m.F, st.w, x0, x1, ClothObstacles<S>{}, o);
    EXPECT_TRUE(stats.collision_free) << "scene " << scene;
    if (scene == 1) {
      EXPECT_GT(stats.impulses.collisions + stats.proximity.collisions + stats.zones.collisions, 0u);
    }
    const auto c = combine(st.m.F, x0, x1, ClothObstacles<S>{});
    EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0) << "scene " << scene;
    EXPECT_GE(cloth_test::sampled_min_distance(c, 16, 2 * h), h) << "scene " << scene;
  }
}

// Sheet A falls 10 h onto a static floor 2 h below it, and sheet B falls with it, 3 h above A
// (beyond the proximity distance): relative to each other they keep their gap until the floor
// stops A, and then B falls onto A. B must end resting on A, and the oracles find nothing
// within h.
TYPED_TEST(RelativeMotions, SheetFallsOntoASheetStoppedUnderIt) {
  using S = TypeParam;
  const double h = 1e-3;
  Stack<S> st(4, {2 * h, 5 * h});
  const Vertices<S> floor = cloth_test::quad<S>(2, 0);
  const Faces qf = cloth_test::quad_faces();
  ClothObstacles<S> obs;
  obs.kinematic.push_back({&floor, &floor, &qf});
  ClothCollisionOptions<S> o;
  o.thickness = S(h);
  const Vertices<S> x0 = st.m.V;
  Vertices<S> x1 = x0;
  x1.col(2).array() -= S(10 * h);
  const auto stats = cloth_collision_step(st.m.F, st.w, x0, x1, obs, o);
  EXPECT_TRUE(stats.collision_free);
  const Eigen::Index half = x0.rows() / 2;
  for (Eigen::Index i = half; i < x1.rows(); ++i) EXPECT_GT(double(x1(i, 2)), 1.9 * h) << "vertex " << i;  // B rests on A
  const auto c = combine(st.m.F, x0, x1, obs);
  EXPECT_EQ(cloth_test::all_pairs_ccd_hits(c, h), 0);
  EXPECT_GE(cloth_test::sampled_min_distance(c, 16, 2 * h), h);
}

}  // namespace
