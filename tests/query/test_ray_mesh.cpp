// SPDX-License-Identifier: MIT
// Ray-mesh first/any hit and swept-sphere-mesh first hit against brute force over all triangles,
// in float and double, for AABB, sphere and oriented-box trees, under random rigid poses;
// watertightness at shared edges and vertices; rays parallel to faces; the t = 0 front-side rule;
// exact equality with the loop on integer and degenerate meshes (slivers, very unequal sizes,
// coincident centroids and triangles).
#include "impact/bvh/compact_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/swept_sphere_mesh.hpp"
#include "support/data.hpp"
#include "support/loop_oracles.hpp"
#include "support/meshes.hpp"
#include "support/obj_reader.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "support/sanitizer.hpp"

// Fewer samples under the sanitizers (CI), the full count in Release.
constexpr int kRaySamples = IMPACT_TEST_SANITIZED ? 4 : 1;

namespace impact {
namespace {

template <class S> TriangleMesh<S> transformed(const TriangleMesh<S>& m, const RigidTransform<S>& P) {
  TriangleMesh<S> w = m;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) w.V.row(i) = P.apply(m.V.row(i).transpose()).transpose();
  return w;
}

// Brute force: the same watertight test on every triangle of the mesh given in world coordinates.
template <class T> class RayMesh : public ::testing::Test {};
using RayBVs = ::testing::Types<Aabb<float>, Aabb<double>, Sphere<float>, Sphere<double>, Obb<float>, Obb<double>>;
TYPED_TEST_SUITE(RayMesh, RayBVs);

template <class BV> void check_against_brute_force(const TriangleMesh<typename BvTraits<BV>::Scalar>& m, std::uint64_t seed, int n_rays) {
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> bvh(m);
  test::Rng rng(seed);
  n_rays /= kRaySamples;
  Aabb<S> box;
  for (int i = 0; i < m.num_vertices(); ++i) box.extend(m.vertex(i));
  const S diag = S(2) * box.half_diagonal();
  const S tol = std::is_same_v<S, float> ? S(2e-4) : S(1e-10);
  int hits = 0;
  for (int k = 0; k < n_rays; ++k) {
    const RigidTransform<S> P = test::random_pose(rng, Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)).cast<S>();
    const TriangleMesh<S> w = transformed(m, P);
    const Vec3<S> c = P.apply(box.center());
    const Vec3<S> o = c + (rng.vec(-1, 1) * double(diag)).cast<S>();
    const Vec3<S> target = c + (rng.vec(-0.5, 0.5) * double(diag)).cast<S>();
    const S t_max = k % 3 == 0 ? std::numeric_limits<S>::infinity() : S(rng.uniform(0.2, 1.2));
    const Ray<S> ray(o, target - o, t_max);
    const auto h = ray_mesh_first_hit(bvh, ray, P);
    const auto b = test::loop_first_hit(w, ray);
    ASSERT_EQ(h.has_value(), b.has_value()) << "ray " << k;
    EXPECT_EQ(ray_mesh_any_hit(bvh, ray, P), b.has_value());
    if (!h) continue;
    ++hits;
    EXPECT_NEAR(h->t, b->first, tol * (S(1) + b->first)) << "ray " << k;
    EXPECT_LE((h->point - (o + h->t * ray.direction)).norm(), tol * diag);
    // the reported triangle contains the hit point
    const Triangle<S> tri = w.triangle(h->triangle);
    const Vec3<S> q = tri.a * h->barycentric[0] + tri.b * h->barycentric[1] + tri.c * h->barycentric[2];
    EXPECT_LE((q - h->point).norm(), S(50) * tol * diag);
    EXPECT_NEAR(std::abs(h->normal.dot(tri.normal())), S(1), S(1e-4));
  }
  EXPECT_GT(hits, n_rays / 20);
}

