// SPDX-License-Identifier: MIT
// The cylinder–cylinder boolean test (convex/cylinder_intersect.hpp, convex_intersect's path for
// the pair): its separating and proving steps against closed forms at 1e-7 either side of
// touching (crossing axes, a cap against a side, a stack), and every step against the oracles of
// support/convex_oracle.hpp on random cylinders of varied proportions, double and float: apart
// where the certified distance bracket (the ellipsoid method on the supports) puts the distance
// above 1e-6 of the size, intersecting where the bracket allows no distance and the direction
// search finds no overlap below 1e-6 of the size (as tests/convex/test_convex_fcl.cpp decides).
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace impact;

RigidTransform<double> pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) { return {R, t}; }

// b's axis turned from a's (z) by `angle` about y, b placed at offset d along y: the axes' common
// normal is y, so they intersect exactly when d <= ra + rb (the closest points are inside both
// segments: step 3's exact branch).
TEST(CylinderIntersect, CrossingAxesAtTheRadiiSum) {
  const Cylinder<double> a(0.4, 0.5), b(0.25, 0.8);
  const RigidTransform<double> pa = pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  for (const double angle : {M_PI / 2, M_PI / 6, 1.2}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
    for (const double shift : {0.0, 0.2, -0.3}) {  // along a's axis, within both segments
      for (const double eps : {1e-7, -1e-7, 0.05, -0.05}) {
        const Eigen::Vector3d t(0, 0.65 + eps, shift);
        const bool hit = convex_intersect(a, pa, b, pose(R, t));
        EXPECT_EQ(hit, eps < 0) << "angle " << angle << " shift " << shift << " eps " << eps;
        EXPECT_EQ(convex_intersect(b, pose(R, t), a, pa), eps < 0);
      }
    }
  }
}

// b's cap against a's side (a T): b along x, its cap's centre at distance ra + eps from a's axis;
// they touch exactly at eps = 0 (the cap is a tangent plane of a's side there).
TEST(CylinderIntersect, CapAgainstSide) {
  const Cylinder<double> a(0.4, 0.5), b(0.3, 0.6);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (const double z : {0.0, 0.3, -0.45}) {
    for (const double eps : {1e-7, -1e-7, 0.01, -0.01}) {
      const RigidTransform<double> pa = pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1, 2, 3));
      const RigidTransform<double> pb = pose(R, Eigen::Vector3d(1 + 0.4 + 0.6 + eps, 2, 3 + z));
      EXPECT_EQ(convex_intersect(a, pa, b, pb), eps < 0) << "z " << z << " eps " << eps;
      EXPECT_EQ(convex_intersect(b, pb, a, pa), eps < 0) << "z " << z << " eps " << eps;
    }
  }
}

// Parallel axes (no common normal): b stacked on a's cap, offset sideways, its lower cap eps above
// a's upper cap; and side by side, eps apart.
TEST(CylinderIntersect, ParallelStacksAndNeighbours) {
  const Cylinder<double> a(0.4, 0.5), b(0.3, 0.2);
  const RigidTransform<double> pa = pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  for (const Eigen::Matrix3d& R : {Eigen::Matrix3d(Eigen::Matrix3d::Identity()),
                                   Eigen::Matrix3d(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix())}) {
    for (const double eps : {1e-7, -1e-7, 0.02, -0.02}) {
      for (const double side : {0.0, 0.35, 0.69}) {
        EXPECT_EQ(convex_intersect(a, pa, b, pose(R, Eigen::Vector3d(side, 0, 0.7 + eps))), eps < 0) << "side " << side << " eps " << eps;
      }
      EXPECT_EQ(convex_intersect(a, pa, b, pose(R, Eigen::Vector3d(0, 0.7 + eps, 0.1))), eps < 0) << "eps " << eps;
    }
  }
}

// Random cylinders (radius and half length 0.02 .. 1, so needles and discs too) about each other,
// 10 % with parallel axes: the answer against the oracles, double and float.
TEST(CylinderIntersect, MatchesTheOracles) {
  test::Rng rng(2026);
  const int n = IMPACT_TEST_SANITIZED ? 60 : 600;
  int compared = 0, hits = 0;
  for (int k = 0; k < n; ++k) {
    const Cylinder<double> a(rng.uniform(0.02, 1.0), rng.uniform(0.02, 1.0)), b(rng.uniform(0.02, 1.0), rng.uniform(0.02, 1.0));
    const double scale = std::max(shape_size(a), shape_size(b)), reach = 0.8 * (shape_size(a) + shape_size(b));
    const RigidTransform<double> pa = pose(rng.rotation(), rng.vec(-2, 2));
    const RigidTransform<double> pb = pose(k % 10 == 0 ? pa.R : rng.rotation(), Eigen::Vector3d(pa.t + rng.vec(-reach, reach)));
    const auto br = test::distance_bracket(a, pa, b, pb, 600);
    const bool separated = br.lower > 1e-6 * scale;
    const double depth = separated ? 0.0 : -test::signed_distance_oracle(a, pa, b, pb, 1500, 1).value;
    const bool intersecting = !separated && br.upper < 1e-9 * scale && depth > 1e-6 * scale;
    if (!separated && !intersecting) continue;
    ++compared;
    hits += intersecting;
    bool limit = true;
    EXPECT_EQ(convex_intersect(a, pa, b, pb, {}, &limit), intersecting) << "pose " << k << ", bracket [" << br.lower << ", " << br.upper << "]";
    EXPECT_FALSE(limit);
    EXPECT_EQ(convex_intersect(b, pb, a, pa), intersecting) << "pose " << k;
    if (std::max(br.lower, depth) > 1e-4 * scale) {  // float: away from touching by its rounding
      const Cylinder<float> af(float(a.radius), float(a.half_length)), bf(float(b.radius), float(b.half_length));
      const RigidTransform<float> paf{pa.R.cast<float>(), pa.t.cast<float>()}, pbf{pb.R.cast<float>(), pb.t.cast<float>()};
      EXPECT_EQ(convex_intersect(af, paf, bf, pbf), intersecting) << "float, pose " << k;
    }
  }
  EXPECT_GT(compared, n * 9 / 10);
  EXPECT_GT(hits, compared / 5);
  EXPECT_LT(hits, compared * 4 / 5);
}

}  // namespace
