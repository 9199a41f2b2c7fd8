// SPDX-License-Identifier: MIT
// A particle's leg is never validated: a slow particle's direction can be far shorter than
// CoordinateRange::min_scale, where the casts' squared norms underflow (they returned no hit,
// however close the surface: the particle tunnelled). MeshCollider::local_first_hit casts such a
// leg scaled up by a power of two (detail::cast_short_ray). Oracle: brute force over every triangle
// (the narrow phase's per-triangle rule) on the leg with the direction scaled here to components
// in [-1, 1] (another power of two than the cast's), its t scaled back: exactly the same t, through
// the binary tree, the compact tree and the wide tree; and a leg crossing a triangle at its middle
// (a point, or a sphere whose radius scales with the leg) must hit it at t = 1/2. The same for
// the other colliders (plane, sphere, box, the convex shapes): their first hit on a tiny leg is
// their first hit on the same leg scaled to unit length, t scaled back, exactly.
#include "impact/bvh/compact_bvh.hpp"
#include "impact/bvh/wide_bvh.hpp"
#include "impact/convex/convex_collider.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "impact/response/collider.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <vector>

namespace impact {
namespace {

template <class S> class ShortLegs : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ShortLegs, Scalars);

template <class S> std::optional<S> brute_first_t(const TriangleMesh<S>& m, const Ray<S>& ray) {
  const PreparedRay<S> pr(ray);
  std::optional<S> best;
  for (int t = 0; t < m.num_triangles(); ++t) {
    const auto h = detail::ray_mesh_triangle_hit(pr, m.triangle(t));
    if (h && (!best || h->t < *best)) best = h->t;
  }
  return best;
}

// One mesh with its three trees and a collider on each: the binary tree, the compact copy and the
// wide tree (held here: the colliders point to them).
template <class S> struct ThreeTrees {
  explicit ThreeTrees(const TriangleMesh<S>& m) : mb(m), cb(mb.tree()), w(m), plain(mb), compact(mb), wide(mb) {
    compact.compact_tree = &cb;
    wide.wide_tree = &w;
  }
  ThreeTrees(const ThreeTrees&) = delete;
  ThreeTrees& operator=(const ThreeTrees&) = delete;
  const MeshBvh<Aabb<S>> mb;
  const CompactBvh cb;
  const WideBvh<S> w;
  MeshCollider<Aabb<S>> plain, compact, wide;
  std::vector<const MeshCollider<Aabb<S>>*> all() const { return {&plain, &compact, &wide}; }
};

template <class S> Vec3<S> scaled(const Vec3<S>& v, int k) { return {std::ldexp(v[0], k), std::ldexp(v[1], k), std::ldexp(v[2], k)}; }

// The exponents of the legs' lengths: from just below min_scale down to subnormal directions.
template <class S> std::vector<int> tiny_exponents() {
  if constexpr (std::is_same_v<S, float>)
    return {30, 70, 100, 125, 140};
  else
    return {210, 540, 800, 1030, 1060};
}

TYPED_TEST(ShortLegs, SameHitsAsBruteForceOnTheScaledLeg) {
  using S = TypeParam;
  const TriangleMesh<S> m = make_torus<S>(S(1), S(0.4), 24, 12);
  const ThreeTrees<S> trees(m);
  test::Rng rng(83);
  int hits = 0;
  for (int i = 0; i < 60; ++i) {
    const Vec3<S> o = (rng.vec(-1.5, 1.5)).template cast<S>();
    const Vec3<S> u0 = ((rng.vec(-0.4, 0.4) - o.template cast<double>()) / 2).template cast<S>();  // towards the shape
    for (int j : tiny_exponents<S>()) {
      const Vec3<S> d = scaled(u0, -j);  // components may be subnormal
      const Vec3<S> u = scaled(d, j);    // exactly d 2^j
      for (bool segment : {false, true}) {
        const S tu = segment ? S(2) : std::numeric_limits<S>::infinity();
        const S td = std::ldexp(tu, j);
        if (segment && !std::isfinite(td)) continue;
        const auto ref = brute_first_t(m, Ray<S>(o, u, tu));
        for (const MeshCollider<Aabb<S>>* c : trees.all()) {
          const auto h = c->local_first_hit(o, d, S(0), td);
          ASSERT_EQ(ref.has_value(), h.has_value()) << i << " " << j << " " << segment;
          if (!ref) continue;
          ++hits;
          EXPECT_EQ(h->t, std::ldexp(*ref, j)) << i << " " << j;
        }
      }
    }
  }
  EXPECT_GT(hits, 300);
}

// A leg from one side of a triangle to the other, centred on it: the hit at t = 1/2 for every
// length (down to subnormal legs), through the three trees; and a sphere whose radius scales with
// the leg, while its square stays a normal number.
TYPED_TEST(ShortLegs, CrossingLegHitsAtItsMiddle) {
  using S = TypeParam;
  TriangleMesh<S> m;
  m.V.resize(3, 3);
  m.F.resize(1, 3);
  m.V << S(0), S(-1), S(-1), S(0), S(2), S(-1), S(0), S(-1), S(2);
  m.F << 0, 1, 2;
  const ThreeTrees<S> trees(m);
  const int lowest = std::numeric_limits<S>::min_exponent - std::numeric_limits<S>::digits;  // denorm_min = 2^(lowest)
  for (int j = 0; -j - 1 >= lowest; j += 7) {
    const S len = std::ldexp(S(1), -j);
    const Vec3<S> o(-len / S(2), S(0.1), S(0.2));
    const Vec3<S> d(len, S(0), S(0));
    for (const MeshCollider<Aabb<S>>* c : trees.all()) {
      const auto h = c->local_first_hit(o, d, S(0), S(1));
      ASSERT_TRUE(h.has_value()) << j;
      EXPECT_EQ(h->t, S(0.5)) << j;
    }
    // a sphere of radius 16 len touching the triangle at the leg's middle, while r * r stays normal
    const S r = std::ldexp(S(1), 4 - j);
    if (r < std::sqrt(std::numeric_limits<S>::min())) continue;
    const Vec3<S> os(-r - len / S(2), S(0.1), S(0.2));  // exact: the two terms 5 bits apart
    const auto s = trees.plain.local_first_hit(os, d, r, S(1));
    ASSERT_TRUE(s.has_value()) << j;
    EXPECT_NEAR(double(s->t), 0.5, 1e-3) << j;
  }
}

// A mesh collider's sphere below the sweep's resolution (query/swept_sphere_mesh.hpp) never goes
// through an edge or a vertex, whichever tree the collider holds (the binary, compact or wide
// tree: spheres are swept on the binary tree): from the centre of a closed unit icosphere towards
// each vertex and edge midpoint, every leg the point crosses the shell on is hit no later. Before,
// 104 of 1,122 legs went through for r = 1e-18 (double), 88 for r = 1e-8 (float).
TYPED_TEST(ShortLegs, TinySpheresNeverTunnelThroughAnyTree) {
  using S = TypeParam;
  const TriangleMesh<S> m = make_icosphere<S>(S(1), 2);
  const ThreeTrees<S> trees(m);
  const S r = std::is_same_v<S, float> ? S(1e-8) : S(1e-18);
  std::vector<Vec3<S>> targets;
  for (int i = 0; i < m.num_vertices(); ++i) targets.push_back(m.vertex(i));
  for (int t = 0; t < m.num_triangles(); t += IMPACT_TEST_SANITIZED ? 4 : 1)
    for (int k = 0; k < 3; ++k) targets.push_back((m.vertex(m.F(t, k)) + m.vertex(m.F(t, (k + 1) % 3))) / S(2));
  for (const MeshCollider<Aabb<S>>* c : trees.all()) {
    int misses = 0;
    for (const Vec3<S>& p : targets) {
      const auto g = c->local_first_hit(Vec3<S>::Zero(), p, S(0), S(2));
      const auto h = c->local_first_hit(Vec3<S>::Zero(), p, r, S(2));
      if (g && (!h || h->t > g->t)) ++misses;
    }
    EXPECT_EQ(misses, 0) << targets.size() << " legs";
  }
}

// Every collider's first hit on a tiny leg (the direction u 2^-j, t_max scaled up by 2^j; u aimed
// near the shape's middle) against its first hit on the leg u: the same t scaled by 2^j, bit for
// bit, and the same normal. Before the scaling, the plane, sphere, box and convex colliders found
// nothing on such legs (their products of the direction underflowed), whatever lay ahead.
template <class S, class C> void expect_scale_free(const C& c, const char* name, test::Rng& rng) {
  int hits = 0;
  for (int i = 0; i < 40; ++i) {
    const Vec3<S> o = (rng.vec(-2, 2)).template cast<S>();
    const Vec3<S> u0 = ((rng.vec(-0.4, 0.4) - o.template cast<double>()) / 2).template cast<S>();  // towards the shape
    for (const S r : {S(0), S(0.125)}) {
      const S tu = S(6);
      for (int j : tiny_exponents<S>()) {
        const S td = std::ldexp(tu, j);
        if (!std::isfinite(td)) continue;
        const Vec3<S> d = scaled(u0, -j);  // components may be subnormal
        const Vec3<S> u = scaled(d, j);    // exactly d 2^j
        const auto ref = c.local_first_hit(o, u, r, tu);
        const auto h = c.local_first_hit(o, d, r, td);
        ASSERT_EQ(ref.has_value(), h.has_value()) << name << " " << i << " r " << r << " j " << j;
        if (!ref) continue;
        ++hits;
        EXPECT_EQ(h->t, std::ldexp(ref->t, j)) << name << " " << i << " r " << r << " j " << j;
        EXPECT_EQ(h->normal, ref->normal) << name << " " << i;
      }
    }
  }
  EXPECT_GT(hits, 60) << name;  // legs aimed near the shape's middle, 3 times as long as needed: many hit
}

TYPED_TEST(ShortLegs, EveryColliderAnswersTinyLegs) {
  using S = TypeParam;
  test::Rng rng(91);
  expect_scale_free<S>(PlaneCollider<S>(Plane<S>(Vec3<S>(S(0.6), S(0), S(0.8)), S(0.25))), "plane", rng);
  expect_scale_free<S>(SphereCollider<S>(Sphere<S>{Vec3<S>(S(0.25), S(0), S(0)), S(1)}), "sphere", rng);
  expect_scale_free<S>(SphereCollider<S>(Sphere<S>{Vec3<S>(S(0), S(0), S(0)), S(3.5)}, ColliderSide::Inside), "hollow sphere", rng);
  Obb<S> box;
  box.center = Vec3<S>(S(0.125), S(-0.25), S(0));
  box.axes = Eigen::AngleAxis<S>(S(0.5), Vec3<S>(S(0.6), S(0), S(0.8))).toRotationMatrix();
  box.half = Vec3<S>(S(1), S(0.5), S(0.75));
  expect_scale_free<S>(BoxCollider<S>(box), "box", rng);
  expect_scale_free<S>(BoxCollider<S>(box, ColliderSide::Inside), "hollow box", rng);
  expect_scale_free<S>(ConvexCollider<S, Capsule<S>>(Capsule<S>(S(0.5), S(0.75))), "capsule", rng);
  expect_scale_free<S>(ConvexCollider<S, Cylinder<S>>(Cylinder<S>(S(0.75), S(0.5))), "cylinder", rng);
  expect_scale_free<S>(ConvexCollider<S, Cone<S>>(Cone<S>(S(0.75), S(0.75))), "cone", rng);
}

}  // namespace
}  // namespace impact
