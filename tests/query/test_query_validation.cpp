// SPDX-License-Identifier: MIT
// Argument checks of the public queries (issue 12, D9, D10, D13): a NaN, scaled, sheared or
// mirrored pose, a bad ray, a bad radius or start node, a negative or NaN max_distance and a grid
// config out of its ranges each throw InvalidInput naming the argument, where they used to give a
// silent wrong answer (a crossing pair reported apart, a hit with t = NaN, a wrong distance), an
// integer overflow or a huge allocation. Valid edge values (a rotation rounded to float, t_max = 0
// or infinity, max_distance = 0) still pass. Float and double.
#include "impact/bvh/compact_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/distance_grid.hpp"
#include "impact/query/mesh_collide.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/swept_sphere_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace impact {
namespace {

/// Runs f, expects InvalidInput whose message contains every needle.
template <class F> void expect_invalid(F&& f, std::initializer_list<const char*> needles) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected InvalidInput mentioning " << *needles.begin();
  } catch (const InvalidInput& e) {
    for (const char* n : needles) EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what() << " lacks " << n;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

template <class T> class QueryValidation : public ::testing::Test {};
using ValidationBVs = ::testing::Types<Aabb<float>, Aabb<double>, Sphere<float>, Sphere<double>>;
TYPED_TEST_SUITE(QueryValidation, ValidationBVs);

template <class S> RigidTransform<S> nan_pose() {
  RigidTransform<S> p;
  p.t.x() = std::numeric_limits<S>::quiet_NaN();
  return p;
}
template <class S> RigidTransform<S> scaled_pose(S k) { return {Mat3<S>::Identity() * k, Vec3<S>::Zero()}; }
template <class S> RigidTransform<S> mirrored_pose() {
  Mat3<S> m = Mat3<S>::Identity();
  m(0, 0) = S(-1);
  return {m, Vec3<S>::Zero()};
}

// D9: two unit boxes crossing at the origin. Before the checks, a NaN pose made collides() false
// and a scale of 3 missed the crossing.
TYPED_TEST(QueryValidation, CollidePosesAreChecked) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> a(make_box<S>(Vec3<S>::Constant(S(1)))), b(make_box<S>(Vec3<S>::Constant(S(1))));
  const RigidTransform<S> cross({Mat3<S>(Eigen::AngleAxis<S>(S(0.5), Vec3<S>::UnitZ())), Vec3<S>(S(1.5), S(0.2), S(0.1))});
  ASSERT_TRUE(collides(a, RigidTransform<S>(), b, cross));
  expect_invalid([&] { collides(a, RigidTransform<S>(), b, nan_pose<S>()); }, {"collides", "pose_b", "finite"});
  expect_invalid([&] { collides(a, nan_pose<S>(), b, cross); }, {"collides", "pose_a", "finite"});
  expect_invalid([&] { collides(a, scaled_pose<S>(S(3)), b, cross); }, {"collides", "pose_a", "rotation"});
  expect_invalid([&] { collides(a, RigidTransform<S>(), b, mirrored_pose<S>()); }, {"collides", "pose_b", "rotation"});
  expect_invalid([&] { collide(a, RigidTransform<S>(), b, scaled_pose<S>(S(3))); }, {"collide", "pose_b", "rotation"});
  expect_invalid([&] { collide(a, nan_pose<S>(), b, cross); }, {"collide", "pose_a"});
  // a shear that keeps det R = 1 is not a rotation either
  Mat3<S> shear = Mat3<S>::Identity();
  shear(0, 1) = S(0.01);
  expect_invalid([&] { collides(a, RigidTransform<S>(shear, Vec3<S>::Zero()), b, cross); }, {"rotation"});
}