TYPED_TEST(RayMesh, MatchesBruteForceOnGeneratedMeshes) {
  using S = typename BvTraits<TypeParam>::Scalar;
  check_against_brute_force<TypeParam>(make_icosphere<S>(S(1), 3), 1, 300);
  check_against_brute_force<TypeParam>(make_torus<S>(S(1), S(0.3), 24, 12), 2, 300);
  check_against_brute_force<TypeParam>(make_random_soup<S>(400, 3, S(1), S(0.2)), 3, 300);
}

TYPED_TEST(RayMesh, MatchesBruteForceOnSpot) {
  using S = typename BvTraits<TypeParam>::Scalar;
  IMPACT_REQUIRE_DATA(path, "meshes/spot.obj");
  check_against_brute_force<TypeParam>(test::read_obj<S>(path), 4, 200);
}

// Rays from inside a closed mesh must hit it whatever their direction, also exactly through
// vertices and edges (watertightness).
TYPED_TEST(RayMesh, ClosedMeshIsWatertightAtEdgesAndVertices) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const TriangleMesh<S> m = make_icosphere<S>(S(1), 2);
  const MeshBvh<TypeParam> bvh(m);
  for (int i = 0; i < m.num_vertices(); ++i) {
    const Vec3<S> v = m.vertex(i);
    EXPECT_TRUE(ray_mesh_first_hit(bvh, Ray<S>(Vec3<S>::Zero(), v)).has_value()) << "vertex " << i;
  }
  for (int t = 0; t < m.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3<S> mid = (m.vertex(m.F(t, k)) + m.vertex(m.F(t, (k + 1) % 3))) / S(2);
      EXPECT_TRUE(ray_mesh_first_hit(bvh, Ray<S>(Vec3<S>::Zero(), mid)).has_value()) << "edge " << t << "," << k;
      EXPECT_TRUE(ray_mesh_any_hit(bvh, Ray<S>(Vec3<S>::Zero(), mid)));
    }
  // A flat grid hit exactly at its shared vertices and edges by axis-aligned rays.
  const TriangleMesh<S> g = make_grid<S>(8, 8, S(2));
  const MeshBvh<TypeParam> gb(g);
  for (int i = 0; i <= 16; ++i)
    for (int j = 0; j <= 16; ++j) {
      const Vec3<S> o(S(-1) + S(i) / S(8), S(-1) + S(j) / S(8), S(1));
      const auto h = ray_mesh_first_hit(gb, Ray<S>(o, Vec3<S>(0, 0, -3)));
      ASSERT_TRUE(h.has_value()) << i << "," << j;
      EXPECT_NEAR(h->t, S(1) / S(3), S(1e-6));
    }
}

TYPED_TEST(RayMesh, ParallelRaysAndSurfaceStarts) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const MeshBvh<TypeParam> gb(make_grid<S>(4, 4, S(2)));
  // in the plane of the faces: miss, no NaN
  EXPECT_FALSE(ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(-2, 0.1, 0), Vec3<S>(4, 0, 0))).has_value());
  EXPECT_FALSE(ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(-2, 0, 0), Vec3<S>(4, 0, 0))).has_value());
  // parallel just above: miss
  EXPECT_FALSE(ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(-2, 0.1, S(1e-6)), Vec3<S>(4, 0, 0))).has_value());
  // starting exactly on the front (the grid's normal is +z): into the surface hits at 0, away misses
  const auto in = ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(0.3, 0.2, 0), Vec3<S>(0.1, 0, -1), S(1)));
  ASSERT_TRUE(in.has_value());
  EXPECT_EQ(in->t, S(0));
  EXPECT_TRUE(in->front_face);
  EXPECT_FALSE(ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(0.3, 0.2, 0), Vec3<S>(0.1, 0, 1), S(1))).has_value());
  // from behind, crossing: a two-sided hit with front_face false
  const auto back = ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(0.3, 0.2, -1), Vec3<S>(0, 0, 2), S(1)));
  ASSERT_TRUE(back.has_value());
  EXPECT_FALSE(back->front_face);
  EXPECT_NEAR(back->t, S(0.5), S(1e-6));
  // zero direction: not a ray (it used to return no hit, even from a point on the surface)
  EXPECT_THROW(ray_mesh_first_hit(gb, Ray<S>(Vec3<S>(0.3, 0.2, 0), Vec3<S>::Zero(), S(1))), InvalidInput);
}

