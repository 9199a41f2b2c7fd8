// SPDX-License-Identifier: MIT
// The 8-wide WideBvh (WideBvh<S, 8>, WideBvhNode8) and its casts: the structure, and the casts
// against brute force over all triangles in float and double (random rays, axis-parallel and
// infinite ones, rays through vertices and edge points of closed meshes, degenerate meshes, a tree
// deeper than the fixed stack, a rigid pose), with the three node-test paths compared on every
// ray: AVX (eight boxes at once, when the CPU has it), SSE (two halves of four) and the scalar
// loop, which must give the same t and triangle. The 8-wide float node test itself: AVX, SSE and
// scalar keys and masks bit for bit, and conservative against the double slab test.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "impact/query/wide_fused_slab.hpp"
#include "support/random.hpp"
#include "wide_bvh_checks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "support/sanitizer.hpp"

namespace impact {
namespace {

constexpr int kWide8Samples = IMPACT_TEST_SANITIZED ? 4 : 1;

template <class S> class WideBvh8Test : public ::testing::Test {};
using Wide8Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(WideBvh8Test, Wide8Scalars);

TYPED_TEST(WideBvh8Test, TorusStructureAndFirstHits) {
  using S = TypeParam;
  const TriangleMesh<S> torus = make_torus<S>(S(1), S(0.4), 32, 16);
  for (int leaf : {1, 4, 7}) {
    WideBvhConfig cfg;
    cfg.leaf_size = leaf;
    const WideBvh<S, 8> w(torus, cfg);
    test::wide::check_structure(torus, w, leaf);
    const int n = 1500 / kWide8Samples;
    EXPECT_GT(test::wide::check_casts(torus, w, n, 0.1, 7 + std::uint64_t(leaf)), n / 10);
  }
  // an 8-wide tree has fewer levels than the 4-wide one of the same binary tree
  const WideBvh<S, 8> w8(torus);
  const WideBvh<S, 4> w4(torus);
  EXPECT_LT(w8.depth(), w4.depth());
  EXPECT_LT(w8.nodes().size(), w4.nodes().size());
  // collapsing an existing tree (spatial middle split, leaves of 3) keeps the answers
  MeshBvhConfig mcfg;
  mcfg.build.leaf_size = 3;
  const WideBvh<S, 8> from_tree(MeshBvh<Aabb<S>>(torus, mcfg));
  test::wide::check_structure(torus, from_tree, 4);
  EXPECT_GT(test::wide::check_casts(torus, from_tree, 500 / kWide8Samples, 0.1, 99), 50 / kWide8Samples);
}

// A mesh large enough that its blocks take the allocator's huge-page path (arrays of 2 MiB or
// more, from a 2 MiB boundary): the structure, the rows of F in the blocks, the casts against
// brute force; and the allocator itself on both sides of its threshold (aligned for the element,
// every element kept through a vector's growth and shrinking).
TYPED_TEST(WideBvh8Test, LargeTreeOnHugePages) {
  using S = TypeParam;
  const TriangleMesh<S> torus = make_torus<S>(S(1), S(0.4), 256, 128);  // 65,536 triangles
  const WideBvh<S, 8> w(torus);
  using Block = WideTriangleBlock<S>;
  const std::size_t block_bytes = w.packed() ? w.packed_blocks().size() * sizeof(WideTriangleBlock<float>) : w.full_blocks().size() * sizeof(Block);
  ASSERT_GE(block_bytes, detail::WideBvhAllocator<Block>::kHugePageMinBytes);  // (the huge-page path)
  const void* blocks = w.packed() ? static_cast<const void*>(w.packed_blocks().data()) : static_cast<const void*>(w.full_blocks().data());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(blocks) % detail::WideBvhAllocator<Block>::kHugePage, 0u);
  test::wide::check_structure(torus, w, 4);
  const int n = 300 / kWide8Samples;
  EXPECT_GT(test::wide::check_casts(torus, w, n, 0.05, 314), n / 20);

  using Alloc = detail::WideBvhAllocator<WideBvhNode8>;
  EXPECT_EQ(Alloc::alignment(10), alignof(WideBvhNode8));
  EXPECT_EQ(Alloc::alignment(8191), alignof(WideBvhNode8));  // below 2 MiB
  EXPECT_EQ(Alloc::alignment(8192), Alloc::kHugePage);       // 2 MiB and more
  std::vector<WideBvhNode8, Alloc> v;
  for (std::int32_t i = 0; i < 10000; ++i) {  // 2.5 MB, through both paths as it grows
    v.emplace_back();
    v.back().first[0] = i;
    ASSERT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % alignof(WideBvhNode8), 0u);
  }
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % Alloc::kHugePage, 0u);
  for (std::int32_t i = 0; i < 10000; ++i) ASSERT_EQ(v[static_cast<std::size_t>(i)].first[0], i);
  v.resize(100);
  v.shrink_to_fit();  // back to operator new
  for (std::int32_t i = 0; i < 100; ++i) ASSERT_EQ(v[static_cast<std::size_t>(i)].first[0], i);
}

#if defined(__linux__)
// An array of 2 MiB or more is a mapping of its own, never heap memory written before (advice to
// pages already mapped small does not make them huge): allocated right after the heap took back
// a block full of ones, it reads zeros (fresh pages), on a 2 MiB boundary. With operator new
// (glibc) it was that block again. The mmap threshold is first raised by freeing a 32 MiB block,
// so that the 8 MiB one comes from the heap.
TEST(WideBvhAllocator, HugeArraysAreMappingsOfTheirOwn) {
  using Alloc = detail::WideBvhAllocator<unsigned char>;
  const std::size_t n = 2 * Alloc::kHugePageMinBytes;
  { std::vector<unsigned char> raise(32u << 20, 1); }
  for (int round = 0; round < 3; ++round) {
    { std::vector<unsigned char> written(8u << 20, 1); }
    Alloc a;
    unsigned char* p = a.allocate(n);
    ASSERT_EQ(reinterpret_cast<std::uintptr_t>(p) % Alloc::kHugePage, 0u);
    std::size_t nonzero = 0;
    for (std::size_t i = 0; i < n; ++i) nonzero += p[i] != 0;
    EXPECT_EQ(nonzero, 0u) << round;
    std::fill(p, p + n, static_cast<unsigned char>(round + 1));  // every byte usable
    EXPECT_EQ(p[n - 1], round + 1);
    a.deallocate(p, n);
  }
}
#endif

