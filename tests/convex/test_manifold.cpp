// SPDX-License-Identifier: MIT
// Contact manifolds (convex/manifold.hpp): face–face configurations whose contact points and
// depths are known in closed form (a box resting on a box, overhanging it, tilted on it; a hull
// cube on a box), edge contacts with one point, and on random poses the manifold's invariants: at
// most four points, depths >= 0 and at most the overlap of the shapes along the manifold's normal.
#include "impact/convex/manifold.hpp"
#include "support/convex_oracle.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

namespace {

using namespace impact;
using V3 = Eigen::Vector3d;
using Pose = RigidTransform<double>;

Pose about_z(double angle, const V3& t) { return {Eigen::AngleAxisd(angle, V3::UnitZ()).toRotationMatrix(), t}; }

// Is x one of the points (within tol)?
bool has_point(const ConvexManifold<double>& m, const V3& x, double tol) {
  for (int i = 0; i < m.count; ++i)
    if ((m.points[static_cast<std::size_t>(i)] - x).norm() <= tol) return true;
  return false;
}

TEST(ConvexManifold, BoxRestingOnABoxHasFourPoints) {
  const Box<double> ground(V3(1, 1, 0.5)), block(V3(0.3, 0.4, 0.2));
  const Pose pa;  // ground top face at z = 0.5
  const double pen = 0.01;
  const Pose pb = about_z(0.3, V3(0.1, -0.2, 0.5 + 0.2 - pen));
  const auto m = convex_manifold(ground, pa, block, pb);
  ASSERT_EQ(m.count, 4);
  EXPECT_LE((m.normal - V3::UnitZ()).norm(), 1e-12);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.depths[static_cast<std::size_t>(i)], pen, 1e-12);
  // the block's bottom corners, lifted by half the depth
  for (int sx : {-1, 1})
    for (int sy : {-1, 1}) EXPECT_TRUE(has_point(m, pb.apply(V3(sx * 0.3, sy * 0.4, -0.2)) + V3(0, 0, pen / 2), 1e-12));
  // and the other way round: normal from the block towards the ground
  const auto r = convex_manifold(block, pb, ground, pa);
  ASSERT_EQ(r.count, 4);
  EXPECT_LE((r.normal + V3::UnitZ()).norm(), 1e-12);
}

TEST(ConvexManifold, OverhangingBoxIsClippedByTheSupportFace) {
  const Box<double> ground(V3(1, 1, 0.5)), block(V3(0.5, 0.5, 0.2));
  const double pen = 0.02;
  const Pose pb(Eigen::Matrix3d::Identity(), V3(0.8, 0.0, 0.5 + 0.2 - pen));  // block spans x in [0.3, 1.3]
  const auto m = convex_manifold(ground, Pose(), block, pb);
  ASSERT_EQ(m.count, 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(m.depths[static_cast<std::size_t>(i)], pen, 1e-12);
    EXPECT_LE(m.points[static_cast<std::size_t>(i)].x(), 1 + 1e-12);  // clipped at the ground's edge x = 1
  }
  for (double x : {0.3, 1.0})
    for (double y : {-0.5, 0.5}) EXPECT_TRUE(has_point(m, V3(x, y, 0.5 - pen / 2), 1e-12));
}

TEST(ConvexManifold, SlightlyTiltedBoxTouchesAlongAnEdge) {
  // tilted by 0.02 rad about y: the bottom face's corners at x = +0.3 sink deeper than those at -0.3
  const Box<double> ground(V3(1, 1, 0.5)), block(V3(0.3, 0.4, 0.2));
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.02, V3::UnitY()).toRotationMatrix();
  const V3 low = R * V3(0.3, 0, -0.2), high = R * V3(-0.3, 0, -0.2);
  ASSERT_LT(low.z(), high.z());
  const double pen = 0.004;
  // place the deepest corners at 0.5 - pen; the others are then above the ground (0.6 sin 0.02 = 0.012 higher)
  const Pose pb(R, V3(0, 0, 0.5 - pen - low.z()));
  const auto m = convex_manifold(ground, Pose(), block, pb);
  ASSERT_EQ(m.count, 2);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.depths[static_cast<std::size_t>(i)], pen, 1e-12);
  const auto c = convex_penetration(ground, Pose(), block, pb);
  EXPECT_NEAR(c.depth, pen, 1e-12);
}