// The t = 0 rule for every direction (audit of 2026-12-07): from a point exactly on the surface,
// a ray into the front hits at t = 0 and one away misses, also when the ray's dominant axis is not
// the normal's (before the fix, tt's rounded sign lost about a third of those rays into the front:
// a particle resting on a floor tunnelled through it).
TYPED_TEST(RayMesh, SurfaceStartsInEveryDirection) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const MeshBvh<TypeParam> gb(make_grid<S>(4, 4, S(2)));  // z = 0, normal +z
  test::Rng rng(77);
  int oblique = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vec3<S> o(S(rng.uniform(-0.9, 0.9)), S(rng.uniform(-0.9, 0.9)), S(0));
    Vec3<S> d = rng.vec(-1, 1).cast<S>();
    if (!(std::abs(d.z()) > S(1e-3))) continue;
    oblique += std::abs(d.z()) < std::max(std::abs(d.x()), std::abs(d.y()));
    d.z() = -std::abs(d.z());
    const auto in = ray_mesh_first_hit(gb, Ray<S>(o, d, S(1)));
    ASSERT_TRUE(in.has_value()) << "ray " << k << " from (" << o.transpose() << ") along (" << d.transpose() << ")";
    EXPECT_EQ(in->t, S(0)) << "ray " << k;
    EXPECT_TRUE(in->front_face) << "ray " << k;
    d.z() = -d.z();
    EXPECT_FALSE(ray_mesh_first_hit(gb, Ray<S>(o, d, S(1))).has_value()) << "ray " << k;
  }
  EXPECT_GT(oblique, 1000);
}

// Swept sphere: the BVH query equals the minimum over all triangles, and at the returned time
// the sphere touches the mesh (distance = r) while just before it does not (checked with an
// independent brute-force closest point).
TYPED_TEST(RayMesh, SweptSphereMatchesBruteForceAndTouches) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const TriangleMesh<S> m = make_torus<S>(S(1), S(0.3), 16, 8);
  const MeshBvh<TypeParam> bvh(m);
  test::Rng rng(7);
  const S tol = std::is_same_v<S, float> ? S(2e-3) : S(1e-9);
  int hits = 0;
  std::array<int, 3> by_kind{0, 0, 0};
  for (int k = 0; k < 400 / kRaySamples; ++k) {
    const S r = S(rng.uniform(0.01, 0.2));
    const Vec3<S> o = (rng.vec(-2, 2)).cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * 3.0).cast<S>();
    const Ray<S> ray(o, d, S(1));
    // skip starts that already overlap (tested separately)
    S d0 = std::numeric_limits<S>::infinity();
    for (int t = 0; t < m.num_triangles(); ++t) d0 = std::min(d0, (o - detail::closest_on_triangle(o, m.triangle(t)).point).norm());
    if (d0 <= r) continue;
    const auto h = swept_sphere_mesh_first_hit(bvh, ray, r);
    std::optional<S> bt;
    for (int t = 0; t < m.num_triangles(); ++t) {
      const auto bh = detail::swept_sphere_triangle(o, d, r, m.triangle(t), S(1));
      if (bh && (!bt || bh->t < *bt)) bt = bh->t;
    }
    ASSERT_EQ(h.has_value(), bt.has_value());
    if (!h) continue;
    ++hits;
    EXPECT_NEAR(h->t, *bt, tol);
    ++by_kind[h->feature == TriangleFeature::Face ? 0 : (is_edge(h->feature) ? 1 : 2)];
    auto dist_at = [&](S t) {
      S best = std::numeric_limits<S>::infinity();
      for (int i = 0; i < m.num_triangles(); ++i)
        best = std::min(best, (ray.at(t) - detail::closest_on_triangle(ray.at(t), m.triangle(i)).point).norm());
      return best;
    };
    EXPECT_NEAR(dist_at(h->t), r, S(10) * tol);
    if (h->t > S(1e-3)) {
      EXPECT_GT(dist_at(h->t * S(0.999)), r * (S(1) - S(10) * tol));
    }
    EXPECT_NEAR(h->normal.norm(), S(1), S(1e-4));
    EXPECT_LT(h->normal.dot(d), S(0));
  }
  EXPECT_GT(hits, 20 / kRaySamples);
  EXPECT_GT(by_kind[0], 0);  // faces
}