// Rays aimed at vertices and edge midpoints of closed meshes: a watertight cast hits, with brute
// force's t, on every path.
TYPED_TEST(WideBvh8Test, RaysThroughVerticesAndEdgesOfClosedMeshesHit) {
  using S = TypeParam;
  for (const bool sphere : {true, false}) {
    const TriangleMesh<S> m = sphere ? make_icosphere<S>(S(1), 2) : make_torus<S>(S(1), S(0.4), 24, 12);
    const WideBvh<S, 8> w(m);
    test::Rng rng(5);
    int hits = 0;
    const int n = 1200 / kWide8Samples;
    const RigidTransform<S>* no_pose = nullptr;
    for (int i = 0; i < n; ++i) {
      const int t = static_cast<int>(rng.index(static_cast<std::uint64_t>(m.num_triangles())));
      const Vec3<S> a = m.vertex(m.F(t, i % 3)), b = m.vertex(m.F(t, (i + 1) % 3));
      const Vec3<S> p = i % 2 == 0 ? a : Vec3<S>((a + b) / S(2));
      const Vec3<S> o = i % 4 < 2 ? Vec3<S>(p * S(0.5)) : Vec3<S>(p + (rng.vec(-1, 1) * 3.0).template cast<S>());
      const Vec3<S> d = p - o;
      if (d.squaredNorm() == S(0)) continue;
      const Ray<S> ray(o, d, S(2));
      const auto ref = test::wide::brute_first_t(m, ray);
      const auto fast = ray_mesh_first_hit(w, ray);
      const auto sse = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, nullptr, true, false);
      // the scalar loop with the public cast's node test (the AVX loop's, when it runs): the same
      // visiting order, so the same triangle among those at the same t (the SSE loop's node test
      // rounds otherwise and may take another one first)
      const auto same = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, nullptr, false, false, detail::wide_fma_available());
      ASSERT_EQ(ref.has_value(), fast.has_value()) << i;
      ASSERT_EQ(fast.has_value(), sse.has_value()) << i;
      ASSERT_EQ(fast.has_value(), same.has_value()) << i;
      if (sphere && i % 4 < 2) {
        ASSERT_TRUE(fast.has_value()) << i;  // from inside the sphere, out through p
      }
      if (!fast) continue;
      ++hits;
      test::wide::expect_first_t(*ref, fast->t, i);
      EXPECT_EQ(fast->t, sse->t) << i;
      EXPECT_EQ(fast->t, same->t) << i;
      EXPECT_EQ(fast->triangle, same->triangle) << i;
    }
    EXPECT_GT(hits, n / 2);
  }
}

// Degenerate meshes: zero-area triangles, 40 coincident triangles (more than eight children's
// worth in one leaf of the source tree), one triangle, a flat mesh.
TYPED_TEST(WideBvh8Test, DegenerateMeshes) {
  using S = TypeParam;
  const std::vector<TriangleMesh<S>> meshes = test::wide::degenerate_meshes<S>();
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const WideBvh<S, 8> w(meshes[k]);
    test::wide::check_structure(meshes[k], w, 4);
    EXPECT_GT(test::wide::check_casts(meshes[k], w, 600 / kWide8Samples, 0.5, 11 + k), 0) << k;
  }
}

// A tree deeper than the fixed stack bounds (a chain of 1,500 shrinking triangles): the stack with a
// heap overflow, the answers brute force's on every path.
TEST(WideBvh8, DeepTreeCastsLikeBruteForce) {
  const int n = 1500;
  Vertices<double> V(3 * n, 3);
  Faces F(n, 3);
  for (int i = 0; i < n; ++i) {
    const double x = std::pow(0.8, i), s = 0.3 * x;
    V.row(3 * i) << x, 0, 0;
    V.row(3 * i + 1) << x, s, 0;
    V.row(3 * i + 2) << x, 0, s;
    F.row(i) << 3 * i, 3 * i + 1, 3 * i + 2;
  }
  const TriangleMesh<double> m(V, F);
  const WideBvh<double, 8> w(m);
  ASSERT_GT(w.depth(), (detail::WideCast<double, 8>::kFixedDepth));
  test::wide::check_structure(m, w, 4);
  EXPECT_GT(test::wide::check_casts(m, w, 400, 0.5, 17), 0);
  for (int i = 0; i < 40; ++i) {
    const double y = std::pow(0.8, 5 * i) * 0.01;
    const Ray<double> ray(Vec3<double>(-1.0, y, y), Vec3<double>(1.0, 0.0, 0.0), 3.0);
    const auto ref = test::wide::brute_first_t(m, ray);
    const auto fast = ray_mesh_first_hit(w, ray);
    ASSERT_TRUE(ref.has_value() && fast.has_value()) << i;
    EXPECT_EQ(*ref, fast->t) << i;
  }
}

