// SPDX-License-Identifier: MIT
// DistanceGrid: its lower bounds never exceed the closest-point distance (inside the grid, outside
// it, on the surface), are at least the distance to the mesh's box outside it and are within a
// cell of it inside; segments it rules out hit nothing; ray casts started from its start nodes give
// exactly the first hits of ray casts from the root, on a generated torus (float and double, box
// and sphere trees) and on the Stanford bunny.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/distance_grid.hpp"
#include "impact/query/ray_mesh.hpp"
#include "support/data.hpp"
#include "support/obj_reader.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

constexpr int kGridSamples = IMPACT_TEST_SANITIZED ? 8 : 1;

namespace impact {
namespace {

// `cap`: the build's max_distance.
template <class BV>
void check_bounds(const MeshBvh<BV>& bvh, const DistanceGrid<typename BvTraits<BV>::Scalar>& grid, int n, std::uint64_t seed,
                  double cap = 1e300) {
  using S = typename BvTraits<BV>::Scalar;
  Aabb<S> box;
  for (Eigen::Index i = 0; i < bvh.mesh().V.rows(); ++i) box.extend(Vec3<S>(bvh.mesh().V.row(i).transpose()));
  const Eigen::Vector3d c = box.center().template cast<double>(), e = box.extent().template cast<double>();
  test::Rng rng(seed);
  const double cell_diag = std::sqrt(3.0) * double(grid.cell_size());
  int useful = 0;
  for (int i = 0; i < n; ++i) {
    Vec3<S> p;
    if (i % 4 == 0) {  // on the surface
      const Triangle<S>& t = bvh.triangle(static_cast<std::int32_t>(rng.index(static_cast<std::uint64_t>(bvh.num_triangles()))));
      const double u = rng.uniform(), v = rng.uniform() * (1 - u);
      p = t.a + S(u) * (t.b - t.a) + S(v) * (t.c - t.a);
    } else {  // in and around the box, up to 0.8 of its size beyond it
      p = rng.in_box(c - 1.3 * e, c + 1.3 * e).template cast<S>();
    }
    const auto cp = closest_point_on_mesh(bvh, p);
    ASSERT_TRUE(cp.has_value());
    const S lb = grid.lower_bound(p);
    ASSERT_GE(lb, S(0));
    ASSERT_LE(lb, cp->distance) << "point " << p.transpose() << " distance " << cp->distance;
    const bool inside = ((p - box.min).array() >= S(0)).all() && ((box.max - p).array() >= S(0)).all();
    if (!inside) {  // at least the distance to the mesh's box
      const Eigen::Vector3d q =
          p.template cast<double>().cwiseMax(box.min.template cast<double>()).cwiseMin(box.max.template cast<double>());
      EXPECT_GE(double(lb), (p.template cast<double>() - q).norm() * (1 - 1e-5)) << "point " << p.transpose();
    }
    if (inside) {
      EXPECT_GE(double(lb), std::min(double(cp->distance), cap) - cell_diag - 1e-4 * e.norm());
      useful += lb > S(0);
    }
  }
  EXPECT_GT(useful, 0);
}

// Short segments near the surface (the particle case) and some longer ones: a cast from the start
// node has the same result as a cast from the root (same t, same triangle), and kNoTriangle is only
// given for segments that hit nothing.
template <class BV>
void check_start_nodes(const MeshBvh<BV>& bvh, const DistanceGrid<typename BvTraits<BV>::Scalar>& grid, int n,
                       std::uint64_t seed) {
  using S = typename BvTraits<BV>::Scalar;
  test::Rng rng(seed);
  const double h = double(grid.cell_size());
  int deep = 0, none = 0, hits = 0;
  for (int i = 0; i < n; ++i) {
    const Triangle<S>& t = bvh.triangle(static_cast<std::int32_t>(rng.index(static_cast<std::uint64_t>(bvh.num_triangles()))));
    const Vec3<S> o = t.centroid() + (rng.vec(-1, 1) * (i % 3 == 0 ? 3 * h : h)).template cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * (i % 5 == 0 ? 4 * h : 1.2 * h)).template cast<S>();
    const Ray<S> ray(o, d, S(1));
    const std::int32_t start = grid.start_node(o, Vec3<S>(o + d));
    const auto plain = ray_mesh_first_hit(bvh, ray);
    hits += plain.has_value();
    if (start == DistanceGrid<S>::kNoTriangle) {
      ++none;
      EXPECT_FALSE(plain.has_value()) << i;
      continue;
    }
    deep += start > 0;
    const auto fast = ray_mesh_first_hit(bvh, ray, RigidTransform<S>(), nullptr, start);
    ASSERT_EQ(plain.has_value(), fast.has_value()) << i;
    if (plain) {
      EXPECT_EQ(plain->t, fast->t) << i;
      EXPECT_EQ(plain->triangle, fast->triangle) << i;
    }
  }
  EXPECT_GT(deep, n / 3);  // the test exercises deep starts
  EXPECT_GT(hits, n / 20);
  EXPECT_GT(none, n / 50);  // and segments ruled out (beside a cell's slab, or away from the mesh)
}

template <class BV>
class DistanceGridTest : public ::testing::Test {};
using GridBVs = ::testing::Types<Aabb<float>, Aabb<double>, Sphere<double>>;
TYPED_TEST_SUITE(DistanceGridTest, GridBVs);

TYPED_TEST(DistanceGridTest, TorusBoundsAndStartNodes) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const MeshBvh<TypeParam> bvh(make_torus<S>(S(1), S(0.4), 48, 24));
  DistanceGridConfig<S> cfg;
  cfg.resolution = 24;
  const DistanceGrid<S> grid(bvh, cfg);
  EXPECT_EQ(grid.sampled_triangles(), bvh.num_triangles());  // no copies: the mesh itself
  check_bounds(bvh, grid, 4000 / kGridSamples, 11);
  check_start_nodes(bvh, grid, 4000 / kGridSamples, 12);
}

