// SPDX-License-Identifier: MIT
// Closest points against brute force: point–triangle (dense barycentric sampling plus the edges),
// segment–segment (dense sampling of one parameter, exact projection for the other, which is
// optimal for a fixed point), including degenerate triangles, zero-length, parallel and collinear
// segments; analytic features. Float and double.
#include "impact/narrow/closest_point.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace impact;
using namespace impact::test;

namespace {

template <class S> class Closest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(Closest, Scalars);

template <class S> double tol_for(double scale) { return (std::is_same_v<S, float> ? 1e-4 : 1e-10) * scale * scale; }

template <class S> Triangle<S> random_triangle(Rng& rng, int kind) {
  const Vec3<S> a = rng.vec(-1, 1).cast<S>(), b = rng.vec(-1, 1).cast<S>(), c = rng.vec(-1, 1).cast<S>();
  switch (kind) {
    case 1: return {a, b, Vec3<S>(a + S(0.3) * (b - a))};  // collinear
    case 2: return {a, a, c};                              // two coincident
    case 3: return {a, a, a};                              // point
    case 4: return {a, b, Vec3<S>(S(2) * b - a)};          // collinear, c beyond b
    default: return {a, b, c};
  }
}

/// Brute-force squared distance to the closed triangle (never below the true distance).
template <class S> double brute_triangle(const Vec3<S>& x, const Triangle<S>& t) {
  const Vec3<double> p = x.template cast<double>(), a = t.a.template cast<double>(), b = t.b.template cast<double>(),
                     c = t.c.template cast<double>();
  double best = 1e300;
  const int n = 100;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      best = std::min(best, (a + u * (b - a) + v * (c - a) - p).squaredNorm());
    }
  // edges, densely
  const Vec3<double> vs[3] = {a, b, c};
  for (int e = 0; e < 3; ++e)
    for (int i = 0; i <= 1000; ++i) best = std::min(best, (vs[e] + (double(i) / 1000) * (vs[(e + 1) % 3] - vs[e]) - p).squaredNorm());
  return best;
}

TYPED_TEST(Closest, PointTriangleAgainstBruteForce) {
  using S = TypeParam;
  Rng rng(31);
  for (int it = 0; it < 400; ++it) {
    const Triangle<S> t = random_triangle<S>(rng, it % 6 == 5 ? 0 : it % 6);
    const Vec3<S> x = rng.vec(-2, 2).cast<S>();
    const auto r = closest_point_on_triangle(x, t);
    const double brute = brute_triangle(x, t);
    // never worse than brute force (up to its sampling, which overestimates)
    EXPECT_LE(double(r.squared_distance), brute * (1 + tol_for<S>(1)) + tol_for<S>(4)) << it;
    // the point is where the barycentrics say, and it is the reported distance away
    const Vec3<S> p = r.barycentric[0] * t.a + r.barycentric[1] * t.b + r.barycentric[2] * t.c;
    EXPECT_LE((p - r.point).norm(), (std::is_same_v<S, float> ? 1e-5 : 1e-12));
    EXPECT_NEAR(double(r.barycentric.sum()), 1.0, 1e-6);
    EXPECT_GE(r.barycentric.minCoeff(), S(0));
    EXPECT_NEAR(double(r.squared_distance), double((x - r.point).squaredNorm()), 1e-6);
    // feature consistency: a vertex feature puts all weight on one vertex, an edge on two
    const int nonzero = (r.barycentric.array() > S(0)).count();
    switch (r.feature) {
      case TriangleFeatureId::VertexA:
      case TriangleFeatureId::VertexB:
      case TriangleFeatureId::VertexC: EXPECT_EQ(nonzero, 1); break;
      case TriangleFeatureId::EdgeAB: EXPECT_EQ(r.barycentric[2], S(0)); break;
      case TriangleFeatureId::EdgeBC: EXPECT_EQ(r.barycentric[0], S(0)); break;
      case TriangleFeatureId::EdgeCA: EXPECT_EQ(r.barycentric[1], S(0)); break;
      case TriangleFeatureId::Face: break;
    }
  }
}