// The collapse minimises the surface-area cost (WideBvhConfig::node_cost, block_cost): on the
// binary SAH tree of a random soup of 1,500 triangles, the cost of the 8-wide tree, counted here
// from its nodes' float boxes, is at least 1 % below that of the rule it replaced, computed here
// on the binary tree (each node opens its largest-area inner child until it has eight; every
// subtree of at most four triangles is a leaf), for block costs 0.5, 1 and 3 (ratios 0.97, 0.94,
// 0.74). Run and failed: the previous collapse (ratio 1.0000003, its float boxes), and a collapse
// taking a leaf where a node costs less (the comparison reversed: ratios 22 to 72). Bad costs
// are InvalidInput.
TEST(WideBvh8, CollapseLowersTheSurfaceAreaCost) {
  const TriangleMesh<double> m = test::random_soup<double>(1500, 5, 1.0, 0.05);
  MeshBvhConfig bcfg;
  bcfg.build.split = SplitRule::Sah;
  bcfg.build.leaf_size = 1;
  const MeshBvh<Aabb<double>> binary(m, bcfg);
  const auto& nodes = binary.tree().nodes;
  auto area = [](const Vec3<double>& lo, const Vec3<double>& hi) {
    const Vec3<double> e = hi - lo;
    return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
  };
  std::vector<int> size(nodes.size());
  for (std::size_t j = nodes.size(); j-- > 0;)
    size[j] = nodes[j].is_leaf() ? nodes[j].count : size[static_cast<std::size_t>(nodes[j].left())] + size[static_cast<std::size_t>(nodes[j].right())];
  for (const double block_cost : {0.5, 1.0, 3.0}) {
    WideBvhConfig cfg;
    cfg.block_cost = block_cost;
    const WideBvh<double, 8> w(binary, cfg);
    test::wide::check_structure(m, w, 4);
    // the wide tree's cost
    double wide_cost = 0;
    Vec3<double> rlo = Vec3<double>::Constant(DBL_MAX), rhi = -rlo;
    for (const auto& n : w.nodes())
      for (int c = 0; c < 8; ++c) {
        if (n.count[c] < 0) continue;
        const Vec3<double> lo(n.bounds[0][c], n.bounds[2][c], n.bounds[4][c]), hi(n.bounds[1][c], n.bounds[3][c], n.bounds[5][c]);
        wide_cost += area(lo, hi) * (n.count[c] == 0 ? 1.0 : block_cost * ((n.count[c] + 3) / 4));
        if (&n == &w.nodes()[0]) rlo = rlo.cwiseMin(lo), rhi = rhi.cwiseMax(hi);
      }
    wide_cost += area(rlo, rhi);
    // the greedy collapse's cost
    auto leaf = [&](std::int32_t j) { return nodes[static_cast<std::size_t>(j)].is_leaf() || size[static_cast<std::size_t>(j)] <= 4; };
    auto node_area = [&](std::int32_t j) { return area(nodes[static_cast<std::size_t>(j)].bv.min, nodes[static_cast<std::size_t>(j)].bv.max); };
    ASSERT_FALSE(leaf(0));
    double greedy = node_area(0);
    std::vector<std::int32_t> work{0};
    while (!work.empty()) {
      const std::int32_t j = work.back();
      work.pop_back();
      std::vector<std::int32_t> kids{nodes[static_cast<std::size_t>(j)].left(), nodes[static_cast<std::size_t>(j)].right()};
      while (kids.size() < 8) {
        int open = -1;
        for (int c = 0; c < static_cast<int>(kids.size()); ++c)
          if (!leaf(kids[static_cast<std::size_t>(c)]) && (open < 0 || node_area(kids[static_cast<std::size_t>(c)]) > node_area(kids[static_cast<std::size_t>(open)]))) open = c;
        if (open < 0) break;
        const std::int32_t x = kids[static_cast<std::size_t>(open)];
        kids[static_cast<std::size_t>(open)] = nodes[static_cast<std::size_t>(x)].left();
        kids.push_back(nodes[static_cast<std::size_t>(x)].right());
      }
      for (const std::int32_t x : kids) {
        if (leaf(x)) {
          greedy += node_area(x) * block_cost * ((size[static_cast<std::size_t>(x)] + 3) / 4);
        } else {
          greedy += node_area(x);
          work.push_back(x);
        }
      }
    }
    EXPECT_LT(wide_cost, 0.99 * greedy) << block_cost;
  }
  WideBvhConfig bad;
  bad.node_cost = 0;
  EXPECT_THROW(WideBvh<double>(m, bad), InvalidInput);
  bad.node_cost = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((WideBvh<double, 8>(binary, bad)), InvalidInput);
  bad.node_cost = 1;
  bad.block_cost = -1;
  EXPECT_THROW(WideBvh<double>(m, bad), InvalidInput);
  bad.block_cost = std::numeric_limits<double>::infinity();
  EXPECT_THROW((WideBvh<double, 8>(binary, bad)), InvalidInput);
}

// Under a rigid pose: the plain tree's hit.
TYPED_TEST(WideBvh8Test, PoseMatchesThePlainTree) {
  using S = TypeParam;
  const TriangleMesh<S> m = make_torus<S>(S(1), S(0.4), 24, 12);
  const WideBvh<S, 8> w(m);
  const MeshBvh<Aabb<S>> plain(m);
  test::Rng rng(23);
  int hits = 0;
  for (int i = 0; i < 600 / kWide8Samples; ++i) {
    const RigidTransform<double> pd = test::random_pose(rng, Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2));
    const RigidTransform<S> pose(pd.R.template cast<S>(), pd.t.template cast<S>());
    const Ray<S> ray((rng.vec(-3, 3)).template cast<S>(), (rng.vec(-1, 1) * 6.0).template cast<S>(), S(1));
    const auto a = ray_mesh_first_hit(w, ray, pose), b = ray_mesh_first_hit(plain, ray, pose);
    ASSERT_EQ(a.has_value(), b.has_value()) << i;
    if (!a) continue;
    ++hits;
    EXPECT_EQ(a->t, b->t) << i;
  }
  EXPECT_GT(hits, 20 / kWide8Samples);
}

// The three node loops visit the same nodes in the same order: with the same keys and masks,
// each takes the nearest entered child first (ties: the lower slot) and prunes the others after a
// hit, so the node and triangle tests a cast counts are equal on every path, the hit too. (The
// AVX loop chooses between two entered children by a mask: taking the farther one first, or
// ordering three or more otherwise, visits other nodes after the first hit.) On the torus in
// double and rounded to floats: the AVX loop's leaves of one float block take their own path
// (leaf_one_block_avx), the others leaf_avx.
TEST(WideBvh8, AvxLoopVisitsTheNodesOfTheOtherLoops) {
  for (const bool rounded : {false, true}) {
    TriangleMesh<double> m = make_torus<double>(1.0, 0.4, 48, 24);
    for (int v = 0; rounded && v < m.num_vertices(); ++v)
      for (int c = 0; c < 3; ++c) m.V(v, c) = double(float(m.V(v, c)));
    const WideBvh<double, 8> w(m);
    ASSERT_EQ(w.packed_without_repeats(), rounded);
    test::Rng rng(29);
    const RigidTransform<double>* no_pose = nullptr;
    std::size_t avx_nodes = 0;
    int hits = 0;
    const int rays = 1500 / kWide8Samples / (rounded ? 2 : 1);
    for (int i = 0; i < rays; ++i) {
      const double len = i % 2 ? 4.0 : 0.3;  // long rays cross several boxes; short legs a few
      const Ray<double> ray(rng.vec(-1.6, 1.6), rng.vec(-1, 1).normalized() * len, 1.0);
      RayMeshStats avx, sse, scalar, fused;
      const auto a = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, &avx, true, true);
      const auto b = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, &sse, true, false);
      const auto c = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, &scalar, false, false);
      // the scalar loop with the AVX loop's node test (when the AVX loop runs: else the SSE one's)
      const auto f = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, &fused, false, false, detail::wide_fma_available());
      ASSERT_EQ(a.has_value(), b.has_value()) << i;
      ASSERT_EQ(a.has_value(), c.has_value()) << i;
      ASSERT_EQ(a.has_value(), f.has_value()) << i;
      if (a) {
        ++hits;
        EXPECT_EQ(a->t, b->t) << i;
        EXPECT_EQ(a->t, c->t) << i;
        EXPECT_EQ(a->t, f->t) << i;
        EXPECT_EQ(a->triangle, f->triangle) << i;
        EXPECT_EQ(b->triangle, c->triangle) << i;
      }
      // the AVX loop and the scalar loop with its node test visit the same nodes and triangles, as
      // do the SSE loop and the scalar loop with its node test
      ASSERT_EQ(avx.node_tests, fused.node_tests) << i;
      EXPECT_EQ(avx.triangle_tests, fused.triangle_tests) << i;
      ASSERT_EQ(sse.node_tests, scalar.node_tests) << i;
      EXPECT_EQ(sse.triangle_tests, scalar.triangle_tests) << i;
      avx_nodes += avx.node_tests;
    }
    EXPECT_GT(hits, 150 / kWide8Samples / (rounded ? 2 : 1));
    // several nodes a ray (about 16 on average: 15.6 over the 375 rays of the sanitizer builds)
    EXPECT_GT(avx_nodes, std::size_t(8) * std::size_t(rays));
  }
}

