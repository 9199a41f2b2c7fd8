// SPDX-License-Identifier: MIT
// respond(): restitution, Coulomb friction with sticking, resting threshold, moving colliders;
// the colliders' local queries (plane, sphere, box, mesh; solid and container).
#include "impact/response/collider.hpp"
#include "impact/response/response.hpp"

#include <gtest/gtest.h>

namespace impact {
namespace {

template <class T> class Response : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(Response, Scalars);

TYPED_TEST(Response, RestitutionSplitsNormalAndTangential) {
  using S = TypeParam;
  const Vec3<S> n = Vec3<S>::UnitZ();
  const Vec3<S> v(3, -1, -4);
  for (S eps : {S(0), S(0.25), S(0.5), S(1)}) {
    const auto r = respond<S>(v, n, Vec3<S>::Zero(), Material<S>{eps, S(0)});
    EXPECT_TRUE(r.approaching);
    EXPECT_NEAR(r.velocity.x(), S(3), S(1e-6));
    EXPECT_NEAR(r.velocity.y(), S(-1), S(1e-6));
    EXPECT_NEAR(r.velocity.z(), S(4) * eps, S(1e-6));
    EXPECT_NEAR(r.normal_impulse, S(4) * (S(1) + eps), S(1e-5));
  }
  // mirror reflection preserves speed
  const auto m = respond<S>(v, n, Vec3<S>::Zero(), Material<S>::elastic());
  EXPECT_NEAR(m.velocity.norm(), v.norm(), S(1e-6));
  // separating: unchanged
  const auto sep = respond<S>(Vec3<S>(1, 0, 2), n, Vec3<S>::Zero(), Material<S>{S(0.5), S(1)});
  EXPECT_FALSE(sep.approaching);
  EXPECT_EQ(sep.velocity, Vec3<S>(1, 0, 2));
}

TYPED_TEST(Response, CoulombFrictionSticksOrSlides) {
  using S = TypeParam;
  const Vec3<S> n = Vec3<S>::UnitZ();
  // j = (1 + 0) * 2 = 2; mu j = 1: |v_t| = 0.8 sticks, |v_t| = 3 slides to 2
  auto r = respond<S>(Vec3<S>(0.8, 0, -2), n, Vec3<S>::Zero(), Material<S>{S(0), S(0.5)});
  EXPECT_TRUE(r.sticking);
  EXPECT_NEAR(r.velocity.norm(), S(0), S(1e-6));
  r = respond<S>(Vec3<S>(3, 0, -2), n, Vec3<S>::Zero(), Material<S>{S(0), S(0.5)});
  EXPECT_FALSE(r.sticking);
  EXPECT_NEAR(r.velocity.x(), S(2), S(1e-6));
  EXPECT_NEAR(r.velocity.z(), S(0), S(1e-6));
}

// Friction with restitution: the friction limit is mu (1 + epsilon) |u.n| (the whole normal velocity
// change), not mu |u.n|. Analytic answers, in a tilted frame with a moving collider (exact values
// rotated, so the tolerance is a few ulps of the speeds).
TYPED_TEST(Response, FrictionLimitScalesWithRestitution) {
  using S = TypeParam;
  const S tol = S(64) * std::numeric_limits<S>::epsilon() * S(8);
  const Eigen::AngleAxis<S> tilt(S(0.7), Vec3<S>(1, -2, 3).normalized());
  const Mat3<S> R = tilt.toRotationMatrix();
  const Vec3<S> n = R * Vec3<S>::UnitZ();
  const Vec3<S> vc = R * Vec3<S>(0.25, -0.5, 0.125);
  // local relative velocity (ut, 0, -2): j = (1 + 0.5) 2 = 3, limit = 0.5 j = 1.5
  const Material<S> m{S(0.5), S(0.5)};
  // |ut| = 1.2 <= 1.5 sticks (with the limit 0.5 * 2 = 1 it would slide)
  auto r = respond<S>(vc + R * Vec3<S>(1.2, 0, -2), n, vc, m);
  EXPECT_TRUE(r.sticking);
  EXPECT_NEAR(r.normal_impulse, S(3), tol);
  EXPECT_LT((r.velocity - (vc + R * Vec3<S>(0, 0, 1))).norm(), tol);
  // |ut| = 3 slides to 3 - 1.5 = 1.5 (with the limit 1 it would keep 2); the normal part is -eps u.n = 1
  r = respond<S>(vc + R * Vec3<S>(3, 0, -2), n, vc, m);
  EXPECT_FALSE(r.sticking);
  EXPECT_LT((r.velocity - (vc + R * Vec3<S>(1.5, 0, 1))).norm(), tol);
  // a tangential direction off the axes: ut = (1.8, 2.4, 0), |ut| = 3, scaled by 1 - 1.5 / 3
  r = respond<S>(vc + R * Vec3<S>(1.8, 2.4, -2), n, vc, Material<S>{S(0.5), S(0.5)});
  EXPECT_LT((r.velocity - (vc + R * Vec3<S>(0.9, 1.2, 1))).norm(), tol);
  // epsilon 1: j = 4, mu = 0.25 gives limit 1: |ut| = 0.9 sticks and the normal speed is kept
  r = respond<S>(vc + R * Vec3<S>(0, 0.9, -2), n, vc, Material<S>{S(1), S(0.25)});
  EXPECT_TRUE(r.sticking);
  EXPECT_LT((r.velocity - (vc + R * Vec3<S>(0, 0, 2))).norm(), tol);
}

TYPED_TEST(Response, RestingThresholdAndMovingCollider) {
  using S = TypeParam;
  const Vec3<S> n = Vec3<S>::UnitZ();
  ResponseOptions<S> o;
  o.rest_speed = S(0.1);
  auto r = respond<S>(Vec3<S>(0, 0, -0.05), n, Vec3<S>::Zero(), Material<S>{S(0.5), S(0)}, o);
  EXPECT_TRUE(r.resting);
  EXPECT_EQ(r.velocity.z(), S(0));
  r = respond<S>(Vec3<S>(0, 0, -0.05), n, Vec3<S>::Zero(), Material<S>::elastic(), o);  // elastic never rests
  EXPECT_FALSE(r.resting);
  EXPECT_NEAR(r.velocity.z(), S(0.05), S(1e-7));
  // a collider moving up at 1 hits a particle at rest: relative reflection gives 2 (epsilon 1)
  r = respond<S>(Vec3<S>::Zero(), n, Vec3<S>(0, 0, 1), Material<S>::elastic());
  EXPECT_NEAR(r.velocity.z(), S(2), S(1e-6));
  // epsilon 0: the particle moves with the collider
  r = respond<S>(Vec3<S>(0.5, 0, 0), n, Vec3<S>(0, 0, 1), Material<S>{S(0), S(0)});
  EXPECT_NEAR(r.velocity.z(), S(1), S(1e-6));
  EXPECT_NEAR(r.velocity.x(), S(0.5), S(1e-6));
}

TYPED_TEST(Response, CollidersLocalQueries) {
  using S = TypeParam;
  // plane
  const PlaneCollider<S> pl(Plane<S>(Vec3<S>::UnitZ(), S(1)));
  auto h = pl.local_first_hit(Vec3<S>(0, 0, 3), Vec3<S>(0, 0, -4), S(0.5), S(1));
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, S(0.375), S(1e-6));
  EXPECT_FALSE(pl.local_first_hit(Vec3<S>(0, 0, 3), Vec3<S>(1, 0, 0), S(0), S(1)).has_value());
  // sphere, solid and container
  const SphereCollider<S> ball(Sphere<S>(Vec3<S>::Zero(), S(1)));
  h = ball.local_first_hit(Vec3<S>(-3, 0, 0), Vec3<S>(4, 0, 0), S(0.5), S(1));
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, S(0.375), S(1e-6));
  EXPECT_NEAR(h->normal.x(), S(-1), S(1e-6));
  const SphereCollider<S> shell(Sphere<S>(Vec3<S>::Zero(), S(2)), ColliderSide::Inside);
  h = shell.local_first_hit(Vec3<S>::Zero(), Vec3<S>(4, 0, 0), S(0.5), S(1));
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, S(0.375), S(1e-6));
  EXPECT_NEAR(h->normal.x(), S(-1), S(1e-6));
  auto p = shell.local_penetration(Vec3<S>(1.9, 0, 0), Vec3<S>::Zero(), S(0.5), S(0));
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->target.x(), S(1.5), S(1e-6));
  // boxes, solid (point and rounded) and container
  const BoxCollider<S> box(Aabb<S>(Vec3<S>::Constant(-1), Vec3<S>::Constant(1)));
  h = box.local_first_hit(Vec3<S>(-3, 0.2, 0.1), Vec3<S>(4, 0, 0), S(0), S(1));
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, S(0.5), S(1e-6));
  h = box.local_first_hit(Vec3<S>(3, 3, 0.1), Vec3<S>(-4, -4, 0), S(0.5), S(1));  // rounded edge
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->normal.dot(Vec3<S>(1, 1, 0).normalized()), S(1), S(1e-5));
  const BoxCollider<S> room(Aabb<S>(Vec3<S>::Constant(-1), Vec3<S>::Constant(1)), ColliderSide::Inside);
  h = room.local_first_hit(Vec3<S>::Zero(), Vec3<S>(0, 0, 4), S(0.25), S(1));
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(h->t, S(0.1875), S(1e-6));
  EXPECT_NEAR(h->normal.z(), S(-1), S(1e-6));
  p = room.local_penetration(Vec3<S>(0, 0, 0.9), Vec3<S>::Zero(), S(0.25), S(0));
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->target.z(), S(0.75), S(1e-6));
  // closed mesh, solid: the pseudo-normal sign tells inside from outside
  const MeshBvh<Aabb<S>> mb(make_icosphere<S>(S(1), 2));
  const MeshCollider<Aabb<S>> solid(mb, ColliderSide::Outside);
  p = solid.local_penetration(Vec3<S>(0.9, 0, 0), Vec3<S>(1.2, 0, 0), S(0), S(0));
  ASSERT_TRUE(p.has_value());
  EXPECT_GT(p->target.x(), S(0.95));
  EXPECT_GT(p->normal.x(), S(0.9));
  EXPECT_FALSE(solid.local_penetration(Vec3<S>(1.1, 0, 0), Vec3<S>(1.2, 0, 0), S(0), S(0)).has_value());
  const MeshCollider<Aabb<S>> two(mb, ColliderSide::TwoSided);
  p = two.local_penetration(Vec3<S>(1.05, 0, 0), Vec3<S>(0.5, 0, 0), S(0), S(0.01));  // crossed from inside
  ASSERT_TRUE(p.has_value());
  EXPECT_LT(p->target.x(), S(1));
  EXPECT_LT(p->normal.x(), S(-0.9));
}

}  // namespace
}  // namespace impact
