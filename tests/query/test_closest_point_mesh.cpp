// SPDX-License-Identifier: MIT
// Closest point on a mesh through the BVH against brute force over all triangles, float and
// double, AABB, sphere and oriented-box trees, under random poses; features, normals and the
// distance bound; exact equality with the loop on integer and degenerate meshes; the work
// counters.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "support/data.hpp"
#include "support/meshes.hpp"
#include "support/obj_reader.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

// Fewer samples under the sanitizers (CI), the full count in Release.
constexpr int kClosestSamples = IMPACT_TEST_SANITIZED ? 4 : 1;

namespace impact {
namespace {

template <class T> class ClosestPointMesh : public ::testing::Test {};
using ClosestBVs = ::testing::Types<Aabb<float>, Aabb<double>, Sphere<float>, Sphere<double>, Obb<float>, Obb<double>>;
TYPED_TEST_SUITE(ClosestPointMesh, ClosestBVs);

template <class BV> void check(const TriangleMesh<typename BvTraits<BV>::Scalar>& m, std::uint64_t seed, int n) {
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> bvh(m);
  test::Rng rng(seed);
  n /= kClosestSamples;
  Aabb<S> box;
  for (int i = 0; i < m.num_vertices(); ++i) box.extend(m.vertex(i));
  const double diag = 2 * double(box.half_diagonal());
  const S tol = std::is_same_v<S, float> ? S(1e-5) * S(diag) : S(1e-12) * S(diag);
  std::array<int, 3> kinds{0, 0, 0};
  for (int k = 0; k < n; ++k) {
    const RigidTransform<S> P = test::random_pose(rng, Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1)).cast<S>();
    const Vec3<S> q = P.apply(box.center() + (rng.vec(-0.8, 0.8) * diag).cast<S>());
    const auto c = closest_point_on_mesh(bvh, q, P);
    ASSERT_TRUE(c.has_value());
    S best = std::numeric_limits<S>::infinity();
    const Vec3<S> ql = P.inverse().apply(q);
    for (int t = 0; t < m.num_triangles(); ++t) best = std::min(best, (ql - detail::closest_on_triangle(ql, m.triangle(t)).point).norm());
    EXPECT_NEAR(c->distance, best, tol) << k;
    EXPECT_NEAR((q - c->point).norm(), c->distance, tol);
    // the point lies on the reported triangle, at its barycentric weights
    const Triangle<S> tri = m.triangle(c->triangle);
    const Vec3<S> pl = tri.a * c->barycentric[0] + tri.b * c->barycentric[1] + tri.c * c->barycentric[2];
    EXPECT_LE((P.apply(pl) - c->point).norm(), S(10) * tol);
    EXPECT_NEAR(c->normal.norm(), S(1), S(1e-4));
    if (c->feature == TriangleFeature::Face) {
      ++kinds[0];
      EXPECT_NEAR(std::abs(c->normal.dot(P.rotate(tri.normal()))), S(1), S(1e-4));
    } else {
      ++kinds[is_edge(c->feature) ? 1 : 2];
      if (c->distance > tol) {
        EXPECT_NEAR(c->normal.dot((q - c->point) / c->distance), S(1), S(1e-3));
      }
    }
    // a bound below the distance finds nothing; above it finds the same distance
    ClosestPointOptions<S> o;
    o.max_distance = best * S(0.9);
    if (best > tol) {
      EXPECT_FALSE(closest_point_on_mesh(bvh, q, P, o).has_value());
    }
    o.max_distance = best * S(1.1) + tol;
    const auto c2 = closest_point_on_mesh(bvh, q, P, o);
    ASSERT_TRUE(c2.has_value());
    EXPECT_NEAR(c2->distance, best, tol);
  }
  EXPECT_GT(kinds[0], 0);
  EXPECT_GT(kinds[1] + kinds[2], 0);
}

TYPED_TEST(ClosestPointMesh, MatchesBruteForce) {
  using S = typename BvTraits<TypeParam>::Scalar;
  check<TypeParam>(make_icosphere<S>(S(1), 2), 11, 300);
  check<TypeParam>(make_torus<S>(S(1), S(0.3), 24, 12), 12, 300);
  check<TypeParam>(make_random_soup<S>(300, 13, S(1), S(0.2)), 13, 300);
}

TYPED_TEST(ClosestPointMesh, MatchesBruteForceOnSpot) {
  using S = typename BvTraits<TypeParam>::Scalar;
  IMPACT_REQUIRE_DATA(path, "meshes/spot.obj");
  check<TypeParam>(test::read_obj<S>(path), 14, 200);
}

TYPED_TEST(ClosestPointMesh, FeaturesOnABox) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const MeshBvh<TypeParam> box(make_box<S>(Vec3<S>::Ones()));
  auto c = closest_point_on_mesh(box, Vec3<S>(0.2, 0.3, 3));
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->distance, S(2), S(1e-6));
  EXPECT_NEAR(c->normal.z(), S(1), S(1e-6));
  c = closest_point_on_mesh(box, Vec3<S>(3, 3, 3));
  ASSERT_TRUE(c.has_value());
  EXPECT_TRUE(is_vertex(c->feature));
  EXPECT_NEAR(c->normal.dot(Vec3<S>::Ones().normalized()), S(1), S(1e-6));
  c = closest_point_on_mesh(box, Vec3<S>(2, 0.5, 2));
  ASSERT_TRUE(c.has_value());
  EXPECT_TRUE(is_edge(c->feature) || c->feature == TriangleFeature::Face);  // the box's diagonal edges split faces
  EXPECT_NEAR(c->distance, std::sqrt(S(2)), S(1e-6));
  // a point on the surface: distance 0, normal = the face normal
  c = closest_point_on_mesh(box, Vec3<S>(0.25, 0.5, 1));
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->distance, S(0));
  EXPECT_NEAR(std::abs(c->normal.z()), S(1), S(1e-6));
}