// Rays through the vertices and edge midpoints of a closed mesh in floats (the rounded torus):
// children whose float keys are within rounding of the hit are decided again in double, by the AVX
// loop as by the scalar loop with its node test (else the leaves around the vertex would all be
// opened): the same node and triangle tests on every ray, and the same hit.
TEST(WideBvh8, AvxLoopRedecidesChildrenAtTheHit) {
  if (!detail::wide_fma_available()) GTEST_SKIP() << "no AVX and FMA: the AVX loop does not run";
  TriangleMesh<double> m = make_torus<double>(1.0, 0.4, 48, 24);
  for (int v = 0; v < m.num_vertices(); ++v)
    for (int c = 0; c < 3; ++c) m.V(v, c) = double(float(m.V(v, c)));
  const WideBvh<double, 8> w(m);
  test::Rng rng(41);
  const RigidTransform<double>* no_pose = nullptr;
  const int n = 1500 / kWide8Samples;
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    const int t = static_cast<int>(rng.index(static_cast<std::uint64_t>(m.num_triangles())));
    const Vec3<double> a = m.vertex(m.F(t, i % 3)), b = m.vertex(m.F(t, (i + 1) % 3));
    const Vec3<double> p = i % 2 == 0 ? a : Vec3<double>((a + b) / 2.0);
    const Vec3<double> o = p + rng.vec(-1, 1) * 3.0;
    if ((p - o).squaredNorm() == 0.0) continue;
    const Ray<double> ray(o, p - o, 2.0);
    RayMeshStats avx, fused;
    const auto x = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, &avx, true, true);
    const auto y = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, &fused, false, false, true);
    ASSERT_EQ(x.has_value(), y.has_value()) << i;
    if (x) {
      ++hits;
      EXPECT_EQ(x->t, y->t) << i;
      EXPECT_EQ(x->triangle, y->triangle) << i;
    }
    ASSERT_EQ(avx.node_tests, fused.node_tests) << i;
    ASSERT_EQ(avx.triangle_tests, fused.triangle_tests) << i;
  }
  EXPECT_GT(hits, n / 4);
}

// The 8-wide float node test of the SSE and scalar loops: SSE and scalar give the same keys and
// mask bit for bit; a child the double slab test (WideSlab, on the same float boxes) enters before
// the bound is entered, its key never above the double entry; empty slots are never entered.
TYPED_TEST(WideBvh8Test, FloatSlabIsConservative) {
  using S = TypeParam;
  test::Rng rng(67);
  int entered = 0, missed = 0;
  for (int i = 0; i < 8000 / kWide8Samples; ++i) {
    const double scale = std::ldexp(1.0, int(rng.integer(40)));
    const Vec3<S> o = (rng.vec(-1, 1) * scale).template cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * 3.0 * scale).template cast<S>();
    const Vec3<S> inv = detail::safe_inverse(d);
    const detail::WideFloatSlab<S, 8> fs(o, inv, S(4 * scale));
    if (!fs.usable()) continue;
    WideBvhNode8 n;
    const int used = 1 + int(rng.index(8));
    for (int c = 0; c < used; ++c) {
      const Eigen::Vector3d m = rng.vec(-1.5, 1.5) * scale, h = rng.vec(0.0, i % 5 == 0 ? 1e-6 : 0.8) * scale;
      for (int k = 0; k < 3; ++k) n.bounds[2 * k][c] = float(m[k] - h[k]), n.bounds[2 * k + 1][c] = float(m[k] + h[k]);
      n.count[c] = 1;
    }
    const S t_max = i % 3 == 0 ? std::numeric_limits<S>::infinity() : S(rng.uniform() * 2);
    const float bound = i % 2 ? std::numeric_limits<float>::infinity() : float(rng.uniform() * 1.5);
    const float exit = detail::float_round_up(double(t_max));
    float simd[8], scalar[8];
    const int ms = fs.entered(n, exit, bound, simd, true), mc = fs.entered(n, exit, bound, scalar, false);
    ASSERT_EQ(ms, mc) << i;
    S exact[8];
    detail::WideSlab<S>(o, inv).keys(n, t_max, exact, false);
    for (int c = 0; c < 8; ++c) {
      if ((mc >> c) & 1) {
        EXPECT_EQ(simd[c], scalar[c]) << i << " " << c;
      }
      if (c >= used) {
        EXPECT_FALSE((mc >> c) & 1) << "empty slot entered " << i;
        continue;
      }
      if (exact[c] <= S(bound)) {
        ++entered;
        ASSERT_TRUE((mc >> c) & 1) << i << " " << c;
        EXPECT_LE(S(scalar[c]), exact[c]) << i << " " << c;
      } else {
        missed += (mc >> c) & 1 ? 0 : 1;
      }
    }
  }
  EXPECT_GT(entered, 500 / kWide8Samples);
  EXPECT_GT(missed, 500 / kWide8Samples);
}

