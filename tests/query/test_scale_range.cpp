// SPDX-License-Identifier: MIT
// The coordinate range of the queries (issue 12, D8; core/validate.hpp CoordinateRange): inside it
// every answer is the same at every power-of-two scale, outside it the input is rejected with
// InvalidInput (it used to give a separated pair "colliding" at 1e-160 and a ray hit with t = NaN
// at 1e300). Checked over the whole range, float and double:
//  - mesh–mesh collision of integer meshes (boxes touching at a face, an edge, a vertex, or one
//    unit apart, and random integer triangle soups) scaled by 2^k and placed by a translation
//    scaled alike, against a brute-force oracle in exact integer arithmetic;
//  - ray casts, swept spheres and closest points: t is the same, distances and points scale by
//    exactly 2^k (power-of-two scaling commutes with rounding as long as nothing over- or
//    underflows: a bitwise comparison);
//  - one step beyond each end of the range throws.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/mesh_collide.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/swept_sphere_mesh.hpp"
#include "narrow/int_oracle.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace impact {
namespace {

using test::IPoint;

struct IntMesh {
  std::vector<IPoint> V;
  std::vector<std::array<int, 3>> F;
};

/// The axis-aligned box [lo, hi] (integers), 12 triangles.
IntMesh int_box(const IPoint& lo, const IPoint& hi) {
  IntMesh m;
  for (int i = 0; i < 8; ++i) m.V.push_back({i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]});
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) m.F.push_back({q[0], q[1], q[2]}), m.F.push_back({q[0], q[2], q[3]});
  return m;
}

/// n random triangles with integer coordinates in [lo, lo + 64)^3.
IntMesh int_soup(test::Rng& rng, int n, const IPoint& lo) {
  IntMesh m;
  for (int t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) {
      IPoint p;
      for (int j = 0; j < 3; ++j) p[j] = lo[j] + std::int64_t(rng.index(64));
      m.V.push_back(p);
    }
    m.F.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  return m;
}

/// Brute force over all triangle pairs with the exact integer separating-axis test; b is
/// translated by tb.
bool int_collide(const IntMesh& a, const IntMesh& b, const IPoint& tb) {
  for (const auto& fa : a.F)
    for (const auto& fb : b.F) {
      std::array<IPoint, 3> P, Q;
      for (int k = 0; k < 3; ++k) {
        P[k] = a.V[std::size_t(fa[k])];
        for (int j = 0; j < 3; ++j) Q[k][j] = b.V[std::size_t(fb[k])][j] + tb[j];
      }
      if (test::triangles_intersect_int(P, Q)) return true;
    }
  return false;
}

template <class S> TriangleMesh<S> scaled(const IntMesh& m, int k) {
  TriangleMesh<S> out;
  out.V.resize(Eigen::Index(m.V.size()), 3);
  out.F.resize(Eigen::Index(m.F.size()), 3);
  for (std::size_t i = 0; i < m.V.size(); ++i)
    for (int j = 0; j < 3; ++j) out.V(Eigen::Index(i), j) = S(std::ldexp(double(m.V[i][j]), k));
  for (std::size_t i = 0; i < m.F.size(); ++i)
    for (int j = 0; j < 3; ++j) out.F(Eigen::Index(i), j) = m.F[i][j];
  return out;
}
template <class S> Vec3<S> scaled(const IPoint& p, int k) {
  return Vec3<S>(S(std::ldexp(double(p[0]), k)), S(std::ldexp(double(p[1]), k)), S(std::ldexp(double(p[2]), k)));
}

/// The smallest and largest k for which a mesh whose largest coordinate lies in [2^lo_bits,
/// 2^hi_bits), scaled by 2^k and moved by a translation of up to the same size, stays in range.
template <class S> int k_lowest(int lo_bits) { return std::ilogb(CoordinateRange<S>::min_scale) - lo_bits; }
template <class S> int k_highest(int hi_bits) { return std::ilogb(CoordinateRange<S>::max) - hi_bits; }