// Coincident triangles (issue 12): every triangle of a small torus 48 times, a third of the copies
// with their vertices rotated. The build samples one copy of each (a tree of 72 triangles, not
// 3,456; before, 20,000 copies of one triangle took 11 s at resolution 8, no tree pruning the equal
// nodes), and its bounds and start nodes hold for the whole mesh: bounds below every
// closest-point distance, casts from the start nodes (nodes of the mesh's own tree, which must hold
// every copy) equal to casts from the root.
TYPED_TEST(DistanceGridTest, CoincidentCopiesAreSampledOnce) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const TriangleMesh<S> torus = make_torus<S>(S(1), S(0.4), 12, 6);
  const int copies = 48, m = int(torus.F.rows());
  TriangleMesh<S> mesh;
  mesh.V = torus.V;
  mesh.F.resize(m * copies, 3);
  for (int c = 0; c < copies; ++c)
    for (int k = 0; k < m; ++k) {
      const Eigen::Index row = Eigen::Index(c) * m + k;
      if (c % 3 == 2)
        mesh.F.row(row) << torus.F(k, 1), torus.F(k, 2), torus.F(k, 0);
      else
        mesh.F.row(row) = torus.F.row(k);
    }
  const MeshBvh<TypeParam> bvh(mesh);
  DistanceGridConfig<S> cfg;
  cfg.resolution = 16;
  const DistanceGrid<S> grid(bvh, cfg);
  EXPECT_EQ(grid.sampled_triangles(), m);
  check_bounds(bvh, grid, 2000 / kGridSamples, 13);
  check_start_nodes(bvh, grid, 2000 / kGridSamples, 14);
}

TEST(DistanceGrid, CappedBuildStaysConservative) {
  const MeshBvh<Aabb<double>> bvh(make_torus<double>(1.0, 0.4, 32, 16));
  DistanceGridConfig<double> cfg;
  cfg.resolution = 16;
  cfg.max_distance = 0.1;
  cfg.start_node_reach = 0;
  const DistanceGrid<double> grid(bvh, cfg);
  check_bounds(bvh, grid, 2000 / kGridSamples, 13, 0.1);
  EXPECT_EQ(grid.start_node(Vec3<double>(0, 0, 0), Vec3<double>(0.01, 0, 0)), 0);  // off: the root
}

// A segment beside a flat patch, on either side, is ruled out by the cell's slab; one in the
// surface, within rounding of it or crossing it is not, and the cast from its start node finds the
// crossing.
TYPED_TEST(DistanceGridTest, SlabRulesOutSegmentsBesideAFlatPatch) {
  using S = typename BvTraits<TypeParam>::Scalar;
  const MeshBvh<TypeParam> bvh(make_grid<S>(32, 32, S(2)));  // z = 0, x and y in [-1, 1]
  DistanceGridConfig<S> cfg;
  cfg.resolution = 16;
  const DistanceGrid<S> grid(bvh, cfg);
  const S eps = std::numeric_limits<S>::epsilon();
  auto along_top = [&](S dz) { return std::make_pair(Vec3<S>(S(-0.05), S(0.01), dz), Vec3<S>(S(0.05), S(0.03), dz)); };
  for (const S dz : {S(1e-3), S(-1e-3), S(0.1)}) {
    const auto [o, e] = along_top(dz);
    EXPECT_EQ(grid.start_node(o, e), DistanceGrid<S>::kNoTriangle) << dz;
    EXPECT_FALSE(ray_mesh_first_hit(bvh, Ray<S>(o, e - o, S(1))).has_value()) << dz;
  }
  for (const S dz : {S(0), S(1e-3) * eps, -S(1e-3) * eps}) {
    const auto [o, e] = along_top(dz);
    EXPECT_NE(grid.start_node(o, e), DistanceGrid<S>::kNoTriangle) << dz;
  }
  const Vec3<S> o(S(0.01), S(0.02), S(0.05)), e(S(-0.01), S(0), S(-0.05));
  const std::int32_t start = grid.start_node(o, e);
  ASSERT_NE(start, DistanceGrid<S>::kNoTriangle);
  const auto hit = ray_mesh_first_hit(bvh, Ray<S>(o, e - o, S(1)), RigidTransform<S>(), nullptr, start);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(double(hit->t), 0.5, 1e-5);
  // far from the mesh's box, nothing can be met, and the bound is the distance to the box
  EXPECT_EQ(grid.start_node(Vec3<S>(5, 0, 0), Vec3<S>(5, 0.1, 0)), DistanceGrid<S>::kNoTriangle);
  EXPECT_NEAR(double(grid.lower_bound(Vec3<S>(5, 0, 0))), 4.0, 1e-4);
}

TEST(DistanceGrid, BunnyBoundsAndStartNodes) {
  IMPACT_REQUIRE_DATA(bunny, "meshes/stanford-bunny.obj");
  const MeshBvh<Aabb<double>> bvh(test::read_obj<double>(bunny));
  DistanceGridConfig<double> cfg;
  cfg.resolution = IMPACT_TEST_SANITIZED ? 12 : 32;
  const DistanceGrid<double> grid(bvh, cfg);
  check_bounds(bvh, grid, 4000 / kGridSamples, 14);
  check_start_nodes(bvh, grid, 20000 / kGridSamples, 15);
}

}  // namespace
}  // namespace impact