// The tree's box as WideBvh::box lays it out: the union of the used slots' boxes of `n`.
std::array<double, 8> union_box(const WideBvhNode8& n) {
  std::array<double, 8> box{DBL_MAX, DBL_MAX, DBL_MAX, 0.0, -DBL_MAX, -DBL_MAX, -DBL_MAX, 0.0};
  for (int c = 0; c < 8; ++c)
    if (n.count[c] >= 0)
      for (std::size_t k = 0; k < 3; ++k) {
        box[k] = std::min(box[k], double(n.bounds[2 * k][c]));
        box[4 + k] = std::max(box[4 + k], double(n.bounds[2 * k + 1][c]));
      }
  return box;
}

// The fused node test of the AVX loop (WideFusedRay, WideFusedAvx), for rays in float and double
// against the double slab test (WideSlab) on random nodes: a child WideSlab enters before the bound
// is entered, its key lo never above WideSlab's entry and at most 2 (|entry| 2^-19 + e) below it
// (the slack the cast's tie bound allows: a key below the hit's t by more is entered before it);
// empty slots are never entered; the AVX test gives the scalar test's keys and mask bit for bit.
// The tree's box is the union of the node's boxes (the tightest the reach can be), or larger. The
// rays: origins near the boxes or far off (up to 2^19 times the scale: large |o / d|), directions
// from 2^-12 to 2^12 times the scale, some with one or two components 2^-30 of the others (nearly
// axis-parallel), some boxes with a face through the origin, t_max infinite, huge or in [0, 2].
TYPED_TEST(WideBvh8Test, FusedSlabIsConservative) {
  using S = TypeParam;
  test::Rng rng(83);
  int entered = 0, missed = 0, avx_checked = 0;
  for (int i = 0; i < 12000 / kWide8Samples; ++i) {
    const double scale = std::ldexp(1.0, int(rng.integer(40)));
    const double shift = i % 4 == 0 ? std::ldexp(1.0, int(rng.index(20))) * scale : 0.0;
    const Vec3<S> o = (rng.vec(-1, 1) * scale + Eigen::Vector3d::Constant(shift)).template cast<S>();
    Eigen::Vector3d dd = rng.vec(-1, 1) * 3.0 * scale * (i % 5 == 1 ? std::ldexp(1.0, int(rng.integer(24)) - 12) : 1.0);
    if (i % 7 == 2) dd[int(rng.index(3))] *= 0x1p-30;  // nearly parallel to a plane
    if (i % 7 == 3) dd[int(rng.index(3))] *= 0x1p-30, dd[int(rng.index(3))] *= 0x1p-30;  // or to an axis
    const Vec3<S> d = dd.template cast<S>();
    const Vec3<S> inv = detail::safe_inverse(d);
    WideBvhNode8 n;
    const int used = 1 + int(rng.index(8));
    for (int c = 0; c < used; ++c) {
      const Eigen::Vector3d m = rng.vec(-1.5, 1.5) * scale + Eigen::Vector3d::Constant(shift);
      const Eigen::Vector3d h = rng.vec(0.0, i % 5 == 0 ? 1e-6 : 0.8) * scale;
      for (int k = 0; k < 3; ++k) n.bounds[2 * k][c] = float(m[k] - h[k]), n.bounds[2 * k + 1][c] = float(m[k] + h[k]);
      if (i % 6 == 5 && c == 0) {  // a face through the origin (when o is a float there)
        const int k = int(rng.index(3));
        n.bounds[2 * k + int(rng.index(2))][c] = float(o[k]);
        if (n.bounds[2 * k][c] > n.bounds[2 * k + 1][c]) std::swap(n.bounds[2 * k][c], n.bounds[2 * k + 1][c]);
      }
      n.count[c] = 1;
    }
    std::array<double, 8> box = union_box(n);
    if (i % 3 == 1)
      for (std::size_t k = 0; k < 3; ++k) box[k] -= rng.uniform() * scale, box[4 + k] += rng.uniform() * scale;
    const S t_max = i % 3 == 0 ? std::numeric_limits<S>::infinity() : (i % 11 == 4 ? S(0x1p40) : S(rng.uniform() * 2));
    const detail::WideFusedRay fr(o, inv, S(4 * (scale + shift)), box, double(t_max));
    if (!fr.usable()) continue;
    const float exit = detail::float_round_up(double(t_max));
    const float bound = std::min(exit, i % 2 ? std::numeric_limits<float>::infinity() : float(rng.uniform() * 1.5));
    float keys[8];
    const int m = fr.entered_scalar(n, bound, keys);
#if defined(IMPACT_WIDE_AVX)
    if (detail::wide_fma_available()) {
      detail::WideFusedAvx a;
      a.set(fr);
      float avx[8];
      ASSERT_EQ(a.entered(n, bound, avx), m) << i;
      for (int c = 0; c < 8; ++c)
        if ((m >> c) & 1) {
          EXPECT_EQ(avx[c], keys[c]) << i << " " << c;
        }
      ++avx_checked;
    }
#endif
    S exact[8];
    detail::WideSlab<S>(o, inv).keys(n, t_max, exact, false);
    for (int c = 0; c < 8; ++c) {
      if (c >= used) {
        EXPECT_FALSE((m >> c) & 1) << "empty slot entered " << i;
        continue;
      }
      if (exact[c] <= S(bound)) {
        ++entered;
        ASSERT_TRUE((m >> c) & 1) << i << " " << c;
        EXPECT_LE(S(keys[c]), exact[c]) << i << " " << c;
        EXPECT_LE(double(exact[c]) - double(keys[c]), 2 * (std::abs(double(exact[c])) * 0x1p-19 + double(fr.e))) << i << " " << c;
      } else {
        missed += (m >> c) & 1 ? 0 : 1;
      }
    }
  }
  EXPECT_GT(entered, 500 / kWide8Samples);
  EXPECT_GT(missed, 500 / kWide8Samples);
  if (detail::wide_fma_available()) {
    EXPECT_GT(avx_checked, 1000 / kWide8Samples);
  }
}

