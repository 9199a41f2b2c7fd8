// SPDX-License-Identifier: MIT
// The kd-tree over triangles (query/kd_tree.hpp): ray and segment first hits against brute force
// over all triangles (the library's triangle rule, detail::ray_mesh_triangle_hit, no tree) and the
// AABB tree's cast, closest points against brute force; float and double; random soups, a closed
// mesh hit through its vertices and edges, axis-aligned rays along splitting planes, and
// degenerate meshes (coincident triangles, slivers, very unequal sizes, a flat grid) with bounded
// depth and references; bad input throws.
#include "impact/query/kd_tree.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"
#include "support/loop_oracles.hpp"
#include "support/meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace impact;
using namespace impact::test;

namespace {

/// Casts rays and compares with brute force; returns the number of hits.
template <class S> int expect_rays_match(const KdTree<S>& kd, const TriangleMesh<S>& m, const std::vector<Ray<S>>& rays) {
  int hits = 0;
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const auto b = loop_first_hit(m, rays[k]);
    const auto h = kd.first_hit(rays[k]);
    if (!b) {
      EXPECT_FALSE(h.has_value()) << "ray " << k << " t " << h->t;
      continue;
    }
    ++hits;
    const S expected = b->first;
    if (!h) {
      ADD_FAILURE() << "ray " << k << " missed, brute force hit at " << expected;
      continue;
    }
    EXPECT_EQ(h->t, expected) << "ray " << k;
    // the reported triangle is hit at that t
    const auto th = detail::ray_mesh_triangle_hit(PreparedRay<S>(rays[k]), m.triangle(h->triangle));
    EXPECT_TRUE(th && th->t == h->t) << "ray " << k;
  }
  return hits;
}

template <class S> std::vector<Ray<S>> random_rays(Rng& rng, int n, double spread, bool segments) {
  std::vector<Ray<S>> rays;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d o = rng.vec(-spread, spread);
    const Eigen::Vector3d target = rng.vec(-1, 1);
    if (segments)
      rays.emplace_back(o.cast<S>(), (target - o).cast<S>(), S(1));  // segment o -> target
    else
      rays.emplace_back(o.cast<S>(), (target - o).normalized().cast<S>(), std::numeric_limits<S>::infinity());
  }
  return rays;
}

}  // namespace

template <class S> class KdTreeTest : public ::testing::Test {};
using KdTreeScalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(KdTreeTest, KdTreeScalars);

TYPED_TEST(KdTreeTest, RaysAndSegmentsMatchBruteForce) {
  using S = TypeParam;
  const auto m = random_soup<S>(600, 71, 1.0, 0.15);
  const KdTree<S> kd(m);
  EXPECT_GT(kd.nodes().size(), 50u);  // it does split
  Rng rng(3);
  const auto rays = random_rays<S>(rng, 300, 2.5, false);
  const auto segs = random_rays<S>(rng, 300, 1.5, true);
  EXPECT_GT(expect_rays_match(kd, m, rays), 100);
  const int seg_hits = expect_rays_match(kd, m, segs);
  EXPECT_GT(seg_hits, 50);
  EXPECT_LT(seg_hits, 300);  // segments end before some triangles
  // the same t as the AABB tree's cast
  const MeshBvh<Aabb<S>> bvh(m);
  for (const auto& r : rays) {
    const auto a = kd.first_hit(r);
    const auto b = ray_mesh_first_hit(bvh, r);
    ASSERT_EQ(a.has_value(), b.has_value());
    if (a) {
      EXPECT_EQ(a->t, b->t);
    }
  }
}

