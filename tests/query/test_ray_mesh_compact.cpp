// SPDX-License-Identifier: MIT
// CompactBvh: its float boxes contain the source boxes and its leaves hold exactly their
// subtrees' primitives; ray casts through it (from the root, or from a DistanceGrid's start nodes)
// give the first hits of ray casts through the plain tree: the same t, and the same triangle
// except between triangles hit at exactly that t. Torus in float and double with source leaves of
// 1 and 3, collapsed leaves of 1, 4 and 16; the Stanford bunny. The two-sibling slab test gives
// exactly the one-box slab test's entry parameters.
#include "impact/bvh/compact_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/distance_grid.hpp"
#include "impact/query/ray_mesh.hpp"
#include "support/data.hpp"
#include "support/obj_reader.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include "support/sanitizer.hpp"

constexpr int kCompactSamples = IMPACT_TEST_SANITIZED ? 8 : 1;

namespace impact {
namespace {

// Every source node's box lies in the box of the compact node standing for it, and every
// compact leaf's range is the range of one source subtree of at most max(leaf_size, source leaf).
template <class S>
void check_structure(const Bvh<Aabb<S>>& tree, const CompactBvh& c, int leaf_size) {
  ASSERT_EQ(c.num_primitives(), tree.num_primitives());
  for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
    const CompactBvhNode& n = c.node(c.from_source(static_cast<std::int32_t>(i)));
    const Aabb<S>& b = tree.nodes[i].bv;
    for (int k = 0; k < 3; ++k) {
      ASSERT_LE(double(n.lo[k]), double(b.min[k]));
      ASSERT_GE(double(n.hi[k]), double(b.max[k]));
    }
    if (n.is_leaf()) {
      ASSERT_LE(n.count, std::max<std::int32_t>(leaf_size, tree.nodes[i].is_leaf() ? tree.nodes[i].count : 0));
    }
  }
}

template <class S>
void check_hits(const MeshBvh<Aabb<S>>& bvh, const CompactBvh& c, const DistanceGrid<S>* grid, int n, double scale,
                std::uint64_t seed) {
  test::Rng rng(seed);
  int hits = 0, ties = 0;
  for (int i = 0; i < n; ++i) {
    const Triangle<S>& t = bvh.triangle(static_cast<std::int32_t>(rng.index(static_cast<std::uint64_t>(bvh.num_triangles()))));
    const Vec3<S> o = t.centroid() + (rng.vec(-1, 1) * scale).template cast<S>();
    Vec3<S> d = (rng.vec(-1, 1) * (i % 7 == 0 ? 20 * scale : scale)).template cast<S>();
    if (i % 13 == 0) d[i % 3] = S(0);        // rays in a coordinate plane (1 / d infinite on an axis)
    if (i % 17 == 0) d[(i + 1) % 3] = S(0);  // and along a coordinate axis, with the case above
    const Ray<S> ray(o, d, i % 11 == 0 ? std::numeric_limits<S>::infinity() : S(1));
    std::int32_t start = 0;
    if (grid && i % 11 != 0) {
      start = grid->start_node(o, Vec3<S>(o + d));
      if (start == DistanceGrid<S>::kNoTriangle) start = 0;
    }
    const auto plain = ray_mesh_first_hit(bvh, ray);
    const auto fast = ray_mesh_first_hit(bvh, c, ray, RigidTransform<S>(), nullptr, start);
    ASSERT_EQ(plain.has_value(), fast.has_value()) << i;
    if (!plain) continue;
    ++hits;
    EXPECT_EQ(plain->t, fast->t) << i;
    ties += plain->triangle != fast->triangle;
  }
  EXPECT_GT(hits, n / 10);
  EXPECT_LE(ties, n / 50);  // only where the ray meets a shared edge or vertex
}

template <class S>
class CompactBvhTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(CompactBvhTest, Scalars);

TYPED_TEST(CompactBvhTest, TorusSameFirstHits) {
  using S = TypeParam;
  for (int source_leaf : {1, 3}) {
    MeshBvhConfig cfg;
    cfg.build.leaf_size = source_leaf;
    const MeshBvh<Aabb<S>> bvh(make_torus<S>(S(1), S(0.4), 48, 24), cfg);
    DistanceGridConfig<S> gcfg;
    gcfg.resolution = 24;
    const DistanceGrid<S> grid(bvh, gcfg);
    for (int leaf : {1, 4, 16}) {
      const CompactBvh c(bvh.tree(), leaf);
      check_structure(bvh.tree(), c, leaf);
      check_hits(bvh, c, &grid, 3000 / kCompactSamples, 0.05, 21 + std::uint64_t(leaf));
    }
  }
}

// Both siblings' entry parameters at once (SSE2 for double) are exactly ray_box_entry's on each
// float box, for rays from every octant, boxes in front of, around and behind the origin, and
// bounds that cut the ray short.
TYPED_TEST(CompactBvhTest, PairSlabIsTheSlabTest) {
  using S = TypeParam;
  test::Rng rng(41);
  int hits = 0, misses = 0;
  for (int i = 0; i < 20000 / kCompactSamples; ++i) {
    const Vec3<S> o = rng.vec(-1, 1).template cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * 3.0).template cast<S>();
    const Vec3<S> inv = detail::safe_inverse(d);
    CompactBvhPair p;
    for (int side = 0; side < 2; ++side) {
      const Eigen::Vector3d c = rng.vec(-1.5, 1.5), h = rng.vec(0.1, 0.8);
      CompactBvhNode n;
      for (int k = 0; k < 3; ++k) n.lo[k] = float(c[k] - h[k]), n.hi[k] = float(c[k] + h[k]);
      p.set(side, n);
    }
    const S t_max = i % 3 == 0 ? std::numeric_limits<S>::infinity() : S(rng.uniform() * 2);
    S keys[2];
    detail::PairSlab<S>(o, inv).keys(p, t_max, keys);
    for (int side = 0; side < 2; ++side) {
      const auto t = detail::ray_box_entry(o, inv, Aabb<S>(p.child(side).box().template cast<S>()), t_max);
      if (t) {
        ++hits;
        EXPECT_EQ(keys[side], *t) << i << " " << side;
      } else {
        ++misses;
        EXPECT_TRUE(std::isnan(keys[side])) << i << " " << side;
      }
    }
  }
  EXPECT_GT(hits, 1000 / kCompactSamples);
  EXPECT_GT(misses, 1000 / kCompactSamples);
}

TEST(CompactBvh, BunnySameFirstHits) {
  IMPACT_REQUIRE_DATA(bunny, "meshes/stanford-bunny.obj");
  const MeshBvh<Aabb<double>> bvh(test::read_obj<double>(bunny));
  DistanceGridConfig<double> gcfg;
  gcfg.resolution = IMPACT_TEST_SANITIZED ? 12 : 32;
  const DistanceGrid<double> grid(bvh, gcfg);
  const CompactBvh c(bvh.tree(), 4);
  check_structure(bvh.tree(), c, 4);
  EXPECT_LT(c.memory_bytes(), 2u << 20);  // the point: it fits in a core's L2 cache
  check_hits(bvh, c, &grid, 20000 / kCompactSamples, 0.003, 31);
}

}  // namespace
}  // namespace impact
