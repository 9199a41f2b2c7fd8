// SPDX-License-Identifier: MIT
// Coincident copies of a triangle (issue 12): no cut by centroids separates copies, and every node
// holding one has the same key in a nearest-first query, so before, a ray or closest-point query
// on a mesh with many copies visited every copy, in every BV (200,000 tilted copies: 200,000
// triangle tests a ray). The top-down build now gathers the copies of one triangle in one leaf,
// and the queries skip a triangle that repeats the one before it (MeshBvh::repeats_previous).
// Checked here on a torus with thousands of tilted copies of one of its triangles, in three vertex
// orders, plus copies of another triangle with the same centroid: every answer equals a loop over
// all triangles (first hits of rays and swept spheres, any hit, closest points, through the tree,
// a CompactBvh and a WideBvh; all pairs and self pairs against the exact brute force), and the
// triangle tests per query stay a handful. Sphere, box and oriented-box trees, float and double.
#include "impact/bvh/compact_bvh.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/wide_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/kd_tree.hpp"
#include "impact/query/mesh_collide.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "impact/query/swept_sphere_mesh.hpp"
#include "support/brute_force.hpp"
#include "support/loop_oracles.hpp"
#include "support/meshes.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <utility>

namespace impact {
namespace {

/// A torus (1,152 triangles) and `copies` copies of its triangle 100, a third each in the vertex
/// orders (a, b, c), (b, c, a) and (a, c, b), then `copies` / 4 copies of that triangle turned by
/// 90 degrees about its centroid (another shape, the same centroid). Vertices are not shared
/// between copies. The copies are interleaved in the rows of F.
template <class S> TriangleMesh<S> torus_with_copies(int copies) {
  const TriangleMesh<S> torus = make_torus<S>(S(1), S(0.4), 48, 12);
  const Triangle<S> t = torus.triangle(100);
  const Vec3<S> c = t.centroid();
  const Vec3<S> axis = t.normal().normalized();
  const Eigen::Matrix<S, 3, 3> R = Eigen::AngleAxis<S>(S(EIGEN_PI / 2), axis).toRotationMatrix();
  const Triangle<S> turned(Vec3<S>(c + R * (t.a - c)), Vec3<S>(c + R * (t.b - c)), Vec3<S>(c + R * (t.c - c)));
  const int turned_copies = copies / 4, n = torus.num_triangles() + copies + turned_copies;
  TriangleMesh<S> m;
  m.V.resize(torus.V.rows() + 3 * (copies + turned_copies), 3);
  m.F.resize(n, 3);
  m.V.topRows(torus.V.rows()) = torus.V;
  m.F.topRows(torus.F.rows()) = torus.F;
  int v = int(torus.V.rows()), f = torus.num_triangles();
  for (int k = 0; k < copies + turned_copies; ++k, ++f, v += 3) {
    const Triangle<S>& src = k < copies ? t : turned;
    m.V.row(v) = src.a.transpose(), m.V.row(v + 1) = src.b.transpose(), m.V.row(v + 2) = src.c.transpose();
    if (k % 3 == 0) m.F.row(f) << v, v + 1, v + 2;
    if (k % 3 == 1) m.F.row(f) << v + 1, v + 2, v;
    if (k % 3 == 2) m.F.row(f) << v, v + 2, v + 1;
  }
  return m;
}

template <class S> std::optional<S> loop_swept(const TriangleMesh<S>& m, const Ray<S>& ray, S r) {
  std::optional<S> best;
  for (int t = 0; t < m.num_triangles(); ++t) {
    const auto h = detail::swept_sphere_triangle(ray.origin, ray.direction, r, m.triangle(t), ray.t_max);
    if (h && (!best || h->t < *best)) best = h->t;
  }
  return best;
}

template <class T> class CoincidentCopies : public ::testing::Test {};
using CopyBVs = ::testing::Types<Aabb<float>, Aabb<double>, Sphere<float>, Sphere<double>, Obb<float>, Obb<double>>;
TYPED_TEST_SUITE(CoincidentCopies, CopyBVs);

// Rays and points aimed at the copies and around the torus: the answers of the loop, and about as
// many triangle tests as on the torus alone (the copies add one test per vertex order), where
// every copy on the ray's way was tested before.
TYPED_TEST(CoincidentCopies, NearestQueriesTestOneCopyPerVertexOrder) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const int copies = IMPACT_TEST_SANITIZED ? 3000 : 9000;  // 9,000 + 2,250: above the parallel build's 8,192
  const TriangleMesh<S> m = torus_with_copies<S>(copies);
  const Triangle<S> t = m.triangle(100);
  const MeshBvh<BV> alone(make_torus<S>(S(1), S(0.4), 48, 12));
  for (int threads : {1, 2}) {
    MeshBvhConfig cfg;
    cfg.build.threads = threads;
    const MeshBvh<BV> bvh(m, cfg);
    // each group of equal copies (same vertices, same order: the torus's own triangle and the
    // copies in its order, the two other orders, the turned copies' three orders) is one run in
    // a leaf, all but its first triangle marked
    int repeats = 0;
    for (std::int32_t k = 0; k < bvh.num_triangles(); ++k) repeats += bvh.repeats_previous(k);
    EXPECT_EQ(repeats, copies + 1 + copies / 4 - 6) << threads;
    test::Rng rng(7);
    const S eps = std::numeric_limits<S>::epsilon();
    for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 20 : 60); ++i) {
      // a point on the copied triangle, a ray to it from a random point of a ball around it
      const double u = rng.uniform(0.05, 0.9), w = rng.uniform(0.05, 0.95) * (1 - u);
      const Vec3<S> target = t.a + S(u) * (t.b - t.a) + S(w) * (t.c - t.a);
      const Vec3<S> o = (target.template cast<double>() + rng.vec(-1, 1)).template cast<S>();
      const Ray<S> ray(o, Vec3<S>(target - o), S(i % 2 ? 2 : 1e6));
      const auto b = test::loop_first_hit(m, ray);
      RayMeshStats st, st0;
      const auto h = ray_mesh_first_hit(bvh, ray, {}, &st);
      ray_mesh_first_hit(alone, ray, {}, &st0);
      ASSERT_EQ(h.has_value(), b.has_value()) << i;
      EXPECT_EQ(ray_mesh_any_hit(bvh, ray), b.has_value()) << i;
      if (b) {
        if constexpr (std::is_same_v<BV, Sphere<S>>) {  // sphere trees: the first hit to rounding
          EXPECT_NEAR(h->t, b->first, S(1e-4) * (S(1) + b->first)) << i;
        } else {
          EXPECT_EQ(h->t, b->first) << i;
        }
      }
      EXPECT_LE(st.triangle_tests, 2 * st0.triangle_tests + 12) << i;  // before: every copy on the ray's way
      // closest point to a point near the copies
      const Vec3<S> p = (target.template cast<double>() + 0.01 * rng.vec(-1, 1)).template cast<S>();
      ClosestPointStats cs, cs0;
      const auto c = closest_point_on_mesh(bvh, p, {}, {}, &cs);
      closest_point_on_mesh(alone, p, {}, {}, &cs0);
      ASSERT_TRUE(c.has_value());
      const S d = test::loop_distance(m, p);
      if constexpr (std::is_same_v<BV, Sphere<S>>) {
        EXPECT_NEAR(c->distance, d, S(1024) * eps) << i;
      } else {
        EXPECT_EQ(c->distance, d) << i;
      }
      EXPECT_LE(cs.triangle_tests, 2 * cs0.triangle_tests + 12) << i;
      // a swept sphere along the same segment
      const S r = S(0.01);
      const auto sw = swept_sphere_mesh_first_hit(bvh, Ray<S>(o, Vec3<S>(target - o), S(2)), r);
      const auto sl = loop_swept(m, Ray<S>(o, Vec3<S>(target - o), S(2)), r);
      ASSERT_EQ(sw.has_value(), sl.has_value()) << i;
      if (sl) {
        EXPECT_NEAR(sw->t, *sl, S(1e-3) * (S(1) + *sl)) << i;
      }
    }
  }
}