// The pose check's boundaries, entry by entry: an infinite or NaN entry anywhere in R or t, a
// translation beyond CoordinateRange, and a departure of R^T R from I just above the tolerance
// in any one entry (a column's norm or two columns' dot product) are refused; just below, and an
// exact rotation by any angle, pass. Then det R decides: a rotation composed with a mirror fails.
TYPED_TEST(QueryValidation, PoseCheckBoundaries) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> a(make_box<S>(Vec3<S>::Constant(S(1))));
  const Mat3<S> rot = Eigen::AngleAxis<S>(S(2.1), Vec3<S>(S(1), S(-2), S(0.5)).normalized()).toRotationMatrix();
  const Vec3<S> t(S(0.3), S(0.1), S(-0.2));
  EXPECT_NO_THROW(collides(a, RigidTransform<S>(), a, RigidTransform<S>(rot, t)));
  for (int i = 0; i < 12; ++i)
    for (const S bad : {std::numeric_limits<S>::infinity(), -std::numeric_limits<S>::infinity(), std::numeric_limits<S>::quiet_NaN()}) {
      RigidTransform<S> p(rot, t);
      if (i < 9) {
        p.R(i / 3, i % 3) = bad;
      } else {
        p.t(i - 9) = bad;
      }
      expect_invalid([&] { collides(a, RigidTransform<S>(), a, p); }, {"collides", "pose_b", "finite"});
    }
  for (int i = 0; i < 3; ++i) {
    RigidTransform<S> p(rot, t);
    p.t(i) = S(2) * CoordinateRange<S>::max;
    expect_invalid([&] { collides(a, p, a, RigidTransform<S>()); }, {"collides", "pose_a"});
  }
  const S tol = rotation_tolerance<S>();
  for (int c = 0; c < 3; ++c) {
    // scaling column c by (1 + e) moves its squared norm by about 2e
    for (const S e : {S(0.25) * tol, S(2) * tol}) {
      Mat3<S> m = rot;
      m.col(c) *= S(1) + e;
      const RigidTransform<S> p(m, t);
      if (e < tol) {
        EXPECT_NO_THROW(collides(a, RigidTransform<S>(), a, p)) << "column " << c;
      } else {
        expect_invalid([&] { collides(a, RigidTransform<S>(), a, p); }, {"pose_b", "rotation"});
      }
    }
    // tilting column c towards the next one by e makes their dot product about e
    for (const S e : {S(0.25) * tol, S(2) * tol}) {
      Mat3<S> m = rot;
      m.col(c) = (m.col(c) + e * m.col((c + 1) % 3)).normalized();
      const RigidTransform<S> p(m, t);
      if (e < tol) {
        EXPECT_NO_THROW(collides(a, RigidTransform<S>(), a, p)) << "column " << c;
      } else {
        expect_invalid([&] { collides(a, RigidTransform<S>(), a, p); }, {"pose_b", "rotation"});
      }
    }
  }
  Mat3<S> mirrored = rot;
  mirrored.col(1) = -mirrored.col(1);
  expect_invalid([&] { collides(a, RigidTransform<S>(), a, RigidTransform<S>(mirrored, t)); }, {"pose_b", "rotation"});
}

// A rotation computed in double and rounded to float, then used in double, passes (the tolerance
// is 1e-6 in double for this).
TEST(QueryValidation, RotationRoundedToFloatPasses) {
  const MeshBvh<Aabb<double>> a(make_box<double>(Eigen::Vector3d::Constant(1)));
  for (int k = 1; k < 50; ++k) {
    const Eigen::Matrix3f rf = Eigen::AngleAxisf(0.37f * float(k), Eigen::Vector3f(1, 2, 3).normalized()).toRotationMatrix();
    const RigidTransform<double> p(rf.cast<double>(), Eigen::Vector3d(0.5, 0, 0));
    EXPECT_TRUE(collides(a, RigidTransform<double>(), a, p));
  }
}