// Small integer meshes under query points on a quarter-integer grid (closest points at shared
// vertices and edges, coincident and zero-area triangles, queries on the surface): with a box
// or oriented-box tree the answer's squared distance is exactly the smallest of the loop over every triangle
// (issue 12: nodes at the best distance are pruned, so a node's key must never exceed a triangle's
// computed value, which rounding of the closest point could take below the distance to the
// triangle's box); sphere trees within rounding. Float and double.
template <class S> void check_integer_grid(std::uint64_t seed) {
  test::Rng rng(seed);
  for (int mesh = 0; mesh < 150 / kClosestSamples; ++mesh) {
    TriangleMesh<S> m;
    const int nv = 4 + int(rng.index(8)), nf = 1 + int(rng.index(16));
    m.V.resize(nv, 3);
    m.F.resize(nf, 3);
    for (int i = 0; i < nv; ++i)
      for (int d = 0; d < 3; ++d) m.V(i, d) = S(int(rng.index(7)) - 3) * S(rng.index(2) ? 1 : 3);
    for (int f = 0; f < nf; ++f)
      for (int d = 0; d < 3; ++d) m.F(f, d) = int(rng.index(std::uint64_t(nv)));
    const MeshBvh<Aabb<S>> ab(m);
    const MeshBvh<Sphere<S>> sp(m);
    const MeshBvh<Obb<S>> ob(m);
    for (int k = 0; k < 24; ++k) {
      Vec3<S> q;
      for (int i = 0; i < 3; ++i) q[i] = S(int(rng.index(41)) - 20) / S(4);
      S best = std::numeric_limits<S>::infinity();
      for (int t = 0; t < nf; ++t) {
        const Triangle<S> tri = m.triangle(t);
        const auto tp = detail::closest_on_triangle(q, tri);
        best = std::min(best, detail::triangle_squared_distance(q, tri, tp));
      }
      const auto ca = closest_point_on_mesh(ab, q), cs = closest_point_on_mesh(sp, q), co = closest_point_on_mesh(ob, q);
      ASSERT_TRUE(ca.has_value() && cs.has_value() && co.has_value());
      EXPECT_EQ(ca->distance, std::sqrt(best)) << mesh << "," << k;
      EXPECT_EQ(co->distance, std::sqrt(best)) << mesh << "," << k;
      EXPECT_NEAR(cs->distance, std::sqrt(best), S(64) * std::numeric_limits<S>::epsilon() * S(20)) << mesh << "," << k;
    }
  }
}

TEST(ClosestPointMeshExact, IntegerGridDistanceIsTheLoopMinimum) {
  check_integer_grid<double>(21);
  check_integer_grid<float>(22);
}