TYPED_TEST(Closest, PointTriangleFeatures) {
  using S = TypeParam;
  using V = Vec3<S>;
  const Triangle<S> t(V(0, 0, 0), V(2, 0, 0), V(0, 2, 0));
  auto f = [&](const V& x) { return closest_point_on_triangle(x, t); };
  EXPECT_EQ(f(V(S(0.5), S(0.5), 3)).feature, TriangleFeatureId::Face);
  EXPECT_NEAR(double(f(V(S(0.5), S(0.5), 3)).squared_distance), 9.0, 1e-5);
  EXPECT_EQ(f(V(-1, -1, 1)).feature, TriangleFeatureId::VertexA);
  EXPECT_EQ(f(V(3, -1, 0)).feature, TriangleFeatureId::VertexB);
  EXPECT_EQ(f(V(-1, 3, 0)).feature, TriangleFeatureId::VertexC);
  EXPECT_EQ(f(V(1, -1, 0)).feature, TriangleFeatureId::EdgeAB);
  EXPECT_EQ(f(V(2, 2, 0)).feature, TriangleFeatureId::EdgeBC);
  EXPECT_EQ(f(V(-1, 1, 0)).feature, TriangleFeatureId::EdgeCA);
  const auto e = f(V(2, 2, 0));
  EXPECT_NEAR(double(e.barycentric[1]), 0.5, 1e-6);
  EXPECT_NEAR(double(e.point.x()), 1.0, 1e-6);
  // degenerate: segment from (0,0,0) to (2,0,0) with c in the middle
  const Triangle<S> seg(V(0, 0, 0), V(2, 0, 0), V(1, 0, 0));
  EXPECT_NEAR(double(closest_point_on_triangle(V(S(1.5), 1, 0), seg).squared_distance), 1.0, 1e-6);
  EXPECT_NEAR(double(closest_point_on_triangle(V(3, 0, 0), seg).squared_distance), 1.0, 1e-6);
  const Triangle<S> pt(V(1, 1, 1), V(1, 1, 1), V(1, 1, 1));
  const auto rp = closest_point_on_triangle(V(1, 1, 3), pt);
  EXPECT_NEAR(double(rp.squared_distance), 4.0, 1e-6);
  EXPECT_TRUE(rp.point.isApprox(V(1, 1, 1)));
}

TYPED_TEST(Closest, PointSegment) {
  using S = TypeParam;
  using V = Vec3<S>;
  const Segment<S> s(V(0, 0, 0), V(2, 0, 0));
  EXPECT_NEAR(double(closest_point_on_segment(V(1, 1, 0), s).t), 0.5, 1e-6);
  EXPECT_EQ(closest_point_on_segment(V(-1, 1, 0), s).t, S(0));
  EXPECT_EQ(closest_point_on_segment(V(5, 1, 0), s).t, S(1));
  EXPECT_NEAR(double(closest_point_on_segment(V(5, 1, 0), s).squared_distance), 10.0, 1e-5);
  const Segment<S> z(V(1, 1, 1), V(1, 1, 1));
  EXPECT_NEAR(double(closest_point_on_segment(V(1, 1, 2), z).squared_distance), 1.0, 1e-6);
}

template <class S> Segment<S> random_segment(Rng& rng, int kind, const Segment<S>& other) {
  const Vec3<S> p = rng.vec(-1, 1).cast<S>(), q = rng.vec(-1, 1).cast<S>();
  const Vec3<S> d = other.q - other.p;
  switch (kind) {
    case 1: return {p, p};                                                                  // zero length
    case 2: return {p, Vec3<S>(p + S(rng.uniform(-2, 2)) * d)};                            // parallel
    case 3: {                                                                               // collinear
      const Vec3<S> a = other.p + S(rng.uniform(-1.5, 1.5)) * d;
      return {a, Vec3<S>(a + S(rng.uniform(-1.5, 1.5)) * d)};
    }
    default: return {p, q};
  }
}

