// SPDX-License-Identifier: MIT
// Sphere–triangle: static overlap against the closest-point distance; swept sphere against analytic
// face, edge and vertex contacts and against a fine time-sampling oracle (conservative tolerance):
// the reported time is a contact (distance = r), no sampled earlier time is in contact, and a miss
// means no sampled time is in contact. Degenerate triangles. Float and double.
#include "impact/narrow/sphere_triangle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace impact;
using namespace impact::test;

namespace {

template <class S> class SphereTri : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(SphereTri, Scalars);

TYPED_TEST(SphereTri, StaticOverlap) {
  using S = TypeParam;
  using V = Vec3<S>;
  const Triangle<S> t(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0));
  EXPECT_TRUE(sphere_triangle_overlap(Sphere<S>(V(S(0.2), S(0.2), S(0.5)), S(0.6)), t));
  EXPECT_FALSE(sphere_triangle_overlap(Sphere<S>(V(S(0.2), S(0.2), S(0.5)), S(0.4)), t));
  EXPECT_TRUE(sphere_triangle_overlap(Sphere<S>(V(2, 0, 0), S(1)), t));  // touching a vertex
  EXPECT_FALSE(sphere_triangle_overlap(Sphere<S>(V(2, 2, 0), S(1)), t));
}

TYPED_TEST(SphereTri, SweptAnalyticFaceEdgeVertex) {
  using S = TypeParam;
  using V = Vec3<S>;
  const Triangle<S> t(V(0, 0, 0), V(4, 0, 0), V(0, 4, 0));
  const S r = S(0.5);
  // face: straight down onto the interior
  auto h = sweep_sphere_triangle(V(1, 1, 2), V(1, 1, -2), r, t);
  ASSERT_TRUE(h);
  EXPECT_NEAR(double(h->time), 0.375, 1e-6);
  EXPECT_EQ(h->feature, TriangleFeatureId::Face);
  EXPECT_TRUE(h->normal.isApprox(V(0, 0, 1), S(1e-5)));
  EXPECT_TRUE(h->point.isApprox(V(1, 1, 0), S(1e-5)));
  // from below
  h = sweep_sphere_triangle(V(1, 1, -2), V(1, 1, 2), r, t);
  ASSERT_TRUE(h);
  EXPECT_TRUE(h->normal.isApprox(V(0, 0, -1), S(1e-5)));
  // edge 01 (y = 0), approached in the plane from y < 0
  h = sweep_sphere_triangle(V(2, -2, 0), V(2, 2, 0), r, t);
  ASSERT_TRUE(h);
  EXPECT_NEAR(double(h->time), 0.375, 1e-6);
  EXPECT_EQ(h->feature, TriangleFeatureId::EdgeAB);
  EXPECT_TRUE(h->point.isApprox(V(2, 0, 0), S(1e-5)));
  EXPECT_TRUE(h->normal.isApprox(V(0, -1, 0), S(1e-5)));
  // edge approached diagonally from above-outside: contact at distance r from the edge
  h = sweep_sphere_triangle(V(2, -1, 1), V(2, 1, -1), r, t);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->feature, TriangleFeatureId::EdgeAB);
  // centre path y = -1 + 2s, z = 1 - 2s; distance to the x axis = r
  const double s = (2 - std::sqrt(2.0) * 0.5) / 4;  // sqrt(2) |1 - 2s| = r
  EXPECT_NEAR(double(h->time), s, 1e-5);
  // vertex 0 approached along the diagonal from outside
  h = sweep_sphere_triangle(V(-2, -2, 0), V(2, 2, 0), r, t);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->feature, TriangleFeatureId::VertexA);
  EXPECT_NEAR(double(h->time), (2 * std::sqrt(2.0) - 0.5) / (4 * std::sqrt(2.0)), 1e-5);
  EXPECT_TRUE(h->point.isApprox(V(0, 0, 0), S(1e-5)) || h->point.norm() < S(1e-5));
  // misses: moving away, passing by, stopping short
  EXPECT_FALSE(sweep_sphere_triangle(V(1, 1, 2), V(1, 1, 5), r, t));
  EXPECT_FALSE(sweep_sphere_triangle(V(-2, 5, 1), V(5, 5, 1), r, t));
  EXPECT_FALSE(sweep_sphere_triangle(V(1, 1, 2), V(1, 1, S(0.6)), r, t));
  // already overlapping: time 0
  h = sweep_sphere_triangle(V(1, 1, S(0.25)), V(1, 1, 5), r, t);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->time, S(0));
  // no motion
  EXPECT_FALSE(sweep_sphere_triangle(V(1, 1, 2), V(1, 1, 2), r, t));
}

template <class S> double dist(const Vec3<S>& c, const Triangle<S>& t) {
  const Vec3<double> cd = c.template cast<double>();
  return std::sqrt(closest_point_on_triangle(cd, t.template cast<double>()).squared_distance);
}

TYPED_TEST(SphereTri, SweptAgainstTimeSampling) {
  using S = TypeParam;
  Rng rng(41);
  const int samples = 2000;
  int hits = 0;
  for (int it = 0; it < 800; ++it) {
    Triangle<S> t(rng.vec(-1, 1).cast<S>(), rng.vec(-1, 1).cast<S>(), rng.vec(-1, 1).cast<S>());
    if (it % 7 == 1) t.c = t.a + S(0.5) * (t.b - t.a);  // collinear
    if (it % 7 == 2) t.c = t.b = t.a;                   // point
    const Vec3<S> p0 = rng.vec(-3, 3).cast<S>(), p1 = rng.vec(-3, 3).cast<S>();
    const S r = S(rng.uniform(0.05, 1.0));
    const auto h = sweep_sphere_triangle(p0, p1, r, t);
    const double tol = std::is_same_v<S, float> ? 2e-4 : 1e-9;
    const double step_slack = 8.0 / samples * (p1 - p0).template cast<double>().norm();  // motion between samples
    int first_inside = -1;
    for (int k = 0; k <= samples && first_inside < 0; ++k) {
      const S tk = S(k) / S(samples);
      if (dist(Vec3<S>(p0 + tk * (p1 - p0)), t) < double(r) - tol) first_inside = k;
    }
    if (!h) {
      EXPECT_EQ(first_inside, -1) << it;
      continue;
    }
    ++hits;
    const Vec3<S> c = p0 + h->time * (p1 - p0);
    const double dc = dist(c, t);
    if (h->time > S(0)) {
      EXPECT_NEAR(dc, double(r), 10 * tol + 1e-6) << it;
    } else {
      EXPECT_LE(dc, double(r) + tol);
    }
    if (first_inside >= 0) {
      EXPECT_LE(double(h->time), double(first_inside) / samples + 1e-6) << it;
    }
    // no earlier contact: every sample before time is at distance >= r - tol - slack
    for (int k = 0; k < samples && double(k) / samples < double(h->time) - 2.0 / samples; ++k) {
      ASSERT_GE(dist(Vec3<S>(p0 + (S(k) / S(samples)) * (p1 - p0)), t), double(r) - tol - step_slack) << it;
    }
    EXPECT_NEAR(double(h->normal.norm()), 1.0, 1e-4);
    EXPECT_NEAR(dist(h->point, t), 0.0, 1e-5);
  }
  EXPECT_GT(hits, 100);
}

}  // namespace
