// SPDX-License-Identifier: MIT
// triangles_intersect against an exact integer separating-axis oracle: random small-integer
// triangles (dense in coincidences: shared vertices and edges, coplanar, collinear and point
// triangles), constructed touching and coplanar configurations, near-coplanar perturbations with
// large coordinates, power-of-two scalings, one-ulp moves off touching contact; the prepared form;
// triangle_intersection's point and segment lie on both triangles. Float and double.
#include "impact/narrow/triangle_triangle.hpp"
#include "int_oracle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace impact;
using namespace impact::test;

namespace {

template <class S> class TriTri : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(TriTri, Scalars);

using ITri = std::array<IPoint, 3>;

template <class S> Triangle<S> to_tri(const ITri& t, double scale = 1.0) {
  auto v = [&](const IPoint& p) { return Vec3<S>(S(double(p[0]) * scale), S(double(p[1]) * scale), S(double(p[2]) * scale)); };
  return {v(t[0]), v(t[1]), v(t[2])};
}

IPoint rand_point(Rng& rng, std::int64_t lo, std::int64_t hi) {
  IPoint p;
  for (auto& c : p) c = lo + std::int64_t(rng.index(std::uint64_t(hi - lo + 1)));
  return p;
}

/// Checks both argument orders, all vertex rotations/reflections of the pair against the oracle.
template <class S> void check_pair(const ITri& a, const ITri& b, double scale, int& mismatches, int& hits) {
  const bool expect = triangles_intersect_int(a, b);
  hits += expect;
  const Triangle<S> ta = to_tri<S>(a, scale), tb = to_tri<S>(b, scale);
  const Triangle<S> tb_rev(tb.c, tb.b, tb.a), ta_rot(ta.b, ta.c, ta.a);
  const bool got[4] = {triangles_intersect(ta, tb), triangles_intersect(tb, ta), triangles_intersect(ta_rot, tb_rev),
                       triangles_intersect(PreparedTriangle<S>(tb_rev), ta_rot)};
  for (bool g : got)
    if (g != expect) {
      if (mismatches < 5)
        ADD_FAILURE() << "mismatch: expected " << expect << " a=(" << a[0][0] << "," << a[0][1] << "," << a[0][2] << ")(" << a[1][0]
                      << "," << a[1][1] << "," << a[1][2] << ")(" << a[2][0] << "," << a[2][1] << "," << a[2][2] << ") b=(" << b[0][0]
                      << "," << b[0][1] << "," << b[0][2] << ")(" << b[1][0] << "," << b[1][1] << "," << b[1][2] << ")(" << b[2][0]
                      << "," << b[2][1] << "," << b[2][2] << ")";
      ++mismatches;
      break;
    }
}

TYPED_TEST(TriTri, RandomSmallIntegersMatchExactOracle) {
  using S = TypeParam;
  Rng rng(11);
  int mismatches = 0, hits = 0;
  const std::int64_t ranges[] = {1, 2, 4, 8};
  for (std::int64_t r : ranges)
    for (int it = 0; it < 15000; ++it) {
      const ITri a{rand_point(rng, 0, r), rand_point(rng, 0, r), rand_point(rng, 0, r)};
      const ITri b{rand_point(rng, 0, r), rand_point(rng, 0, r), rand_point(rng, 0, r)};
      check_pair<S>(a, b, 1.0, mismatches, hits);
    }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, 1000);
}

/// b's vertices drawn from a menu of features of a: a's vertices, points of a's plane (integer
/// affine combinations), those points pushed off the plane by +-1 normal, collinear/coincident.
ITri constructed_b(Rng& rng, const ITri& a, std::int64_t push) {
  const IVec A0 = to_ivec(a[0]), e1 = isub(to_ivec(a[1]), A0), e2 = isub(to_ivec(a[2]), A0);
  const IVec n = icross(e1, e2);
  ITri b;
  for (int k = 0; k < 3; ++k) {
    const auto kind = rng.index(6);
    IVec p;
    if (kind == 0) {
      p = to_ivec(a[rng.index(3)]);
    } else {
      const I128 i = I128(rng.index(5)) - 1, j = I128(rng.index(5)) - 1;
      p = {A0[0] + i * e1[0] + j * e2[0], A0[1] + i * e1[1] + j * e2[1], A0[2] + i * e1[2] + j * e2[2]};
      if (kind == 3 || kind == 4) {
        const I128 s = kind == 3 ? 1 : -1;
        const int axis = int(rng.index(3));
        // a push along a coordinate axis that is not parallel to the plane changes the side
        p[axis] += s * push * (n[axis] != 0 ? 1 : 0);
      }
      if (kind == 5) p = {p[0] + I128(rng.index(3)) - 1, p[1] + I128(rng.index(3)) - 1, p[2] + I128(rng.index(3)) - 1};
    }
    b[k] = {std::int64_t(p[0]), std::int64_t(p[1]), std::int64_t(p[2])};
  }
  const auto deg = rng.index(8);
  if (deg == 0) b[2] = b[1];                                                                               // segment
  if (deg == 1) b[1] = b[2] = b[0];                                                                        // point
  if (deg == 2) b[2] = {2 * b[1][0] - b[0][0], 2 * b[1][1] - b[0][1], 2 * b[1][2] - b[0][2]};              // collinear
  return b;
}