// Rays that touch a box exactly, by construction: the ray passes at t = 1/2 (or starts, at t = 0)
// through a point q on a face, an edge or a corner of the box (q's coordinates are floats and
// o = q - d / 2 is exact in double), at scales from 2^-40 to 2^36, near the coordinate origin and
// translated by up to 2^20 times the box size, t_max at or beyond the touch, the tree's box the
// union of the node's boxes (so the ray may leave it right at the touch: the reach is tight): the
// fused test enters the box with a key at most the touch's t.
TEST(WideBvh8, FusedSlabEntersBoxesTheRayGrazes) {
  test::Rng rng(89);
  int checked = 0, corners = 0;
  for (int i = 0; i < 20000 / kWide8Samples; ++i) {
    const int k = int(rng.integer(38)) - 2;
    const double s = std::ldexp(1.0, k);
    const double shift = i % 3 == 0 ? 0.0 : std::ldexp(1.0, int(rng.index(21))) * s * (i % 2 ? 1 : -1);
    Vec3<double> q, d;
    for (int a = 0; a < 3; ++a) {
      q[a] = double(float(rng.uniform(-1, 1) * s + shift));
      d[a] = double(float(rng.uniform(0.25, 4.0) * s)) * (rng.index(2) ? 1 : -1);  // no tiny component: o exact
    }
    const bool at_start = i % 7 == 0;
    const Vec3<double> o = at_start ? q : Vec3<double>(q - 0.5 * d);
    const double t_touch = at_start ? 0.0 : 0.5;
    if (!at_start && (o + 0.5 * d != q || (q - o) * 2.0 != d)) continue;  // (never: checked)
    // the box: q on its boundary on 1 (face), 2 (edge) or 3 (corner) axes, inside on the others
    const int boundary = 1 + int(rng.index(3));
    corners += boundary == 3 ? 1 : 0;
    WideBvhNode8 n;
    const int slot = int(rng.index(8)), used = slot + 1 + int(rng.index(std::uint64_t(8 - slot)));
    for (int c = 0; c < used; ++c) {
      for (int a = 0; a < 3; ++a) {
        const float lo = float(q[a] - rng.uniform(0.01, 1.0) * s), hi = float(q[a] + rng.uniform(0.01, 1.0) * s);
        float box_lo = lo < float(q[a]) ? lo : std::nextafter(float(q[a]), -FLT_MAX);
        float box_hi = hi > float(q[a]) ? hi : std::nextafter(float(q[a]), FLT_MAX);
        if (c == slot && a < boundary) {  // q on the lower or the upper face of this axis
          if (rng.index(2)) box_lo = float(q[a]);
          else box_hi = float(q[a]);
        } else if (c != slot) {  // other children: anywhere around
          const float off = float(rng.uniform(-2, 2) * s);
          box_lo += off, box_hi += off;
        }
        n.bounds[2 * a][c] = box_lo, n.bounds[2 * a + 1][c] = box_hi;
      }
      n.count[c] = 1;
    }
    const double t_max = i % 5 == 0 ? t_touch : (i % 5 == 1 ? std::numeric_limits<double>::infinity() : 1.0);
    const Vec3<double> inv = detail::safe_inverse(d);
    const std::array<double, 8> box = union_box(n);
    const detail::WideFusedRay fr(o, inv, 4 * (s + std::abs(shift)), box, t_max);
    ASSERT_TRUE(fr.usable()) << i;
    const float exit = detail::float_round_up(t_max);
    float keys[8];
    const int m = fr.entered_scalar(n, exit, keys);
    ASSERT_TRUE((m >> slot) & 1) << i << " scale 2^" << k << " shift " << shift << " axes " << boundary;
    EXPECT_LE(double(keys[slot]), t_touch) << i;
    // a key below the touch's t keeps the box entered against a bound at that t
    EXPECT_TRUE((fr.entered_scalar(n, float(t_touch), keys) >> slot) & 1) << i;
#if defined(IMPACT_WIDE_AVX)
    if (detail::wide_fma_available()) {
      detail::WideFusedAvx a;
      float e = -1.0f, avx[8];
      ASSERT_TRUE(a.set(o, inv, 4 * (s + std::abs(shift)), box, t_max, e)) << i;
      EXPECT_EQ(e, fr.e) << i;
      EXPECT_EQ(a.entered(n, exit, avx), m) << i;
    }
#endif
    ++checked;
  }
  EXPECT_GT(checked, 19000 / kWide8Samples);
  EXPECT_GT(corners, 5000 / kWide8Samples);
}

// Rays in float past a box that its float slab test (WideSlab<float>: its exit padded by 8 u, u =
// 2^-24) may still enter: the ray crosses the box's near plane on one axis at t1 and its far plane
// on another at t1 (1 - delta), delta from -4 u to 24 u (a miss by up to 24 u of t1), the box alone
// in the node, so the tree's box is the box itself and the reach ends at its exit (the smallest
// margin the fused test takes). Every box WideSlab enters is entered, its key at most WideSlab's
// entry; some of them are misses the padding enters (which need more than 4 u of margin a plane;
// WideFusedRay's proof asks 7.51 u).
TEST(WideBvh8, FusedSlabEntersBoxesTheFloatSlabPads) {
  test::Rng rng(113);
  int entered = 0, padded = 0;
  for (int i = 0; i < 20000 / kWide8Samples; ++i) {
    const double s = std::ldexp(1.0, int(rng.integer(20)));
    Vec3<float> o, d;
    for (int k = 0; k < 3; ++k) {
      o[k] = float(rng.uniform(-1, 1) * s);
      d[k] = float(rng.uniform(0.25, 4.0) * s) * (rng.index(2) ? 1.0f : -1.0f);
    }
    const int a = int(rng.index(3)), b = (a + 1 + int(rng.index(2))) % 3, c3 = 3 - a - b;
    const double t1 = rng.uniform(0.25, 2.0), delta = (i % 2 ? rng.uniform(-4, 24) : rng.uniform(6, 18)) * 0x1p-24;
    WideBvhNode8 n;
    const auto set = [&](int k, double lo, double hi) { n.bounds[2 * k][0] = float(lo), n.bounds[2 * k + 1][0] = float(hi); };
    const double pa = double(o[a]) + t1 * double(d[a]), qb = double(o[b]) + t1 * (1 - delta) * double(d[b]);
    const double far_a = double(o[a]) + 4 * t1 * double(d[a]), near_b = double(o[b]) - 2 * t1 * double(d[b]);
    set(a, std::min(pa, far_a), std::max(pa, far_a));  // entered at pa on axis a
    set(b, std::min(qb, near_b), std::max(qb, near_b));  // left at qb on axis b
    const double e3 = double(o[c3]) + t1 * double(d[c3]), w3 = 4 * t1 * std::abs(double(d[c3]));
    set(c3, e3 - w3, e3 + w3);
    n.count[0] = 1;
    const float t_max = i % 3 == 0 ? std::numeric_limits<float>::infinity() : float(t1 * (i % 3 == 1 ? 1.0 : 1.5));
    const Vec3<float> inv = detail::safe_inverse(d);
    const detail::WideFusedRay fr(o, inv, float(8 * s), union_box(n), double(t_max));
    ASSERT_TRUE(fr.usable()) << i;
    float exact[8], keys[8];
    detail::WideSlab<float>(o, inv).keys(n, t_max, exact, false);
    const int m = fr.entered_scalar(n, detail::float_round_up(double(t_max)), keys);
    EXPECT_FALSE(m & ~1) << i;
    if (!(exact[0] <= t_max)) continue;
    ++entered;
    ASSERT_TRUE(m & 1) << i << " scale " << s << " delta/u " << delta * 0x1p24;
    EXPECT_LE(keys[0], exact[0]) << i;
    // a miss in exact arithmetic: the far plane's parameter below the near plane's
    const double near_t = (double(n.bounds[2 * a + (d[a] < 0)][0]) - double(o[a])) / double(d[a]);
    const double far_t = (double(n.bounds[2 * b + (d[b] > 0)][0]) - double(o[b])) / double(d[b]);
    padded += far_t < near_t ? 1 : 0;
  }
  EXPECT_GT(entered, 4000 / kWide8Samples);
  EXPECT_GT(padded, 1000 / kWide8Samples);
}