TYPED_TEST(RayMesh, SweptSphereHitsEdgesAndVerticesAndStartsInContact) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const MeshBvh<TypeParam> box(make_box<S>(Vec3<S>::Ones()));
  const S r = S(0.25);
  // towards a vertex along the diagonal: first contact at the corner
  const Vec3<S> o = Vec3<S>::Constant(3);
  auto h = swept_sphere_mesh_first_hit(box, Ray<S>(o, Vec3<S>::Constant(-2), S(1)), r);
  ASSERT_TRUE(h.has_value());
  EXPECT_TRUE(is_vertex(h->feature));
  EXPECT_NEAR((o + h->t * Vec3<S>::Constant(-2) - Vec3<S>::Ones()).norm(), r, S(1e-5));
  // towards an edge (x = y = 1)
  h = swept_sphere_mesh_first_hit(box, Ray<S>(Vec3<S>(3, 3, 0.2), Vec3<S>(-2, -2, 0), S(1)), r);
  ASSERT_TRUE(h.has_value());
  EXPECT_TRUE(is_edge(h->feature));
  EXPECT_NEAR(h->normal.dot(Vec3<S>(1, 1, 0).normalized()), S(1), S(1e-5));
  // touching a face at t = 0: moving in hits now, moving away does not
  const Vec3<S> touching(S(0.2), S(0.1), S(1) + r);
  h = swept_sphere_mesh_first_hit(box, Ray<S>(touching, Vec3<S>(0, 0, -1), S(1)), r);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, S(0));
  EXPECT_FALSE(swept_sphere_mesh_first_hit(box, Ray<S>(touching, Vec3<S>(0, 0, 1), S(1)), r).has_value());
  EXPECT_FALSE(swept_sphere_mesh_first_hit(box, Ray<S>(touching, Vec3<S>(1, 0, 0), S(0.5)), r).has_value());
}

// A sphere whose radius squared is not a normal number is cast as a point: aimed from the centre
// of a closed icosphere exactly at each vertex and edge midpoint it hits at the ray cast's t and
// triangle, never passing through. Before, r * r rounded to zero and the sweep lost the tube
// around each edge and the ball around each vertex: 104 of these 1,122 paths went through
// (r = 2^-520 in double; 88 in float, r = 2^-70).
TYPED_TEST(RayMesh, SweptSphereWithUnderflowingRadiusIsAPoint) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const TriangleMesh<S> m = make_icosphere<S>(S(1), 2);
  const MeshBvh<TypeParam> bvh(m);
  const bool is_float = std::is_same_v<S, float>;
  const S radii[] = {std::ldexp(S(1), is_float ? -64 : -512), std::ldexp(S(1), is_float ? -70 : -520),
                     std::numeric_limits<S>::denorm_min()};  // r * r subnormal or zero
  std::vector<Vec3<S>> targets;
  for (int i = 0; i < m.num_vertices(); ++i) targets.push_back(m.vertex(i));
  for (int t = 0; t < m.num_triangles(); t += kRaySamples)
    for (int k = 0; k < 3; ++k) targets.push_back((m.vertex(m.F(t, k)) + m.vertex(m.F(t, (k + 1) % 3))) / S(2));
  for (const Vec3<S>& p : targets) {
    const Ray<S> ray(Vec3<S>::Zero(), p, S(2));
    const auto g = ray_mesh_first_hit(bvh, ray);
    ASSERT_TRUE(g.has_value());
    for (const S r : radii) {
      const auto h = swept_sphere_mesh_first_hit(bvh, ray, r);
      ASSERT_TRUE(h.has_value()) << "r " << r << " through " << p.transpose();
      EXPECT_EQ(h->t, g->t) << "r " << r;
      EXPECT_EQ(h->triangle, g->triangle) << "r " << r;
      EXPECT_LT(h->normal.dot(ray.direction), S(0));
    }
  }
  // the bound itself is swept: r * r is the smallest normal number
  EXPECT_EQ(detail::kMinSweptRadius<S> * detail::kMinSweptRadius<S>, std::numeric_limits<S>::min());
}