// A closed mesh hit exactly through its vertices and edge midpoints (watertight: never a miss),
// and axis-aligned rays (zero direction components) starting on splitting planes.
TYPED_TEST(KdTreeTest, WatertightThroughVerticesEdgesAndPlanes) {
  using S = TypeParam;
  const auto m = make_icosphere<S>(S(1), 3);
  const KdTree<S> kd(m);
  std::vector<Ray<S>> rays;
  for (int f = 0; f < m.num_triangles(); f += 3) {
    const Triangle<S> t = m.triangle(f);
    for (const Vec3<S>& target : {t.a, Vec3<S>((t.a + t.b) / S(2))}) {
      const Vec3<S> o = target * S(3);
      rays.emplace_back(o, target - o, std::numeric_limits<S>::infinity());
    }
  }
  for (const auto& r : rays) EXPECT_TRUE(kd.first_hit(r).has_value());
  expect_rays_match(kd, m, rays);
  // axis-aligned rays from the splitting planes of the first few inner nodes
  std::vector<Ray<S>> aligned;
  Rng rng(5);
  for (const auto& n : kd.nodes()) {
    if (n.is_leaf() || aligned.size() >= 60) continue;
    Vec3<S> o = rng.vec(-0.8, 0.8).cast<S>();
    o[n.axis] = n.split;
    Vec3<S> d = Vec3<S>::Zero();
    d[(n.axis + 1) % 3] = S(1);  // parallel to the plane, in it
    aligned.emplace_back(o, d, std::numeric_limits<S>::infinity());
    Vec3<S> d2 = Vec3<S>::Zero();
    d2[n.axis] = S(-1);  // across the plane
    aligned.emplace_back(o, d2, std::numeric_limits<S>::infinity());
  }
  EXPECT_GT(expect_rays_match(kd, m, aligned), 40);
}

TYPED_TEST(KdTreeTest, ClosestPointMatchesBruteForce) {
  using S = TypeParam;
  const auto m = random_soup<S>(500, 72, 1.0, 0.2);
  const KdTree<S> kd(m);
  Rng rng(9);
  for (int k = 0; k < 200; ++k) {
    const Vec3<S> p = rng.vec(-1.5, 1.5).template cast<S>();
    const auto c = kd.closest_point(p);
    ASSERT_TRUE(c.has_value());
    EXPECT_EQ(c->distance, loop_distance(m, p)) << "point " << k;
    EXPECT_EQ((closest_point_on_triangle(p, m.triangle(c->triangle)).point - c->point).norm(), S(0));
  }
  // max_distance: nothing beyond it
  EXPECT_FALSE(kd.closest_point(Vec3<S>(S(10), S(0), S(0)), nullptr, S(1)).has_value());
}