TYPED_TEST(Closest, SegmentSegmentAgainstBruteForce) {
  using S = TypeParam;
  Rng rng(32);
  for (int it = 0; it < 600; ++it) {
    const Segment<S> a(rng.vec(-1, 1).cast<S>(), rng.vec(-1, 1).cast<S>());
    Segment<S> sa = it % 11 == 0 ? Segment<S>(a.p, a.p) : a;
    const Segment<S> sb = random_segment<S>(rng, it % 4, sa);
    const auto r = closest_points_segment_segment(sa, sb);
    // brute force: sample s densely, optimal t by projection (in double)
    const Segment<double> da(sa.p.template cast<double>(), sa.q.template cast<double>());
    const Segment<double> db(sb.p.template cast<double>(), sb.q.template cast<double>());
    double brute = 1e300;
    for (int i = 0; i <= 2000; ++i) brute = std::min(brute, closest_point_on_segment(da.at(double(i) / 2000), db).squared_distance);
    for (int i = 0; i <= 2000; ++i) brute = std::min(brute, closest_point_on_segment(db.at(double(i) / 2000), da).squared_distance);
    EXPECT_LE(double(r.squared_distance), brute * (1 + tol_for<S>(1)) + tol_for<S>(4)) << it;
    EXPECT_GE(r.s, S(0));
    EXPECT_LE(r.s, S(1));
    EXPECT_GE(r.t, S(0));
    EXPECT_LE(r.t, S(1));
    EXPECT_LE((r.point_a - sa.at(r.s)).norm(), 1e-5);
    EXPECT_LE((r.point_b - sb.at(r.t)).norm(), 1e-5);
  }
}

TYPED_TEST(Closest, SegmentSegmentAnalytic) {
  using S = TypeParam;
  using V = Vec3<S>;
  // crossing at right angles, 1 apart
  auto r = closest_points_segment_segment(Segment<S>(V(-1, 0, 0), V(1, 0, 0)), Segment<S>(V(0, -1, 1), V(0, 1, 1)));
  EXPECT_NEAR(double(r.squared_distance), 1.0, 1e-6);
  EXPECT_NEAR(double(r.s), 0.5, 1e-6);
  EXPECT_NEAR(double(r.t), 0.5, 1e-6);
  // parallel overlapping: distance is the line distance
  r = closest_points_segment_segment(Segment<S>(V(0, 0, 0), V(2, 0, 0)), Segment<S>(V(1, 1, 0), V(3, 1, 0)));
  EXPECT_NEAR(double(r.squared_distance), 1.0, 1e-6);
  // parallel disjoint: endpoint to endpoint
  r = closest_points_segment_segment(Segment<S>(V(0, 0, 0), V(1, 0, 0)), Segment<S>(V(3, 1, 0), V(2, 1, 0)));
  EXPECT_NEAR(double(r.squared_distance), 2.0, 1e-6);
  // collinear overlapping: zero
  r = closest_points_segment_segment(Segment<S>(V(0, 0, 0), V(2, 0, 0)), Segment<S>(V(1, 0, 0), V(3, 0, 0)));
  EXPECT_NEAR(double(r.squared_distance), 0.0, 1e-9);
  // two points
  r = closest_points_segment_segment(Segment<S>(V(0, 0, 0), V(0, 0, 0)), Segment<S>(V(0, 3, 4), V(0, 3, 4)));
  EXPECT_NEAR(double(r.squared_distance), 25.0, 1e-4);
  // point and segment
  r = closest_points_segment_segment(Segment<S>(V(1, 1, 0), V(1, 1, 0)), Segment<S>(V(0, 0, 0), V(2, 0, 0)));
  EXPECT_NEAR(double(r.squared_distance), 1.0, 1e-6);
  EXPECT_NEAR(double(r.t), 0.5, 1e-6);
}

}  // namespace