// D9: a NaN pose gave a hit with t = NaN through a CompactBvh; a scaled pose a wrong t.
TYPED_TEST(QueryValidation, RayCastsCheckRayAndPose) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> m(make_icosphere<S>(S(1), 2));
  const Ray<S> ray(Vec3<S>(S(-5), S(0.1), S(0.05)), Vec3<S>::UnitX());
  ASSERT_TRUE(ray_mesh_first_hit(m, ray).has_value());
  const S nan = std::numeric_limits<S>::quiet_NaN(), inf = std::numeric_limits<S>::infinity();
  expect_invalid([&] { ray_mesh_first_hit(m, ray, nan_pose<S>()); }, {"ray_mesh_first_hit", "pose"});
  expect_invalid([&] { ray_mesh_first_hit(m, ray, scaled_pose<S>(S(2))); }, {"ray_mesh_first_hit", "pose.R"});
  expect_invalid([&] { ray_mesh_any_hit(m, ray, scaled_pose<S>(S(2))); }, {"ray_mesh_any_hit", "pose.R"});
  expect_invalid([&] { ray_mesh_any_hit(m, ray, nan_pose<S>()); }, {"ray_mesh_any_hit", "pose"});
  expect_invalid([&] { swept_sphere_mesh_first_hit(m, ray, S(0.1), nan_pose<S>()); }, {"swept_sphere_mesh_first_hit", "pose"});
  // the ray itself
  expect_invalid([&] { ray_mesh_first_hit(m, Ray<S>(Vec3<S>(nan, 0, 0), Vec3<S>::UnitX())); }, {"ray.origin"});
  expect_invalid([&] { ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>(inf, 0, 0))); }, {"ray.direction"});
  expect_invalid([&] { ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>::Zero())); }, {"ray.direction", "non-zero"});
  expect_invalid([&] { ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>::UnitX(), nan)); }, {"ray.t_max"});
  expect_invalid([&] { ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>::UnitX(), S(-1))); }, {"ray.t_max"});
  expect_invalid([&] { ray_mesh_any_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>::UnitX(), nan)); }, {"ray_mesh_any_hit", "ray.t_max"});
  expect_invalid([&] { ray_mesh_first_hit(m, ray, RigidTransform<S>(), nullptr, -1); }, {"start_node"});
  expect_invalid([&] { ray_mesh_first_hit(m, ray, RigidTransform<S>(), nullptr, std::int32_t(m.tree().nodes.size())); }, {"start_node"});
  // the radius of a swept sphere
  expect_invalid([&] { swept_sphere_mesh_first_hit(m, ray, nan); }, {"swept_sphere_mesh_first_hit", "radius"});
  expect_invalid([&] { swept_sphere_mesh_first_hit(m, ray, S(-0.5)); }, {"radius"});
  expect_invalid([&] { swept_sphere_mesh_first_hit(m, ray, inf); }, {"radius"});
  expect_invalid([&] { swept_sphere_mesh_first_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>::Zero()), S(0.1)); }, {"ray.direction"});
  // edge values that are valid
  EXPECT_FALSE(ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-5, 0, 0), Vec3<S>::UnitX(), S(0))).has_value());
  EXPECT_TRUE(swept_sphere_mesh_first_hit(m, ray, S(0)).has_value());
}

// D9 through a CompactBvh: a NaN pose returned a hit with t = NaN; a CompactBvh of another tree
// was an assert only.
TEST(QueryValidation, CompactRayCastChecks) {
  using S = double;
  const MeshBvh<Aabb<S>> m(make_icosphere<S>(1, 2)), other(make_icosphere<S>(1, 1));
  const CompactBvh fast(m.tree()), wrong(other.tree());
  const Ray<S> ray(Vec3<S>(-5, 0.1, 0.05), Vec3<S>::UnitX());
  ASSERT_TRUE(ray_mesh_first_hit(m, fast, ray).has_value());
  expect_invalid([&] { ray_mesh_first_hit(m, fast, ray, nan_pose<S>()); }, {"ray_mesh_first_hit", "pose"});
  expect_invalid([&] { ray_mesh_first_hit(m, fast, ray, scaled_pose<S>(3)); }, {"pose.R"});
  expect_invalid([&] { ray_mesh_first_hit(m, fast, Ray<S>(ray.origin, Vec3<S>::Zero())); }, {"ray.direction"});
  expect_invalid([&] { ray_mesh_first_hit(m, wrong, ray); }, {"CompactBvh"});
  // a leaf size below 1 was documented only
  expect_invalid([&] { CompactBvh(m.tree(), 0); }, {"CompactBvh", "leaf_size"});
  expect_invalid([&] { CompactBvh(m.tree(), -4); }, {"leaf_size"});
  EXPECT_NO_THROW(CompactBvh(m.tree(), 1));
}