TYPED_TEST(TriTri, ConstructedTouchingCoplanarDegenerateMatchExactOracle) {
  using S = TypeParam;
  Rng rng(12);
  int mismatches = 0, hits = 0;
  for (int it = 0; it < 30000; ++it) {
    const std::int64_t r = it % 2 ? 6 : 40;
    ITri a{rand_point(rng, -r, r), rand_point(rng, -r, r), rand_point(rng, -r, r)};
    if (it % 10 == 0) a[2] = a[1];  // degenerate a as well
    const ITri b = constructed_b(rng, a, 1 + std::int64_t(rng.index(2)));
    check_pair<S>(a, b, 1.0, mismatches, hits);
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, 5000);
}

TYPED_TEST(TriTri, NearCoplanarLargeCoordinatesAndScalings) {
  using S = TypeParam;
  Rng rng(13);
  int mismatches = 0, hits = 0;
  for (int it = 0; it < 20000; ++it) {
    const std::int64_t r = std::int64_t(1) << 17;
    const ITri a{rand_point(rng, -r, r), rand_point(rng, -r, r), rand_point(rng, -r, r)};
    const ITri b = constructed_b(rng, a, 1);
    bool fits = true;
    for (const auto& p : b)
      for (auto c : p) fits = fits && c > -(std::int64_t(1) << 20) && c < (std::int64_t(1) << 20);
    if (!fits) continue;
    const double scale = std::ldexp(1.0, int(rng.index(41)) - 20);
    check_pair<S>(a, b, scale, mismatches, hits);
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, 1000);
}

TYPED_TEST(TriTri, RandomDyadicGeneralPosition) {
  using S = TypeParam;
  Rng rng(14);
  int mismatches = 0, hits = 0;
  for (int it = 0; it < 20000; ++it) {
    const std::int64_t r = std::int64_t(1) << 20;
    const IPoint c = rand_point(rng, -r / 2, r / 2);
    auto near = [&]() {
      IPoint p = rand_point(rng, -r / 4, r / 4);
      for (int k = 0; k < 3; ++k) p[k] = std::clamp<std::int64_t>(p[k] + c[k] * (it % 3 == 0), -r, r);
      return p;
    };
    const ITri a{rand_point(rng, -r / 4, r / 4), rand_point(rng, -r / 4, r / 4), rand_point(rng, -r / 4, r / 4)};
    const ITri b{near(), near(), near()};
    check_pair<S>(a, b, 0x1p-10, mismatches, hits);
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(hits, 1000);
}

TYPED_TEST(TriTri, HandPickedCases) {
  using S = TypeParam;
  using V = Vec3<S>;
  const Triangle<S> t(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0));
  EXPECT_TRUE(triangles_intersect(t, t));                                                  // identical
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(1, 0, 0), V(2, 0, 0), V(1, 1, 5))));    // shared vertex
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(1, 0, 0), V(0, 1, 0), V(1, 1, 0))));    // shared edge, coplanar
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(1, 0, 0), V(0, 1, 0), V(1, 1, 1))));    // shared edge, folded
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(S(0.25), S(0.25), 0), V(1, 1, 1), V(2, 1, 1))));  // vertex on face
  EXPECT_FALSE(triangles_intersect(t, Triangle<S>(V(S(0.25), S(0.25), S(1e-6)), V(1, 1, 1), V(2, 1, 1))));
  EXPECT_FALSE(triangles_intersect(t, Triangle<S>(V(S(0.6), S(0.6), 0), V(1, 1, 0), V(1, 2, 0))));  // coplanar, disjoint
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(S(0.5), S(0.5), 0), V(1, 1, 0), V(1, 2, 0))));   // coplanar, touching
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(S(0.5), S(0.5), -1), V(S(0.5), S(0.5), 1), V(S(0.5), S(0.5), 1))));  // segment through
  EXPECT_TRUE(triangles_intersect(t, Triangle<S>(V(S(0.2), S(0.2), 0), V(S(0.2), S(0.2), 0), V(S(0.2), S(0.2), 0))));  // point inside
  EXPECT_FALSE(triangles_intersect(t, Triangle<S>(V(S(0.2), S(0.2), 1), V(S(0.2), S(0.2), 1), V(S(0.2), S(0.2), 1))));  // point above
}