// A sphere whose r * r is normal but below the sweep's rounding (r < 2^-20 L in double, 2^-12 L in
// float) is swept and also cast as a point, the earlier hit taken: aimed from the centre of a
// closed unit icosphere exactly at each vertex and edge midpoint, it hits no later than the ray
// cast (the centre's crossing), never passing through. Before, the sweep alone missed 104 of these
// 1,122 paths for r = 1e-18, 16 for 1e-16 (double), 88 for r = 1e-8 (float).
TYPED_TEST(RayMesh, SweptSphereBelowTheSweepsResolutionNeverTunnels) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const TriangleMesh<S> m = make_icosphere<S>(S(1), 2);
  const MeshBvh<TypeParam> bvh(m);
  std::vector<S> radii;
  if constexpr (std::is_same_v<S, float>)
    radii = {S(1e-8), S(1e-6)};
  else
    radii = {S(1e-18), S(1e-16), S(1e-12), S(1e-9)};
  std::vector<Vec3<S>> targets;
  for (int i = 0; i < m.num_vertices(); ++i) targets.push_back(m.vertex(i));
  for (int t = 0; t < m.num_triangles(); t += kRaySamples)
    for (int k = 0; k < 3; ++k) targets.push_back((m.vertex(m.F(t, k)) + m.vertex(m.F(t, (k + 1) % 3))) / S(2));
  for (const S r : radii) {
    ASSERT_LT(r, detail::kSweptRadiusResolution<S>);
    int misses = 0;
    for (const Vec3<S>& p : targets) {
      const Ray<S> ray(Vec3<S>::Zero(), p, S(2));
      const auto g = ray_mesh_first_hit(bvh, ray);
      ASSERT_TRUE(g.has_value());
      const auto h = swept_sphere_mesh_first_hit(bvh, ray, r);
      if (!h || h->t > g->t) {
        ++misses;
        continue;
      }
      EXPECT_GE(h->t, S(0.5));  // the sphere stays inside until it nears the shell
      EXPECT_LT(h->normal.dot(ray.direction), S(0)) << "r " << r;
    }
    EXPECT_EQ(misses, 0) << "r " << r << " of " << targets.size() << " paths";
  }
  // a radius far above the resolution is swept alone: it touches strictly before the centre crosses
  const S big = S(1e-2);
  const Ray<S> ray(Vec3<S>::Zero(), m.vertex(0), S(2));
  const auto g = ray_mesh_first_hit(bvh, ray);
  const auto h = swept_sphere_mesh_first_hit(bvh, ray, big);
  ASSERT_TRUE(g.has_value());
  ASSERT_TRUE(h.has_value());
  EXPECT_LT(h->t, g->t);
}

