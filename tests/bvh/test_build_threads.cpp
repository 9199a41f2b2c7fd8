// SPDX-License-Identifier: MIT
// The parallel top-down build (BuildConfig::threads): the tree is the same, node for node and bit
// for bit, for one, two and three threads, for each split rule and two leaf sizes, each bounding
// volume, float and double, on an uneven soup, a sphere and a mesh whose centroids all coincide.
// Also through MeshBvh, whose fitter keeps scratch memory (each parallel task owns a copy).
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/meshes.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <memory>

using namespace impact;

namespace {

template <class BV> void expect_same_tree(const Bvh<BV>& a, const Bvh<BV>& b, const std::string& what) {
  ASSERT_EQ(a.nodes.size(), b.nodes.size()) << what;
  ASSERT_EQ(a.primitives, b.primitives) << what;
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    const auto &x = a.nodes[i], &y = b.nodes[i];
    differing += x.first != y.first || x.count != y.count || std::memcmp(&x.bv, &y.bv, sizeof(BV)) != 0;
  }
  EXPECT_EQ(differing, 0u) << what << ": nodes differ from the one-thread build";
}

/// Builds `mesh` with each config on one thread and on 2 and 3, and compares the trees.
template <class BV>
void check_thread_counts(const TriangleMesh<typename BvTraits<BV>::Scalar>& mesh, const std::string& name,
                         const std::vector<std::pair<SplitRule, int>>& configs) {
  for (const auto& [split, leaf] : configs) {
    MeshBvhConfig cfg;
    cfg.build.split = split;
    cfg.build.leaf_size = leaf;
    cfg.build.threads = 1;
    const MeshBvh<BV> serial(mesh, cfg);
    // every triangle in exactly one leaf (the serial build is checked in depth in test_bvh.cpp)
    std::vector<int> seen(static_cast<std::size_t>(mesh.F.rows()), 0);
    for (std::int32_t k = 0; k < serial.num_triangles(); ++k) ++seen[static_cast<std::size_t>(serial.triangle_id(k))];
    ASSERT_EQ(std::count(seen.begin(), seen.end(), 1), mesh.F.rows()) << name;
    for (int threads : {2, 3}) {
      cfg.build.threads = threads;
      const MeshBvh<BV> parallel(mesh, cfg);
      const std::string what = name + ", split " + std::to_string(static_cast<int>(split)) + ", leaf " + std::to_string(leaf) +
                               ", threads " + std::to_string(threads);
      expect_same_tree(serial.tree(), parallel.tree(), what);
      for (std::int32_t k = 0; k < serial.num_triangles(); ++k) ASSERT_EQ(serial.triangle_id(k), parallel.triangle_id(k)) << what;
    }
  }
}

// The cuts do not depend on the bounding volume, only the fits do: every split rule with the
// AABB, the default split with the others.
template <class BV> void check_meshes(bool every_rule) {
  using S = typename BvTraits<BV>::Scalar;
  // uneven sizes and a cluster: the subtrees handed to the threads differ widely in size
  TriangleMesh<S> soup = make_random_soup<S>(9000, 7, S(1), S(0.05));
  soup.V.topRows(3 * 3000) *= S(0.01);
  if (every_rule) {
    check_thread_counts<BV>(soup, "soup",
                            {{SplitRule::SpatialMiddle, 1}, {SplitRule::CentroidMedian, 1}, {SplitRule::Sah, 1}, {SplitRule::SpatialMiddle, 4}});
    check_thread_counts<BV>(make_uv_sphere<S>(S(2), 96, 48), "sphere", {{SplitRule::SpatialMiddle, 1}});
  } else {
    check_thread_counts<BV>(soup, "soup", {{SplitRule::SpatialMiddle, 1}});
  }
  check_thread_counts<BV>(test::coincident_copies<S>(8500), "coincident", {{SplitRule::SpatialMiddle, 1}});
}

TEST(BuildThreads, SameTreeForEveryThreadCountAabbDouble) { check_meshes<Aabb<double>>(true); }
TEST(BuildThreads, SameTreeForEveryThreadCountSphereFloat) { check_meshes<Sphere<float>>(false); }
TEST(BuildThreads, SameTreeForEveryThreadCountObbDouble) { check_meshes<Obb<double>>(false); }

/// An AABB fit that counts the copies made of it: the parallel build copies the fit once per
/// subtree it hands out, the serial one never.
struct CountingFit {
  const TriangleMesh<double>* mesh;
  std::shared_ptr<std::atomic<int>> copies;
  CountingFit(const TriangleMesh<double>* m, std::shared_ptr<std::atomic<int>> c) : mesh(m), copies(std::move(c)) {}
  CountingFit(const CountingFit& o) : mesh(o.mesh), copies(o.copies) { ++*copies; }
  Aabb<double> operator()(const std::int32_t* ids, std::size_t n) const {
    Aabb<double> b;
    for (std::size_t i = 0; i < n; ++i) {
      const Triangle<double> t = mesh->triangle(ids[i]);
      b.extend(t.a), b.extend(t.b), b.extend(t.c);
    }
    return b;
  }
};

// The comparisons above would pass if the parallel path never ran: it must hand out subtrees
// (about 8 a thread) above 8,192 primitives and none below or on one thread.
TEST(BuildThreads, ParallelPathHandsOutSubtrees) {
  const auto check = [](int n, int threads) {
    const TriangleMesh<double> m = make_random_soup<double>(n, 3);
    std::vector<Vec3<double>> centroids(static_cast<std::size_t>(n));
    for (int t = 0; t < n; ++t) centroids[static_cast<std::size_t>(t)] = m.triangle(t).centroid();
    BuildConfig cfg;
    cfg.threads = threads;
    auto copies = std::make_shared<std::atomic<int>>(0);
    const Bvh<Aabb<double>> tree = build_top_down<Aabb<double>>(centroids, CountingFit(&m, copies), cfg);
    EXPECT_EQ(tree.nodes.size(), std::size_t(2 * n - 1));
    return copies->load();
  };
  EXPECT_EQ(check(9000, 1), 0);
  EXPECT_EQ(check(5000, 2), 0);
  EXPECT_GE(check(9000, 2), 8);
  EXPECT_GE(check(9000, 3), 12);
}

}  // namespace