template <class T> class ScaleRange : public ::testing::Test {};
using ScaleBVs = ::testing::Types<Aabb<float>, Aabb<double>, Sphere<float>, Sphere<double>>;
TYPED_TEST_SUITE(ScaleRange, ScaleBVs);

TYPED_TEST(ScaleRange, CollideMatchesIntegerOracleAtEveryScale) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  test::Rng rng(21);
  struct Case {
    IntMesh a, b;
    IPoint tb;
  };
  std::vector<Case> cases;
  const IntMesh box = int_box({0, 0, 0}, {16, 16, 16});
  const IntMesh unit = int_box({0, 0, 0}, {16, 8, 4});
  for (const IPoint t : {IPoint{16, 0, 0}, IPoint{17, 0, 0}, IPoint{16, 16, 0}, IPoint{16, 17, 0}, IPoint{16, 16, 16}, IPoint{16, 16, 17},
                         IPoint{-16, 4, 12}, IPoint{-17, 4, 12}, IPoint{3, 5, 7}})
    cases.push_back({box, unit, t});
  for (int i = 0; i < 6; ++i) cases.push_back({int_soup(rng, 12, {0, 0, 0}), int_soup(rng, 12, {0, 0, 0}), IPoint{40, 0, 0}});
  int hits = 0, misses = 0, wrong = 0, checks = 0;
  const int lo = k_lowest<S>(4), hi = k_highest<S>(7);  // coordinates up to 2^7 with the translation
  for (const Case& c : cases) {
    const bool expect = int_collide(c.a, c.b, c.tb);
    hits += expect, misses += !expect;
    for (int k = lo; k <= hi; k += (std::is_same_v<S, float> ? 1 : 5)) {
      const MeshBvh<BV> a(scaled<S>(c.a, k)), b(scaled<S>(c.b, k));
      const RigidTransform<S> pb(Mat3<S>::Identity(), scaled<S>(c.tb, k));
      wrong += collides(a, RigidTransform<S>(), b, pb) != expect;
      wrong += collide(b, pb, a, RigidTransform<S>()).colliding != expect;
      ++checks;
    }
  }
  EXPECT_EQ(wrong, 0) << "of " << checks;
  EXPECT_GT(hits, 5);
  EXPECT_GE(misses, 4);
}

template <class S> void expect_invalid_mesh(const TriangleMesh<S>& m, const char* needle) {
  try {
    validate_mesh(m);
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

template <class T> class ScaleRangeScalar : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ScaleRangeScalar, Scalars);

// The ends of the range: meshes at the largest and smallest allowed scales build; one step beyond
// throws (the 1e300 and 1e-160 cases for double among them).
TYPED_TEST(ScaleRangeScalar, MeshesOutsideTheRangeThrow) {
  using S = TypeParam;
  const IntMesh box = int_box({-1, -1, -1}, {1, 1, 1});  // largest coordinate 1 = 2^0
  const int top = std::ilogb(CoordinateRange<S>::max), bottom = std::ilogb(CoordinateRange<S>::min_scale);
  EXPECT_NO_THROW(MeshBvh<Aabb<S>>(scaled<S>(box, top)));
  EXPECT_NO_THROW(MeshBvh<Aabb<S>>(scaled<S>(box, bottom)));
  expect_invalid_mesh(scaled<S>(box, top + 1), "CoordinateRange");
  expect_invalid_mesh(scaled<S>(box, bottom - 1), "CoordinateRange");
  if (std::is_same_v<S, double>) {
    expect_invalid_mesh(scaled<S>(box, 997), "CoordinateRange");    // about 1e300
    expect_invalid_mesh(scaled<S>(box, -531), "CoordinateRange");  // about 1e-160
  }
  // all zeros is valid (every triangle a point)
  TriangleMesh<S> zero = scaled<S>(box, 0);
  zero.V.setZero();
  EXPECT_NO_THROW(validate_mesh(zero));
  // a pose's translation, a ray's origin and direction, a query point
  const MeshBvh<Aabb<S>> m(scaled<S>(box, 0));
  const S big = std::ldexp(S(1), top + 1), small = std::ldexp(S(1), bottom - 1);
  EXPECT_THROW(collides(m, RigidTransform<S>(), m, RigidTransform<S>(Mat3<S>::Identity(), Vec3<S>(big, 0, 0))), InvalidInput);
  EXPECT_THROW(ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-big, 0, 0), Vec3<S>::UnitX())), InvalidInput);
  EXPECT_THROW(ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-2, 0, 0), Vec3<S>(big, 0, 0))), InvalidInput);
  EXPECT_THROW(ray_mesh_first_hit(m, Ray<S>(Vec3<S>(-2, 0, 0), Vec3<S>(small, 0, 0))), InvalidInput);
  EXPECT_THROW(closest_point_on_mesh(m, Vec3<S>(0, 0, big)), InvalidInput);
  EXPECT_THROW(swept_sphere_mesh_first_hit(m, Ray<S>(Vec3<S>(-2, 0, 0), Vec3<S>::UnitX()), big), InvalidInput);
}