// The float rays that need the most of the fused test's margin (WideFusedRay, whose proof asks
// 7.51 u a plane, u = 2^-24): misses of about 11 u that WideSlab<float> enters because every one of
// its roundings and the fused test's runs the same way. All values are near 1. On the entry axis
// the origin is tiny, so WideSlab's b - o rounds, down by nearly u, and its product rounds down by
// nearly u; on the exit axis both round up and the 8 u padding's sum rounds up; WideSlab's entry
// and exit are then the same float. The fused near value rounds up, the far one down (the exit
// axis's far value below 1, where the float grid is twice as fine). Found by a search over such
// rays; a margin of 5 u misses both boxes. Each case is checked on every pair of axes and both
// signs of each (a mirrored axis gives the same roundings), the box alone in the node (its exit
// is the reach) and t_max just past it.
TEST(WideBvh8, FusedSlabEntersTheFloatSlabsWorstMisses) {
  struct Plane {
    float o, b, d;  // the origin, the plane crossed and the direction on that axis
  };
  struct Case {
    Plane entry, exit;
  };
  const Case cases[] = {
      {{-0x1.49b598p-18f, 0x1.64041p-1f, 0x1.6404b2p-1f}, {0x1.775f84p-19f, 0x1.02cd7cp+0f, 0x1.02cd56p+0f}},
      {{-0x1.ea7bc2p-25f, 0x1.331054p+0f, 0x1.33105p+0f}, {0x1.04231cp-30f, 0x1.65fb18p-1f, 0x1.65fb22p-1f}},
  };
  const float t_max = 1.0f + 0x1p-17f;
  int checked = 0;
  for (const Case& k : cases)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        if (a == b) continue;
        const int c = 3 - a - b;
        for (int signs = 0; signs < 4; ++signs) {
          const float sa = signs & 1 ? -1.0f : 1.0f, sb = signs & 2 ? -1.0f : 1.0f;
          Vec3<float> o, d;
          o[a] = sa * k.entry.o, d[a] = sa * k.entry.d;
          o[b] = sb * k.exit.o, d[b] = sb * k.exit.d;
          o[c] = 0.0f, d[c] = 1.0f;
          WideBvhNode8 n;
          const auto set = [&](int axis, float p, float q) { n.bounds[2 * axis][0] = std::min(p, q), n.bounds[2 * axis + 1][0] = std::max(p, q); };
          set(a, sa * k.entry.b, sa * 4.0f);  // entered at the first plane, left far beyond
          set(b, sb * k.exit.b, -sb * 4.0f);  // left at the first plane
          set(c, -4.0f, 4.0f);
          n.count[0] = 1;
          // a miss in exact arithmetic: the exit's parameter below the entry's
          const long double t_in = ((long double)k.entry.b - k.entry.o) / k.entry.d, t_out = ((long double)k.exit.b - k.exit.o) / k.exit.d;
          EXPECT_GT(t_in, t_out);
          const Vec3<float> inv = detail::safe_inverse(d);
          float exact[8], keys[8];
          detail::WideSlab<float>(o, inv).keys(n, t_max, exact, false);
          ASSERT_LE(exact[0], t_max) << a << b << signs;  // the float slab test enters it
          const detail::WideFusedRay fr(o, inv, 4.0f, union_box(n), double(t_max));
          ASSERT_TRUE(fr.usable());
          EXPECT_EQ(fr.entered_scalar(n, t_max, keys) & 1, 1) << "entry axis " << a << ", exit axis " << b << ", signs " << signs;
          EXPECT_LE(keys[0], exact[0]) << a << b << signs;
#if defined(IMPACT_WIDE_AVX)
          if (detail::wide_fma_available()) {
            detail::WideFusedAvx avx;
            avx.set(fr);
            float avx_keys[8];
            EXPECT_EQ(avx.entered(n, t_max, avx_keys) & 1, 1) << a << b << signs;
          }
#endif
          ++checked;
        }
      }
  EXPECT_EQ(checked, 48);
}