// Degenerate soups (test::degenerate_soup: slivers, sizes from 1e-4 to 1, coincident centroids,
// exact copies), every builder: box and oriented-box trees give exactly the loop's smallest
// squared distance, sphere trees to rounding; points around and inside the soup.
template <class S> void check_degenerate_soup_closest(std::uint64_t seed) {
  const TriangleMesh<S> m = test::degenerate_soup<S>(200, seed);
  test::Rng rng(seed + 1);
  for (BuildMethod method : {BuildMethod::TopDown, BuildMethod::BottomUp, BuildMethod::Incremental}) {
    MeshBvhConfig cfg;
    cfg.build.method = method;
    const MeshBvh<Aabb<S>> ab(m, cfg);
    const MeshBvh<Sphere<S>> sp(m, cfg);
    const MeshBvh<Obb<S>> ob(m, cfg);
    for (int k = 0; k < 100 / kClosestSamples; ++k) {
      const Vec3<S> q = k % 4 == 0 ? m.vertex(int(rng.index(std::uint64_t(m.num_vertices())))) : Vec3<S>(rng.vec(-1.5, 1.5).cast<S>());
      S best = std::numeric_limits<S>::infinity();
      for (int t = 0; t < m.num_triangles(); ++t) {
        const Triangle<S> tri = m.triangle(t);
        best = std::min(best, detail::triangle_squared_distance(q, tri, detail::closest_on_triangle(q, tri)));
      }
      const auto ca = closest_point_on_mesh(ab, q), cs = closest_point_on_mesh(sp, q), co = closest_point_on_mesh(ob, q);
      ASSERT_TRUE(ca.has_value() && cs.has_value() && co.has_value());
      EXPECT_EQ(ca->distance, std::sqrt(best)) << k;
      EXPECT_EQ(co->distance, std::sqrt(best)) << k;
      EXPECT_NEAR(cs->distance, std::sqrt(best), S(256) * std::numeric_limits<S>::epsilon() * S(4)) << k;
    }
  }
}

TEST(ClosestPointMeshExact, DegenerateSoupDistanceIsTheLoopMinimum) {
  check_degenerate_soup_closest<double>(41);
  check_degenerate_soup_closest<float>(42);
}

// The work counters count every node key and every triangle tested: one triangle is one node and
// one triangle; two far apart triangles need the root, both children and the nearer triangle only
// (the farther child's key exceeds the distance found). 4,096 copies of one triangle: the tree
// gathers them in one leaf and the query tests one (before issue 12, every copy was tested).
TYPED_TEST(ClosestPointMesh, WorkCounters) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  TriangleMesh<S> one;
  one.V.resize(3, 3);
  one.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  one.F.resize(1, 3);
  one.F << 0, 1, 2;
  ClosestPointStats st;
  ASSERT_TRUE(closest_point_on_mesh(MeshBvh<BV>(one), Vec3<S>(0.2, 0.2, 1), {}, {}, &st).has_value());
  EXPECT_EQ(st.node_tests, 1u);
  EXPECT_EQ(st.triangle_tests, 1u);

  TriangleMesh<S> two;
  two.V.resize(6, 3);
  two.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 10, 0, 0, 11, 0, 0, 10, 1, 0;
  two.F.resize(2, 3);
  two.F << 0, 1, 2, 3, 4, 5;
  MeshBvhConfig leaf1;
  leaf1.build.leaf_size = 1;
  const MeshBvh<BV> t2(two, leaf1);
  ASSERT_EQ(t2.tree().nodes.size(), 3u);
  st = {};
  const auto c = closest_point_on_mesh(t2, Vec3<S>(0.2, 0.2, 1), {}, {}, &st);
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->triangle, 0);
  EXPECT_EQ(st.node_tests, 3u);
  EXPECT_EQ(st.triangle_tests, 1u);
  // the counters add up over queries
  closest_point_on_mesh(t2, Vec3<S>(10.2, 0.2, 1), {}, {}, &st);
  EXPECT_EQ(st.node_tests, 6u);
  EXPECT_EQ(st.triangle_tests, 2u);

  const int copies = 4096;
  const MeshBvh<BV> ts(impact::test::coincident_copies<S>(copies));
  st = {};
  const auto cs = closest_point_on_mesh(ts, Vec3<S>(0.25, 0.25, 1), {}, {}, &st);
  ASSERT_TRUE(cs.has_value());
  EXPECT_EQ(cs->distance, S(1));
  EXPECT_EQ(st.triangle_tests, 1u);
  EXPECT_EQ(st.node_tests, 1u);
  // a tree that does not gather them (bottom-up) relies on pruning: in a box tree, nodes at the
  // distance found are pruned; sphere and oriented-box keys are below the copies' distance (their
  // volumes are grown by rounding bounds), so those trees test every copy
  MeshBvhConfig bottom_up;
  bottom_up.build.method = BuildMethod::BottomUp;
  const MeshBvh<BV> tb(impact::test::coincident_copies<S>(copies), bottom_up);
  st = {};
  ASSERT_TRUE(closest_point_on_mesh(tb, Vec3<S>(0.25, 0.25, 1), {}, {}, &st).has_value());
  if constexpr (std::is_same_v<BV, Aabb<S>>) {
    EXPECT_LE(st.triangle_tests, 8u);
    EXPECT_LE(st.node_tests, 200u);
  } else {
    EXPECT_EQ(st.triangle_tests, std::size_t(copies));
  }
}

}  // namespace
}  // namespace impact