TEST(ConvexManifold, HullCubeOnABox) {
  Vertices<double> p(27, 3);
  int k = 0;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) p.row(k++) = V3(0.25 * x, 0.25 * y, 0.25 * z).transpose();
  const auto cube = convex_hull(p);
  ASSERT_EQ(cube.faces.size(), 6u);
  const Box<double> ground(V3(1, 1, 0.5));
  const double pen = 0.03;
  const Pose pb = about_z(-0.7, V3(0.2, 0.1, 0.5 + 0.25 - pen));
  const auto m = convex_manifold(ground, Pose(), cube, pb);
  ASSERT_EQ(m.count, 4);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.depths[static_cast<std::size_t>(i)], pen, 1e-12);
  for (int sx : {-1, 1})
    for (int sy : {-1, 1}) EXPECT_TRUE(has_point(m, pb.apply(V3(sx * 0.25, sy * 0.25, -0.25)) + V3(0, 0, pen / 2), 1e-12));
}

TEST(ConvexManifold, EdgeContactsAndCurvedShapesGiveOnePoint) {
  const Box<double> a(V3(0.5, 0.5, 0.5));
  // b's edge (rotated 45 degrees about x) pushed into a's edge (rotated 45 degrees about y... a stays
  // axis-aligned: b's bottom edge crosses a's top face diagonally -> edge–face, one face aligned)
  const Pose pa{Eigen::AngleAxisd(M_PI / 4, V3::UnitY()).toRotationMatrix(), V3::Zero()};
  const Pose pb{Eigen::AngleAxisd(M_PI / 4, V3::UnitX()).toRotationMatrix(), V3(0, 0, std::sqrt(2.0) - 0.01)};
  const auto m = convex_manifold(a, pa, a, pb);
  ASSERT_TRUE(convex_penetration(a, pa, a, pb).intersecting);
  EXPECT_EQ(m.count, 1);
  const Capsule<double> cap(0.3, 0.5);
  const auto mc = convex_manifold(cap, Pose(), a, Pose(Eigen::Matrix3d::Identity(), V3(0.7, 0, 0)));
  EXPECT_EQ(mc.count, 1);
  EXPECT_NEAR(mc.depths[0], 0.1, 1e-9);
  const auto none = convex_manifold(cap, Pose(), a, Pose(Eigen::Matrix3d::Identity(), V3(2, 0, 0)));
  EXPECT_EQ(none.count, 0);
}

TEST(ConvexManifold, RandomPosesKeepTheInvariants) {
  const test::ConvexZoo z;
  int multi = 0;
  for (const auto& [pa, pb] : test::convex_poses(IMPACT_TEST_SANITIZED ? 60 : 400, 0.8, 91)) {
    for (int which = 0; which < 2; ++which) {
      const auto m = which == 0 ? convex_manifold(z.box, pa, z.hull, pb) : convex_manifold(z.box, pa, z.box, pb);
      const double overlap = which == 0 ? test::overlap_along(z.box, pa, z.hull, pb, m.normal) : test::overlap_along(z.box, pa, z.box, pb, m.normal);
      ASSERT_LE(m.count, 4);
      EXPECT_NEAR(m.normal.norm(), 1.0, 1e-12);
      multi += m.count > 1;
      for (int i = 0; i < m.count; ++i) {
        EXPECT_GE(m.depths[static_cast<std::size_t>(i)], 0.0);
        EXPECT_LE(m.depths[static_cast<std::size_t>(i)], overlap + 1e-9);
      }
      for (int i = 0; i < m.count; ++i)
        for (int j = i + 1; j < m.count; ++j)
          EXPECT_GT((m.points[static_cast<std::size_t>(i)] - m.points[static_cast<std::size_t>(j)]).norm(), 0.0) << "duplicate point";
    }
  }
  EXPECT_GT(multi, 0);
}

}  // namespace
