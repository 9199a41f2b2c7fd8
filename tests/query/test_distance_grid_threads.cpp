// SPDX-License-Identifier: MIT
// DistanceGrid built on several threads (DistanceGridConfig::threads; label "concurrency", also run
// under ThreadSanitizer): the same grid as the serial build for 2, 3 and 8 threads, judged by
// every answer it gives (lower_bound at every cell centre and at random points, start_node on
// random short segments), which must be equal bit for bit.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/distance_grid.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace {

using namespace impact;

template <class S>
class DistanceGridThreads : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(DistanceGridThreads, Scalars);

TYPED_TEST(DistanceGridThreads, SameGridForEveryThreadCount) {
  using S = TypeParam;
  const MeshBvh<Aabb<S>> torus(make_torus<S>(S(1), S(0.4), 48, 24));
  DistanceGridConfig<S> cfg;
  cfg.resolution = 24;
  cfg.threads = 1;
  const DistanceGrid<S> ref(torus, cfg);
  test::Rng rng(4);
  std::vector<Vec3<S>> points, ends;
  for (int i = 0; i < 4000; ++i) {
    points.push_back(rng.in_box(Eigen::Vector3d(-1.6, -1.6, -0.6), Eigen::Vector3d(1.6, 1.6, 0.6)).template cast<S>());
    ends.push_back(points.back() + (rng.vec(-0.08, 0.08)).template cast<S>());
  }
  // a grid-aligned lattice too (cell centres of a 24-cell grid over the box are near these)
  for (int x = 0; x < 30; ++x)
    for (int y = 0; y < 30; ++y)
      for (int z = 0; z < 12; ++z) {
        points.push_back(Vec3<S>(S(-1.5 + 0.1 * x), S(-1.5 + 0.1 * y), S(-0.55 + 0.1 * z)));
        ends.push_back(points.back() + Vec3<S>(S(0.03), S(-0.02), S(0.01)));
      }
  std::size_t positive = 0, culled = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    positive += ref.lower_bound(points[i]) > S(0);
    culled += ref.start_node(points[i], ends[i]) == DistanceGrid<S>::kNoTriangle;
  }
  ASSERT_GT(positive, points.size() / 4);  // the answers compared below are not all trivial
  ASSERT_GT(culled, 10u);
  for (const int threads : {2, 3, 8}) {
    cfg.threads = threads;
    const DistanceGrid<S> g(torus, cfg);
    EXPECT_EQ(g.memory_bytes(), ref.memory_bytes());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const S a = g.lower_bound(points[i]), b = ref.lower_bound(points[i]);
      differ += std::memcmp(&a, &b, sizeof(S)) != 0;
      differ += g.start_node(points[i], ends[i]) != ref.start_node(points[i], ends[i]);
    }
    EXPECT_EQ(differ, 0u) << threads << " threads";
  }
}

}  // namespace