// The casts of the flat trees: a CompactBvh and a WideBvh (both from box trees) give the loop's t
// with about the triangle tests of the torus alone.
template <class S> void check_flat_trees() {
  const TriangleMesh<S> m = torus_with_copies<S>(4000);
  const MeshBvh<Aabb<S>> bvh(m);
  const CompactBvh fast(bvh.tree());
  const WideBvh<S> wide(m), wide_of_tree(bvh);
  const TriangleMesh<S> torus = make_torus<S>(S(1), S(0.4), 48, 12);
  const MeshBvh<Aabb<S>> bvh0(torus);
  const CompactBvh fast0(bvh0.tree());
  const WideBvh<S> wide0(torus), wide_of_tree0(bvh0);
  EXPECT_TRUE(wide.has_repeats());
  EXPECT_FALSE(wide.packed_without_repeats());  // (the 8-wide cast's one-block leaf path skips no repeats)
  EXPECT_EQ(wide0.packed_without_repeats(), wide0.packed());
  const Triangle<S> t = m.triangle(100);
  test::Rng rng(8);
  for (int i = 0; i < 40; ++i) {
    const Vec3<S> target = t.a + S(0.3) * (t.b - t.a) + S(0.3) * (t.c - t.a);
    const Vec3<S> o = (target.template cast<double>() + rng.vec(-1, 1)).template cast<S>();
    const Ray<S> ray(o, Vec3<S>(target - o), S(2));
    const auto b = test::loop_first_hit(m, ray);
    RayMeshStats sc, sw, st, sc0, sw0, st0;  // ...0: the torus alone
    ray_mesh_first_hit(bvh0, fast0, ray, {}, &sc0);
    ray_mesh_first_hit(wide0, ray, RigidTransform<S>(), &sw0);
    ray_mesh_first_hit(wide_of_tree0, ray, RigidTransform<S>(), &st0);
    const auto hc = ray_mesh_first_hit(bvh, fast, ray, {}, &sc);
    const auto hw = ray_mesh_first_hit(wide, ray, RigidTransform<S>(), &sw);
    const auto ht = ray_mesh_first_hit(wide_of_tree, ray, RigidTransform<S>(), &st);
    ASSERT_EQ(hc.has_value(), b.has_value()) << i;
    ASSERT_EQ(hw.has_value(), b.has_value()) << i;
    ASSERT_EQ(ht.has_value(), b.has_value()) << i;
    if (b) {
      EXPECT_EQ(hc->t, b->first) << i;
      EXPECT_EQ(hw->t, b->first) << i;
      EXPECT_EQ(ht->t, b->first) << i;
    }
    EXPECT_LE(sc.triangle_tests, 2 * sc0.triangle_tests + 12) << i;
    EXPECT_LE(sw.triangle_tests, 2 * sw0.triangle_tests + 12) << i;
    EXPECT_LE(st.triangle_tests, 2 * st0.triangle_tests + 12) << i;
  }
}