// The AVX cast's one-pass set-up in double (WideFusedAvx::set) against WideFusedRay: the same
// usability (rays beyond its range, zero and tiny direction components, origins far off, |o / d|
// beyond 2^63, a reach beyond 2^80), the same e, offsets and plane offsets and, node by node, the
// same mask and keys bit for bit (a wrong axis, sign or rounding in the set-up changes them); the
// tree's box around the node's boxes, or off to a side (the ray may leave it before t = 0).
TEST(WideBvh8, AvxSetUpMatchesTheScalarTest) {
#if defined(IMPACT_WIDE_AVX)
  if (!detail::wide_fma_available()) GTEST_SKIP() << "no AVX and FMA";
  test::Rng rng(71);
  int usable = 0, unusable = 0, keys_checked = 0;
  for (int i = 0; i < 6000 / kWide8Samples; ++i) {
    const double scale = std::ldexp(1.0, int(rng.integer(70)));
    Vec3<double> o = rng.vec(-1, 1) * scale, d = rng.vec(-1, 1) * std::ldexp(1.0, int(rng.integer(70)));
    if (i % 7 == 0) d[int(rng.index(3))] = 0.0;                      // an infinite 1 / d
    if (i % 11 == 0) o[int(rng.index(3))] = std::ldexp(1.0, 61);     // beyond the node test's range
    if (i % 13 == 0) o[int(rng.index(3))] += std::ldexp(1.0, 45);    // far off
    const Vec3<double> inv = detail::safe_inverse(d);
    const double bound_c = i % 17 == 0 ? std::ldexp(1.0, 61) : 4 * scale;
    WideBvhNode8 n;
    const int used = 1 + int(rng.index(8));
    for (int c = 0; c < used; ++c) {
      const Eigen::Vector3d m = o + rng.vec(-1.5, 1.5) * scale, h = rng.vec(0.0, 0.8) * scale;
      for (int k = 0; k < 3; ++k) n.bounds[2 * k][c] = float(m[k] - h[k]), n.bounds[2 * k + 1][c] = float(m[k] + h[k]);
      n.count[c] = 1;
    }
    std::array<double, 8> box = union_box(n);
    if (i % 5 == 0) {  // off to a side
      const std::size_t k = rng.index(3);
      const double off = (rng.index(2) ? 4.0 : -4.0) * scale;
      box[k] += off, box[4 + k] += off;
    }
    const double t_max = i % 3 == 0 ? std::numeric_limits<double>::infinity() : (i % 19 == 1 ? 0x1p90 : rng.uniform() * 2);
    const detail::WideFusedRay fr(o, inv, bound_c, box, t_max);
    const float bound = std::min(detail::float_round_up(t_max), i % 2 ? std::numeric_limits<float>::infinity() : float(rng.uniform() * 1.5));
    detail::WideFusedAvx a;
    float e = -1.0f;
    ASSERT_EQ(a.set(o, inv, bound_c, box, t_max, e), fr.usable()) << i;
    if (!fr.usable()) {
      EXPECT_EQ(e, 0.0f) << i;
      ++unusable;
      continue;
    }
    ++usable;
    EXPECT_EQ(e, fr.e) << i;
    for (int j = 0; j < 6; ++j) {
      EXPECT_EQ(a.planes[j], fr.planes[j]) << i << " " << j;
      float lanes[8];
      std::memcpy(lanes, &a.oi[j], sizeof lanes);
      EXPECT_EQ(lanes[0], fr.oi[j]) << i << " " << j;
    }
    float direct[8], scalar[8];
    const int md = a.entered(n, bound, direct), ms = fr.entered_scalar(n, bound, scalar);
    ASSERT_EQ(md, ms) << i;
    for (int c = 0; c < 8; ++c)
      if ((ms >> c) & 1) {
        EXPECT_EQ(direct[c], scalar[c]) << i << " " << c;
        ++keys_checked;
      }
  }
  EXPECT_GT(usable, 1000 / kWide8Samples);
  EXPECT_GT(unusable, 1000 / kWide8Samples);
  EXPECT_GT(keys_checked, 500 / kWide8Samples);
#else
  GTEST_SKIP() << "the AVX node test is not compiled in";
#endif
}

// The public 8-wide cast in double folds its argument check into the AVX set-up (a ray its float
// test takes is in range): it must throw InvalidInput exactly for the rays validate_ray rejects,
// and give the other node tests' answer on the others. Components at and around the float test's
// limits (2^60 for the origin and 1 / d) and CoordinateRange's (2^200, 2^-200), zero, infinite, NaN.
TEST(WideBvh8, PublicCastThrowsExactlyForInvalidRays) {
  const TriangleMesh<double> m = make_torus<double>(1.0, 0.4, 16, 8);
  const WideBvh<double, 8> w(m);
  test::Rng rng(97);
  const double inf = std::numeric_limits<double>::infinity();
  const double specials[] = {0.0, -0.0, 1.0, -3.0, inf, -inf, std::numeric_limits<double>::quiet_NaN(), 0x1p59, -0x1p60, 0x1p61,
                             0x1p-59, 0x1p-61, -0x1p-62, 0x1p200, -0x1p201, 0x1p-200, 0x1p-201, std::numeric_limits<double>::denorm_min()};
  const int ns = static_cast<int>(sizeof(specials) / sizeof(specials[0]));
  int accepted = 0, rejected = 0, hits = 0;
  for (int i = 0; i < 4000 / kWide8Samples; ++i) {
    auto value = [&] { return rng.index(3) == 0 ? specials[rng.index(static_cast<std::uint64_t>(ns))] : rng.uniform(-2, 2); };
    Ray<double> ray(Vec3<double>(value(), value(), value()), Vec3<double>(value(), value(), value()), value());
    if (i % 2 == 0) ray.origin = Vec3<double>(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), value());
    if (i % 3 != 0) ray.t_max = i % 5 == 0 ? inf : rng.uniform(0, 3);
    bool invalid = false;
    try {
      validate_ray(ray, "test");
    } catch (const InvalidInput&) {
      invalid = true;
    }
    if (invalid) {
      EXPECT_THROW(ray_mesh_first_hit(w, ray), InvalidInput) << i;
      ++rejected;
      continue;
    }
    ++accepted;
    std::optional<RayMeshHit<double>> a;
    EXPECT_NO_THROW(a = ray_mesh_first_hit(w, ray)) << i;
    const auto b = detail::ray_wide_first_hit_unchecked(w, ray, static_cast<const RigidTransform<double>*>(nullptr), nullptr, true, false);
    ASSERT_EQ(a.has_value(), b.has_value()) << i;
    if (!a) continue;
    ++hits;
    EXPECT_EQ(a->t, b->t) << i;
    EXPECT_EQ(a->triangle, b->triangle) << i;
  }
  EXPECT_GT(accepted, 400 / kWide8Samples);
  EXPECT_GT(rejected, 400 / kWide8Samples);
  EXPECT_GT(hits, 20 / kWide8Samples);
}

}  // namespace
}  // namespace impact