// D9: R = 2 I gave a wrong distance. D10: max_distance < 0 acted as its absolute value, NaN as
// no limit.
TYPED_TEST(QueryValidation, ClosestPointChecks) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> m(make_icosphere<S>(S(1), 2));
  const Vec3<S> q(S(0), S(0), S(1.5));
  ASSERT_TRUE(closest_point_on_mesh(m, q).has_value());
  expect_invalid([&] { closest_point_on_mesh(m, q, scaled_pose<S>(S(2))); }, {"closest_point_on_mesh", "pose.R"});
  expect_invalid([&] { closest_point_on_mesh(m, q, nan_pose<S>()); }, {"closest_point_on_mesh", "pose"});
  expect_invalid([&] { closest_point_on_mesh(m, q, mirrored_pose<S>()); }, {"pose.R"});
  expect_invalid([&] { closest_point_on_mesh(m, Vec3<S>(0, std::numeric_limits<S>::infinity(), 0)); }, {"query"});
  ClosestPointOptions<S> o;
  o.max_distance = S(-1);
  expect_invalid([&] { closest_point_on_mesh(m, q, RigidTransform<S>(), o); }, {"options.max_distance"});
  o.max_distance = std::numeric_limits<S>::quiet_NaN();
  expect_invalid([&] { closest_point_on_mesh(m, q, RigidTransform<S>(), o); }, {"options.max_distance"});
  o.max_distance = -std::numeric_limits<S>::infinity();
  expect_invalid([&] { closest_point_on_mesh(m, q, RigidTransform<S>(), o); }, {"options.max_distance"});
  // valid limits: 0 (only points on the surface), a finite bound, infinity
  o.max_distance = S(0);
  EXPECT_FALSE(closest_point_on_mesh(m, q, RigidTransform<S>(), o).has_value());
  o.max_distance = S(0.4);
  EXPECT_FALSE(closest_point_on_mesh(m, q, RigidTransform<S>(), o).has_value());
  o.max_distance = S(0.6);
  EXPECT_TRUE(closest_point_on_mesh(m, q, RigidTransform<S>(), o).has_value());
}

// D13: the resolution overflowed a signed int (UB) or threw bad_alloc / length_error; 0 was
// silently taken as 1, a negative padding as 0, a NaN reach as none.
TYPED_TEST(QueryValidation, DistanceGridConfigChecks) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> m(make_icosphere<S>(S(1), 1));
  auto with = [&](auto set) {
    DistanceGridConfig<S> c;
    c.resolution = 4;
    set(c);
    return c;
  };
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.resolution = 0; })); }, {"DistanceGrid", "config.resolution"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.resolution = -3; })); }, {"config.resolution"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.resolution = 1 << 30; })); }, {"config.resolution"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.resolution = std::numeric_limits<int>::max(); })); }, {"config.resolution"});
  // within the resolution's range, but too many cells in all
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.resolution = 4096; })); }, {"cells", "exceed"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.padding = 1000; })); }, {"cells", "exceed"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.padding = -1; })); }, {"config.padding"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.padding = 1 << 30; })); }, {"config.padding"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.max_distance = std::numeric_limits<S>::quiet_NaN(); })); },
                 {"config.max_distance"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.max_distance = S(-1); })); }, {"config.max_distance"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.start_node_reach = std::numeric_limits<S>::quiet_NaN(); })); },
                 {"config.start_node_reach"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.start_node_reach = S(-1); })); }, {"config.start_node_reach"});
  expect_invalid([&] { DistanceGrid<S>(m, with([](auto& c) { c.start_node_reach = S(1e9); })); }, {"config.start_node_reach"});
  // the edges of the ranges are valid
  const DistanceGrid<S> g1(m, with([](auto& c) { c.resolution = 1, c.padding = 0, c.max_distance = S(0), c.start_node_reach = S(0); }));
  EXPECT_EQ(g1.dims(), Eigen::Vector3i(1, 1, 1));
  const DistanceGrid<S> g2(m, with([](auto& c) { c.resolution = 2, c.padding = 1; }));
  EXPECT_EQ(g2.dims(), Eigen::Vector3i(4, 4, 4));
}

}  // namespace
}  // namespace impact