TEST(CoincidentCopiesFlat, CompactAndWideTreesTestOneCopyPerVertexOrder) {
  check_flat_trees<double>();
  check_flat_trees<float>();
}

// The kd-tree: the copies make one leaf (no plane separates them); its references are sorted by
// vertices and the repeats skipped: the loop's answers with about the torus's own tests.
template <class S> void check_kd_tree() {
  const TriangleMesh<S> m = torus_with_copies<S>(4000);
  const KdTree<S> kd(m), kd0(make_torus<S>(S(1), S(0.4), 48, 12));
  int marked = 0;
  for (std::int32_t k = 0; k < std::int32_t(kd.references().size()); ++k) marked += kd.repeats_previous(k);
  EXPECT_GE(marked, 4000 + 1 + 1000 - 6);  // at least once per copy beyond the first of its group
  const Triangle<S> t = m.triangle(100);
  test::Rng rng(9);
  for (int i = 0; i < 40; ++i) {
    const Vec3<S> target = t.a + S(0.3) * (t.b - t.a) + S(0.3) * (t.c - t.a);
    const Vec3<S> o = (target.template cast<double>() + rng.vec(-1, 1)).template cast<S>();
    const Ray<S> ray(o, Vec3<S>(target - o), S(2));
    const auto b = test::loop_first_hit(m, ray);
    KdTreeStats st, st0;
    const auto h = kd.first_hit(ray, &st);
    kd0.first_hit(ray, &st0);
    ASSERT_EQ(h.has_value(), b.has_value()) << i;
    if (b) {
      EXPECT_EQ(h->t, b->first) << i;
    }
    EXPECT_LE(st.triangle_tests, 2 * st0.triangle_tests + 12) << i;
    const Vec3<S> p = (target.template cast<double>() + 0.01 * rng.vec(-1, 1)).template cast<S>();
    KdTreeStats cs, cs0;
    const auto c = kd.closest_point(p, &cs);
    kd0.closest_point(p, &cs0);
    ASSERT_TRUE(c.has_value());
    EXPECT_EQ(c->distance, test::loop_distance(m, p)) << i;
    EXPECT_LE(cs.triangle_tests, 2 * cs0.triangle_tests + 12) << i;
  }
}