// Coincident triangles (issue 12): 4,096 copies of one triangle, all hit at the same t. The
// top-down build gathers them in one leaf and the cast tests one (every BV;
// test_coincident_copies.cpp has the general case). Trees that do not gather them (bottom-up)
// rely on pruning: once one is hit, nodes entered at that t cannot hold an earlier hit and are
// pruned: before, every node and every triangle was visited (4,096 triangle tests; on 200 k
// copies 0.19 s a ray). The same through a CompactBvh, and the hit itself is unchanged (box
// trees; see below for spheres).
TYPED_TEST(RayMesh, CoincidentTrianglesArePruned) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const TriangleMesh<S> m = impact::test::coincident_copies<S>(4096);
  const Ray<S> ray(Vec3<S>(S(0.25), S(0.25), S(1)), Vec3<S>(0, 0, -1), S(10));
  {
    const MeshBvh<BV> gathered(m);
    RayMeshStats sg;
    const auto hg = ray_mesh_first_hit(gathered, ray, {}, &sg);
    ASSERT_TRUE(hg.has_value());
    EXPECT_EQ(hg->t, S(1));
    EXPECT_EQ(sg.triangle_tests, 1u);
    EXPECT_EQ(sg.node_tests, 1u);
  }
  MeshBvhConfig bottom_up;
  bottom_up.build.method = BuildMethod::BottomUp;
  const MeshBvh<BV> bvh(m, bottom_up);
  RayMeshStats st;
  const auto h = ray_mesh_first_hit(bvh, ray, {}, &st);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->t, S(1));
  // Boxes only: a node's box is entered at t = 1 itself. A node's sphere is entered earlier (it
  // could hold an earlier hit as far as it tells), so sphere trees still visit every copy; so do
  // oriented-box trees, whose keys are entries into hulls grown by their rounding.
  if constexpr (std::is_same_v<BV, Aabb<S>>) {
    EXPECT_LE(st.triangle_tests, 8u);  // the first leaf's triangles
    EXPECT_LE(st.node_tests, 200u);    // about two per level on the path to it
    const CompactBvh fast(bvh.tree());
    RayMeshStats sc;
    const auto hc = ray_mesh_first_hit(bvh, fast, ray, {}, &sc);
    ASSERT_TRUE(hc.has_value());
    EXPECT_EQ(hc->t, S(1));
    EXPECT_LE(sc.triangle_tests, 8u);
  }
}

// The first hit is exactly the smallest t of a loop over every triangle (issue 12, found by the
// mesh_bvh fuzz target). The ray o + t d, o = (-3, -3, -4), d = (2, 1, 3), passes exactly through
// the vertex (-1, -2, -1) at t = 1, a corner of both triangles' boxes. The narrow phase computes
// t = 1 for the first triangle and 1 - 2^-53 for the second (its t is a rounded convex combination
// of the vertices' depths); before the fix the tree returned 1 (it pruned the second triangle's
// node, entered at t = 1 = the best found) while the loop found 1 - 2^-53. A hit's t is now never
// below the entry into its triangle's box, so both give exactly 1, the exact answer. (Since the
// edge functions' signs are exact, issue 14: the ray lies exactly in the first triangle's plane,
// normal (-1, 5, -1), so that triangle is not hit, as every ray in a triangle's plane; the second
// is, at exactly 1.)
TEST(RayMeshExact, FirstHitThroughASharedBoxCorner) {
  TriangleMesh<double> m;
  m.V.resize(5, 3);
  m.V << -1, -2, -1, 2, -1, 1, 0, -2, -2, 2, 0, 1, 0, 1, -1;
  m.F.resize(2, 3);
  m.F << 0, 1, 2, 0, 3, 4;
  const Ray<double> ray(Vec3<double>(-3, -3, -4), Vec3<double>(2, 1, 3));
  const PreparedRay<double> pr(ray);
  EXPECT_EQ(m.triangle(0).scaled_normal().dot(ray.direction), 0.0);  // (exactly: small integers)
  EXPECT_FALSE(detail::ray_mesh_triangle_hit(pr, m.triangle(0)).has_value());  // in its plane
  const auto h1 = detail::ray_mesh_triangle_hit(pr, m.triangle(1));
  ASSERT_TRUE(h1.has_value());
  EXPECT_EQ(h1->t, 1.0);  // before the fix of issue 12: 1 - 2^-53
  for (int leaf : {1, 4}) {
    MeshBvhConfig cfg;
    cfg.build.leaf_size = leaf;
    const MeshBvh<Aabb<double>> ab(m, cfg);
    const MeshBvh<Sphere<double>> sp(m, cfg);
    const CompactBvh fast(ab.tree(), 1);
    for (const auto& h : {ray_mesh_first_hit(ab, ray), ray_mesh_first_hit(ab, fast, ray), ray_mesh_first_hit(sp, ray)}) {
      ASSERT_TRUE(h.has_value());
      EXPECT_EQ(h->t, 1.0);
      EXPECT_EQ(h->point, Vec3<double>(-1, -2, -1));
    }
  }
}