// Constructions at every scale in the range: ray t unchanged, swept-sphere t unchanged, closest
// points and distances scaled by exactly 2^k.
TYPED_TEST(ScaleRange, ConstructionsScaleExactly) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const TriangleMesh<S> base = make_icosphere<S>(S(1), 2);  // largest coordinate 1
  test::Rng rng(22);
  struct Query {
    Vec3<S> o, d, q;
  };
  std::vector<Query> qs;
  for (int i = 0; i < 12; ++i) {
    const Vec3<S> o = (rng.vec(-1, 1) * 3.0).template cast<S>();
    qs.push_back({o, Vec3<S>((rng.vec(-0.3, 0.3)).template cast<S>() - o), (rng.vec(-1, 1) * 2.0).template cast<S>()});
  }
  const MeshBvh<BV> m0(base);
  const int lo = k_lowest<S>(0) + 1, hi = k_highest<S>(3);
  int wrong = 0, checks = 0;
  for (int k = lo; k <= hi; k += (std::is_same_v<S, float> ? 1 : 3)) {
    TriangleMesh<S> mk = base;
    mk.V *= std::ldexp(S(1), k);
    const MeshBvh<BV> m(mk);
    const S s = std::ldexp(S(1), k);
    for (const Query& q : qs) {
      const auto h0 = ray_mesh_first_hit(m0, Ray<S>(q.o, q.d, S(1)));
      const auto h = ray_mesh_first_hit(m, Ray<S>(q.o * s, q.d * s, S(1)));
      const bool rw = h0.has_value() != h.has_value() || (h0 && (h->t != h0->t || h->triangle != h0->triangle));
      if (rw && wrong < 5) ADD_FAILURE() << "ray k=" << k << " " << h0.has_value() << h.has_value() << " " << (h0 ? h0->t : -1) << " " << (h ? h->t : -1);
      wrong += rw;
      const auto w0 = swept_sphere_mesh_first_hit(m0, Ray<S>(q.o, q.d, S(1)), S(0.05));
      const auto w = swept_sphere_mesh_first_hit(m, Ray<S>(q.o * s, q.d * s, S(1)), S(0.05) * s);
      const bool ww = w0.has_value() != w.has_value() || (w0 && w->t != w0->t);
      if (ww && wrong < 5) ADD_FAILURE() << "sweep k=" << k << " " << w0.has_value() << w.has_value() << " " << (w0 ? w0->t : -1) << " " << (w ? w->t : -1);
      wrong += ww;
      const auto c0 = closest_point_on_mesh(m0, q.q);
      const auto c = closest_point_on_mesh(m, Vec3<S>(q.q * s));
      const bool cw = !c0 || !c || c->distance != c0->distance * s || c->point != Vec3<S>(c0->point * s);
      if (cw && wrong < 5) ADD_FAILURE() << "closest k=" << k << " " << c0->distance << " " << c->distance / s << " " << (c->point / s - c0->point).transpose();
      wrong += cw;
      ++checks;
    }
  }
  EXPECT_EQ(wrong, 0) << "of " << checks << " queries";
}

}  // namespace
}  // namespace impact