TEST(CoincidentCopiesFlat, KdTreeTestsOneCopyPerVertexOrder) {
  check_kd_tree<double>();
  check_kd_tree<float>();
}

// Queries that list pairs must still list every copy: all pairs against another mesh and self
// pairs, against the exact brute force (copies of a triangle touch each other and its torus
// neighbours). Then the copies are moved apart (set_vertices): nothing is marked any more and the
// answers still match.
TYPED_TEST(CoincidentCopies, PairQueriesListEveryCopy) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  TriangleMesh<S> m = torus_with_copies<S>(40);
  MeshBvh<BV> bvh(m);
  CollideOptions all;
  all.all_pairs = true;
  auto check = [&](const char* what) {
    EXPECT_EQ(test::sorted(self_collide(bvh, all).pairs), test::brute_force_self_pairs(m)) << what;
    const TriangleMesh<S> other = make_torus<S>(S(1), S(0.4), 24, 8);
    const MeshBvh<BV> ob(other);
    const RigidTransform<S> pose(Eigen::AngleAxis<S>(S(0.3), Vec3<S>(1, 0, 0)).toRotationMatrix(), Vec3<S>(S(0.2), S(0.1), S(0)));
    const auto expected = test::brute_force_pairs(m, RigidTransform<S>(), other, pose);
    EXPECT_EQ(test::sorted(collide(bvh, RigidTransform<S>(), ob, pose, all).pairs), expected) << what;
    EXPECT_EQ(collides(bvh, RigidTransform<S>(), ob, pose), !expected.empty()) << what;
  };
  check("copies");
  bool marked = false;
  for (std::int32_t k = 0; k < bvh.num_triangles(); ++k) marked = marked || bvh.repeats_previous(k);
  EXPECT_TRUE(marked);
  // move every copy by its own small offset: no two remain equal
  for (int v = int(make_torus<S>(S(1), S(0.4), 48, 12).V.rows()); v < m.V.rows(); ++v) m.V(v, 2) += S(1e-3) * S(1 + v % 97);
  bvh.set_vertices(m.V);
  for (std::int32_t k = 0; k < bvh.num_triangles(); ++k) EXPECT_FALSE(bvh.repeats_previous(k)) << k;
  check("moved apart");
}

}  // namespace
}  // namespace impact