// Small integer meshes (shared and coincident vertices, triangles edge-on to the rays, rays
// through vertices and edges and in the triangles' planes: the cases where the narrow phase's t
// rounds below the boxes' entries) under exact poses: the tree's first hit has exactly the
// smallest t of the loop over every triangle, for box trees, CompactBvh, sphere and oriented-box
// trees, float and double, and any hit agrees.
template <class S> void check_integer_grid_rays(std::uint64_t seed) {
  test::Rng rng(seed);
  int hits = 0;
  for (int mesh = 0; mesh < 150 / kRaySamples; ++mesh) {
    TriangleMesh<S> m;
    const int nv = 4 + int(rng.index(8)), nf = 1 + int(rng.index(16));
    m.V.resize(nv, 3);
    m.F.resize(nf, 3);
    for (int i = 0; i < nv; ++i)
      for (int d = 0; d < 3; ++d) m.V(i, d) = S(int(rng.index(7)) - 3);
    for (int f = 0; f < nf; ++f)
      for (int d = 0; d < 3; ++d) m.F(f, d) = int(rng.index(std::uint64_t(nv)));
    const MeshBvh<Aabb<S>> ab(m);
    const MeshBvh<Sphere<S>> sp(m);
    const MeshBvh<Obb<S>> ob(m);
    const CompactBvh fast(ab.tree(), 1);
    for (int k = 0; k < 24; ++k) {
      Vec3<S> o, d;
      for (int i = 0; i < 3; ++i) o[i] = S(int(rng.index(13)) - 6), d[i] = S(int(rng.index(9)) - 4);
      if (k % 2) d = m.vertex(int(rng.index(std::uint64_t(nv)))) - o;  // through a vertex, at t = 1
      if (d == Vec3<S>::Zero()) continue;
      const Ray<S> ray(o, d, k % 4 == 1 ? S(1) : std::numeric_limits<S>::infinity());
      const auto b = test::loop_first_hit(m, ray);
      hits += b.has_value();
      const auto ha = ray_mesh_first_hit(ab, ray), hc = ray_mesh_first_hit(ab, fast, ray), hs = ray_mesh_first_hit(sp, ray);
      const auto ho = ray_mesh_first_hit(ob, ray);
      ASSERT_EQ(ha.has_value(), b.has_value()) << mesh << "," << k;
      ASSERT_EQ(hc.has_value(), b.has_value()) << mesh << "," << k;
      ASSERT_EQ(hs.has_value(), b.has_value()) << mesh << "," << k;
      ASSERT_EQ(ho.has_value(), b.has_value()) << mesh << "," << k;
      EXPECT_EQ(ray_mesh_any_hit(ab, ray), b.has_value());
      EXPECT_EQ(ray_mesh_any_hit(sp, ray), b.has_value());
      EXPECT_EQ(ray_mesh_any_hit(ob, ray), b.has_value());
      if (!b) continue;
      EXPECT_EQ(ha->t, b->first) << mesh << "," << k;
      EXPECT_EQ(hc->t, b->first) << mesh << "," << k;
      EXPECT_EQ(hs->t, b->first) << mesh << "," << k;
      EXPECT_EQ(ho->t, b->first) << mesh << "," << k;
    }
  }
  EXPECT_GT(hits, 100 / kRaySamples);
}