TYPED_TEST(TriTri, UlpPerturbationsOfTouchingConfigurations) {
  using S = TypeParam;
  Rng rng(16);
  int wrong = 0;
  for (int it = 0; it < 3000; ++it) {
    // A in the plane coordinate[axis] = h, B with one vertex on A's interior, the others above it;
    // that vertex moved by one ulp up (disjoint), not at all (touching) or one ulp down (crossing)
    const int axis = int(rng.index(3)), i = (axis + 1) % 3, j = (axis + 2) % 3;
    const S h = S(1 + rng.index(64)) * S(0.25);
    auto point = [&](S u, S v, S w) {
      Vec3<S> p;
      p[i] = u, p[j] = v, p[axis] = w;
      return p;
    };
    const S scale = S(1 + rng.index(8));
    const Triangle<S> a(point(0, 0, h), point(4 * scale, 0, h), point(0, 4 * scale, h));
    const S u = S(1 + rng.index(7)) * S(0.125) * scale, v = S(1 + rng.index(7)) * S(0.125) * scale;  // u + v < 4 scale
    for (int d = -1; d <= 1; ++d) {
      const S w = d == 0 ? h : std::nextafter(h, d > 0 ? S(100) : S(-100));
      const Triangle<S> b(point(u, v, w), point(u + 1, v - 3, h + 2), point(u - 2, v + 1, h + S(0.5)));
      const bool expect = d <= 0;
      wrong += triangles_intersect(a, b) != expect;
      wrong += triangles_intersect(b, a) != expect;
    }
  }
  EXPECT_EQ(wrong, 0);
}

template <class S> S dist_to_tri(const Vec3<S>& p, const Triangle<S>& t) {
  return std::sqrt(closest_point_on_triangle(Vec3<double>(p.template cast<double>()), t.template cast<double>()).squared_distance);
}

TYPED_TEST(TriTri, IntersectionPointLiesOnBothTriangles) {
  using S = TypeParam;
  Rng rng(15);
  int checked = 0;
  for (int it = 0; it < 10000; ++it) {
    const bool small = it % 2;
    const std::int64_t r = small ? 4 : 1000;
    const ITri a{rand_point(rng, -r, r), rand_point(rng, -r, r), rand_point(rng, -r, r)};
    const ITri b = small ? ITri{rand_point(rng, -r, r), rand_point(rng, -r, r), rand_point(rng, -r, r)} : constructed_b(rng, a, 1);
    const Triangle<S> ta = to_tri<S>(a), tb = to_tri<S>(b);
    const auto hit = triangle_intersection(ta, tb);
    ASSERT_EQ(hit.has_value(), triangles_intersect(ta, tb));
    if (!hit) continue;
    ++checked;
    double size = 0;
    for (int k = 0; k < 3; ++k) size = std::max({size, double(ta[k].cwiseAbs().maxCoeff()), double(tb[k].cwiseAbs().maxCoeff())});
    // a fixed tolerance, relative to the coordinates (measured at most 4.3e-8 in float and 2.2e-12 in
    // double on these pairs, nearly parallel planes included): every check can fail
    const double tol = size * (std::is_same_v<S, float> ? 2e-7 : 1e-11);
    const S na = hit->normal_a.norm();
    EXPECT_TRUE(na == S(0) || std::abs(na - S(1)) < S(1e-5));
    EXPECT_LE(dist_to_tri(hit->point, ta), tol);
    EXPECT_LE(dist_to_tri(hit->point, tb), tol);
    if (!hit->coplanar) {
      EXPECT_LE(dist_to_tri(hit->p, ta), tol);
      EXPECT_LE(dist_to_tri(hit->p, tb), tol);
      EXPECT_LE(dist_to_tri(hit->q, ta), tol);
      EXPECT_LE(dist_to_tri(hit->q, tb), tol);
    }
  }
  EXPECT_GT(checked, 1000);
}

}  // namespace