// Degenerate meshes: coincident triangles make one leaf (no deep chain), slivers and very unequal
// sizes and a flat grid (zero extent on one axis) build within the depth and memory bounds, and
// every query still matches brute force.
TYPED_TEST(KdTreeTest, DegenerateMeshesStayBoundedAndCorrect) {
  using S = TypeParam;
  TriangleMesh<S> same;
  same.V.resize(3, 3);
  same.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  same.F.resize(300, 3);
  for (int t = 0; t < 300; ++t) same.F.row(t) << 0, 1, 2;
  const KdTree<S> kd_same(same);
  EXPECT_LE(kd_same.references().size(), 300u * 8 + 64);
  EXPECT_LE(kd_same.depth(), 2);
  const Ray<S> down(Vec3<S>(S(0.2), S(0.2), S(1)), Vec3<S>(0, 0, -1), std::numeric_limits<S>::infinity());
  ASSERT_TRUE(kd_same.first_hit(down).has_value());
  EXPECT_EQ(kd_same.first_hit(down)->t, S(1));

  Rng rng(11);
  TriangleMesh<S> mixed;
  const int n = 500;
  mixed.V.resize(3 * n, 3);
  mixed.F.resize(n, 3);
  for (int t = 0; t < n; ++t) {
    const Eigen::Vector3d c = rng.vec(-1, 1);
    Eigen::Vector3d e0, e1;
    if (t % 3 == 0) {  // long slivers across the whole box: they overlap many cells
      e0 = rng.vec(-2, 2);
      e1 = 0.5 * e0 + Eigen::Vector3d(0, 1e-6, 0);
    } else {
      const double size = std::pow(10.0, rng.uniform(-4, 0));
      e0 = rng.vec(-size, size);
      e1 = rng.vec(-size, size);
    }
    mixed.V.row(3 * t) = c.cast<S>().transpose();
    mixed.V.row(3 * t + 1) = (c + e0).cast<S>().transpose();
    mixed.V.row(3 * t + 2) = (c + e1).cast<S>().transpose();
    mixed.F.row(t) << 3 * t, 3 * t + 1, 3 * t + 2;
  }
  KdTreeConfig tight;
  tight.max_references_per_triangle = 2.0;
  for (const KdTreeConfig& cfg : {KdTreeConfig{}, tight}) {
    const KdTree<S> kd(mixed, cfg);
    EXPECT_LE(double(kd.references().size()), cfg.max_references_per_triangle * n + 64 + 2.0 * n);  // the last split may overshoot by one cell's worth
    EXPECT_LE(kd.depth(), int(8 + 1.3 * std::log2(double(n))));
    expect_rays_match(kd, mixed, random_rays<S>(rng, 150, 2.0, false));
    for (int k = 0; k < 50; ++k) {
      const Vec3<S> p = rng.vec(-1.2, 1.2).template cast<S>();
      EXPECT_EQ(kd.closest_point(p)->distance, loop_distance(mixed, p));
    }
  }

  const auto grid = make_grid<S>(20, 20, S(2));  // flat: zero extent along z
  const KdTree<S> kd_grid(grid);
  std::vector<Ray<S>> rays = random_rays<S>(rng, 100, 2.0, false);
  for (int k = 0; k <= 20; ++k) {  // inside the plane (they miss: parallel), and straight down through the grid's vertices
    rays.emplace_back(Vec3<S>(S(-2), S(-1) + S(k) / S(10), S(0)), Vec3<S>(1, 0, 0), std::numeric_limits<S>::infinity());
    rays.emplace_back(Vec3<S>(S(-1) + S(k) / S(10), S(-1) + S(k) / S(10), S(1)), Vec3<S>(0, 0, -1), std::numeric_limits<S>::infinity());
  }
  EXPECT_GE(expect_rays_match(kd_grid, grid, rays), 21);
}

TEST(KdTreeInput, BadInputThrows) {
  const auto m = random_soup<double>(20, 81);
  KdTreeConfig bad;
  bad.bins = 1;
  EXPECT_THROW(KdTree<double>(m, bad), InvalidInput);
  bad = KdTreeConfig{};
  bad.intersection_cost = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(KdTree<double>(m, bad), InvalidInput);
  bad = KdTreeConfig{};
  bad.max_depth = 65;
  EXPECT_THROW(KdTree<double>(m, bad), InvalidInput);
  bad = KdTreeConfig{};
  bad.max_references_per_triangle = 0.5;
  EXPECT_THROW(KdTree<double>(m, bad), InvalidInput);
  TriangleMesh<double> nan = m;
  nan.V(3, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(KdTree<double>{nan}, InvalidInput);
  TriangleMesh<double> out = m;
  out.F(2, 2) = 1000;
  EXPECT_THROW(KdTree<double>{out}, InvalidInput);
  const KdTree<double> kd(m);
  EXPECT_THROW(kd.first_hit(Ray<double>(Vec3<double>(0, 0, std::nan("")), Vec3<double>(1, 0, 0))), InvalidInput);
  EXPECT_THROW(kd.first_hit(Ray<double>(Vec3<double>(0, 0, 0), Vec3<double>(0, 0, 0))), InvalidInput);
  EXPECT_THROW(kd.closest_point(Vec3<double>(std::numeric_limits<double>::infinity(), 0, 0)), InvalidInput);
  EXPECT_THROW(kd.closest_point(Vec3<double>(0, 0, 0), nullptr, -1.0), InvalidInput);
}