TEST(RayMeshExact, IntegerGridFirstHitIsTheLoopMinimum) {
  check_integer_grid_rays<double>(11);
  check_integer_grid_rays<float>(12);
}

// Degenerate soups (test::degenerate_soup: slivers across the box, sizes from 1e-4 to 1,
// coincident centroids, exact copies), every builder: box and oriented-box trees give exactly the
// loop's smallest t (sphere trees to rounding), any hit agrees, and the reported triangle is hit
// at that t. Rays from around the box through random points, and rays through vertices (the cases
// whose t rounds below a box's entry). In the mesh's frame, so that the loop sees the same ray
// bit for bit (poses are covered above).
template <class S> void check_degenerate_soup_rays(std::uint64_t seed) {
  const TriangleMesh<S> m = test::degenerate_soup<S>(200, seed);
  test::Rng rng(seed + 1);
  int hits = 0;
  for (BuildMethod method : {BuildMethod::TopDown, BuildMethod::BottomUp, BuildMethod::Incremental}) {
    MeshBvhConfig cfg;
    cfg.build.method = method;
    const MeshBvh<Aabb<S>> ab(m, cfg);
    const MeshBvh<Sphere<S>> sp(m, cfg);
    const MeshBvh<Obb<S>> ob(m, cfg);
    for (int k = 0; k < 200 / kRaySamples; ++k) {
      const Vec3<S> o = rng.vec(-1.5, 1.5).cast<S>();
      const Vec3<S> target = k % 2 ? m.vertex(int(rng.index(std::uint64_t(m.num_vertices())))) : Vec3<S>(rng.vec(-1, 1).cast<S>());
      if (target == o) continue;
      const Ray<S> ray(o, target - o, k % 3 == 0 ? S(1) : std::numeric_limits<S>::infinity());
      const auto b = test::loop_first_hit(m, ray);
      const auto ha = ray_mesh_first_hit(ab, ray), hs = ray_mesh_first_hit(sp, ray), ho = ray_mesh_first_hit(ob, ray);
      ASSERT_EQ(ha.has_value(), b.has_value()) << k;
      ASSERT_EQ(ho.has_value(), b.has_value()) << k;
      ASSERT_EQ(hs.has_value(), b.has_value()) << k << " method " << int(method) << " float " << std::is_same_v<S, float> << " tmax " << ray.t_max << " t " << b->first << " tri " << b->second;
      EXPECT_EQ(ray_mesh_any_hit(ob, ray), b.has_value()) << k;
      EXPECT_EQ(ray_mesh_any_hit(ab, ray), b.has_value()) << k;
      if (!b) continue;
      ++hits;
      EXPECT_EQ(ha->t, b->first) << k;
      EXPECT_EQ(ho->t, b->first) << k;
      EXPECT_NEAR(hs->t, b->first, S(1e-4) * (S(1) + b->first)) << k;
      const auto th = detail::ray_mesh_triangle_hit(PreparedRay<S>(ray), m.triangle(ho->triangle));
      EXPECT_TRUE(th && th->t == ho->t) << k;
    }
  }
  EXPECT_GT(hits, 150 / kRaySamples);
}

TEST(RayMeshExact, DegenerateSoupFirstHitIsTheLoopMinimum) {
  check_degenerate_soup_rays<double>(31);
  check_degenerate_soup_rays<float>(32);
}

}  // namespace
}  // namespace impact
