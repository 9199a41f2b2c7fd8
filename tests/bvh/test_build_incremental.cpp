// SPDX-License-Identifier: MIT
// Incremental construction (bvh/build_incremental.hpp): after random inserts and removes the tree
// is valid (every present primitive in exactly one leaf, parent links and counts consistent, each
// box holding its children and its triangle, each BV of the flat copy holding its triangles'
// vertices) and its queries agree with brute force (a probe ball, and pair traversal of two trees
// filtered by the tests' exact triangle test); degenerate input (coincident triangles, slivers,
// very unequal sizes) builds a balanced tree; the sibling choice keeps the surface-area cost near
// a top-down SAH build's; bad input throws and changes nothing. Sphere, AABB and oriented box,
// float and double.
#include "impact/bvh/build_incremental.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/bvh/traverse_pair.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/meshes.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <tuple>

using namespace impact;
using namespace impact::test;

namespace {

/// Slack of the containment checks: merged spheres and boxes are rounded.
template <class S> S containment_slack() { return std::is_same_v<S, float> ? S(1e-4) : S(1e-10); }

template <class S> bool bv_holds(const Sphere<S>& s, const Vec3<S>& x) { return (x - s.center).norm() <= s.radius + containment_slack<S>(); }
template <class S> bool bv_holds(const Aabb<S>& b, const Vec3<S>& x) {
  return ((x.array() >= b.min.array() - containment_slack<S>()) && (x.array() <= b.max.array() + containment_slack<S>())).all();
}
template <class S> bool bv_holds(const Obb<S>& o, const Vec3<S>& x) {
  const Eigen::Vector3d h = o.axes.template cast<double>().fullPivLu().solve((x - o.center).template cast<double>());
  return (h.cwiseAbs().array() <= o.half.template cast<double>().array() + double(containment_slack<S>())).all();
}

/// Walks the pool from the root: parent links, counts, boxes holding children and triangles,
/// every primitive once. Returns the primitive ids found and the maximum depth.
template <class BV>
std::multiset<int> check_pool(const IncrementalBvh<BV>& t, const TriangleMesh<typename BvTraits<BV>::Scalar>& m, std::size_t& depth) {
  using S = typename BvTraits<BV>::Scalar;
  std::multiset<int> ids;
  depth = 0;
  if (t.root() == t.null) {
    EXPECT_EQ(t.size(), 0u);
    return ids;
  }
  const auto& nodes = t.nodes();
  EXPECT_EQ(nodes[static_cast<std::size_t>(t.root())].parent, t.null);
  std::vector<std::pair<std::int32_t, std::size_t>> stack{{t.root(), 0}};
  while (!stack.empty()) {
    const auto [i, d] = stack.back();
    stack.pop_back();
    depth = std::max(depth, d);
    const auto& n = nodes[static_cast<std::size_t>(i)];
    if (n.is_leaf()) {
      EXPECT_EQ(n.count, 1);
      const int id = n.child[1];
      ids.insert(id);
      const Triangle<S> tri = m.triangle(id);
      for (int v = 0; v < 3; ++v) {
        EXPECT_TRUE(n.box.contains(tri[v])) << "leaf box of " << id;
        EXPECT_TRUE(bv_holds(t.leaf_bv(id), tri[v])) << "leaf BV of " << id;
      }
      continue;
    }
    int sum = 0;
    for (int c = 0; c < 2; ++c) {
      const auto& k = nodes[static_cast<std::size_t>(n.child[c])];
      EXPECT_EQ(k.parent, i);
      EXPECT_TRUE(n.box.contains(k.box.min) && n.box.contains(k.box.max)) << "inner box " << i;
      sum += k.count;
      stack.push_back({n.child[c], d + 1});
    }
    EXPECT_EQ(n.count, sum);
  }
  return ids;
}

/// Every node BV of the flat copy holds every vertex of the triangles below it; every primitive
/// appears once; children follow their parent. Returns the primitive ids.
template <class BV> std::multiset<int> check_flat(const Bvh<BV>& t, const TriangleMesh<typename BvTraits<BV>::Scalar>& m) {
  std::multiset<int> ids;
  if (t.empty()) return ids;
  for (std::size_t k = 0; k < t.nodes.size(); ++k) {
    const auto& n = t.nodes[k];
    if (!n.is_leaf()) {
      EXPECT_GT(n.left(), static_cast<std::int32_t>(k));
      continue;
    }
    for (std::int32_t p = n.first; p < n.first + n.count; ++p) ids.insert(t.primitives[static_cast<std::size_t>(p)]);
  }
  // containment: walk each node's subtree
  for (std::size_t k = 0; k < t.nodes.size(); ++k) {
    std::vector<std::int32_t> stack{static_cast<std::int32_t>(k)};
    while (!stack.empty()) {
      const auto& n = t.nodes[static_cast<std::size_t>(stack.back())];
      stack.pop_back();
      if (!n.is_leaf()) {
        stack.push_back(n.left());
        stack.push_back(n.right());
        continue;
      }
      for (std::int32_t p = n.first; p < n.first + n.count; ++p)
        for (int v = 0; v < 3; ++v)
          EXPECT_TRUE(bv_holds(t.nodes[k].bv, m.triangle(t.primitives[static_cast<std::size_t>(p)])[v])) << "node " << k;
    }
  }
  return ids;
}

/// Triangle rows of `m` (those in `present`) that touch the ball, by brute force.
template <class S> std::vector<int> ball_brute(const TriangleMesh<S>& m, const std::set<int>& present, const Sphere<S>& ball) {
  std::vector<int> out;
  for (int t : present) {
    const Triangle<S> tri = m.triangle(t);
    if ((tri.centroid() - ball.center).norm() <= ball.radius) out.push_back(t);
  }
  return out;
}

}  // namespace

template <class BV> class IncrementalBvhTest : public ::testing::Test {};
using BvTypes = ::testing::Types<Sphere<float>, Sphere<double>, Aabb<float>, Aabb<double>, Obb<float>, Obb<double>>;
TYPED_TEST_SUITE(IncrementalBvhTest, BvTypes);

// Random inserts and removes: the tree stays valid and its queries agree with brute force.
TYPED_TEST(IncrementalBvhTest, RandomInsertsAndRemovesKeepAValidTree) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const int n = 150;
  const auto ma = random_soup<S>(n, 31, 1.0, 0.2);
  const auto mb = random_soup<S>(80, 32, 1.0, 0.2);
  for (const auto& [search, rot] : {std::pair{SiblingSearch::Greedy, true}, std::pair{SiblingSearch::BranchAndBound, false},
                                    std::pair{SiblingSearch::BranchAndBound, true}}) {
  SCOPED_TRACE(std::string(search == SiblingSearch::Greedy ? "greedy" : "branch and bound") + (rot ? " + rotations" : ""));
  IncrementalBvh<BV> a(search, rot), b(search, rot);
  for (int t = 0; t < mb.num_triangles(); ++t) b.insert(t, mb.triangle(t));
  Rng rng(7);
  std::set<int> present;
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  for (int i = n - 1; i > 0; --i) std::swap(order[static_cast<std::size_t>(i)], order[rng.index(std::uint64_t(i) + 1)]);
  std::size_t next = 0, pairs_seen = 0;
  for (int round = 0; round < 4; ++round) {
    // insert a batch, then remove a random third of what is present
    for (int k = 0; k < 45 && next < order.size(); ++k, ++next) {
      a.insert(order[next], ma.triangle(order[next]));
      present.insert(order[next]);
    }
    std::vector<int> now(present.begin(), present.end());
    for (int k = 0; k < int(now.size()) / 3; ++k) {
      const int id = now[rng.index(now.size())];
      if (!present.count(id)) continue;
      a.remove(id);
      present.erase(id);
    }
    if (round == 2)  // removed ones come back
      for (int id = 0; id < n; id += 5)
        if (!present.count(id) && std::find(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(next), id) != order.begin() + static_cast<std::ptrdiff_t>(next)) {
          a.insert(id, ma.triangle(id));
          present.insert(id);
        }
    ASSERT_EQ(a.size(), present.size());
    std::size_t depth = 0;
    const auto ids = check_pool(a, ma, depth);
    ASSERT_EQ(ids, std::multiset<int>(present.begin(), present.end())) << "round " << round;
    for (int id = 0; id < n; ++id) EXPECT_EQ(a.contains(id), present.count(id) == 1);
    EXPECT_LE(depth, 4 * 8u);  // a few times log2 n on a uniform soup
    const Bvh<BV> flat = a.to_bvh();
    ASSERT_EQ(check_flat(flat, ma), std::multiset<int>(present.begin(), present.end()));
    ASSERT_EQ(flat.nodes.size(), 2 * present.size() - 1);

    // a probe ball against brute force (centroids inside the ball)
    for (int probe = 0; probe < 3; ++probe) {
      const Sphere<S> ball(rng.vec(-1, 1).cast<S>(), S(0.4));
      Vec3<S> corners[8];  // a BV around the ball's cube holds the ball
      for (int c = 0; c < 8; ++c)
        corners[c] = ball.center + ball.radius * Vec3<S>(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1);
      const BV probe_bv = BvTraits<BV>::fit(corners, 8, {});
      std::vector<int> got;
      traverse(
          flat, [&](const BV& bv) { return BvTraits<BV>::overlap(bv, probe_bv); },
          [&](std::int32_t id) {
            if ((ma.triangle(id).centroid() - ball.center).norm() <= ball.radius) got.push_back(id);
            return true;
          });
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, ball_brute(ma, present, ball));
    }
    // pair traversal of the two trees against the exact brute force, under a few poses
    const Bvh<BV> fb = b.to_bvh();
    for (int pose = 0; pose < 2; ++pose) {
      const RigidTransform<S> xf = random_pose(rng, Eigen::Vector3d::Constant(-0.5), Eigen::Vector3d::Constant(0.5)).template cast<S>();
      std::vector<std::pair<int, int>> got;
      traverse_pair(
          flat, fb, [&](const BV& x, const BV& y) { return BvTraits<BV>::overlap(x, BvTraits<BV>::transformed(y, xf)); },
          [&](std::int32_t i, std::int32_t j) {
            const Triangle<S> tb = mb.triangle(j);
            const Triangle<S> moved(xf.apply(tb.a), xf.apply(tb.b), xf.apply(tb.c));
            if (boxes_touch(ma.triangle(i), moved) && triangles_intersect_exact(ma.triangle(i), moved)) got.emplace_back(i, j);
            return true;
          });
      std::vector<std::pair<int, int>> expected;
      for (const auto& pr : brute_force_pairs(ma, RigidTransform<S>{}, mb, xf))
        if (present.count(pr.first)) expected.push_back(pr);
      std::sort(got.begin(), got.end());
      ASSERT_EQ(got, expected) << "round " << round << " pose " << pose;
      pairs_seen += expected.size();
    }
  }
  EXPECT_GT(pairs_seen, 10u);  // the poses make contacts
  // remove everything: empty, then usable again
  for (int id : std::vector<int>(present.begin(), present.end())) a.remove(id);
  EXPECT_TRUE(a.empty());
  EXPECT_EQ(a.root(), a.null);
  EXPECT_TRUE(a.to_bvh().empty());
  a.insert(3, ma.triangle(3));
  std::size_t depth = 0;
  EXPECT_EQ(check_pool(a, ma, depth), std::multiset<int>{3});
  }
}

// Coincident triangles (every box equal: every sibling costs the same) build a balanced tree,
// slivers and very unequal sizes a shallow one; every primitive stays once.
TYPED_TEST(IncrementalBvhTest, DegenerateInputBuildsABalancedTree) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  TriangleMesh<S> same;
  same.V.resize(3, 3);
  same.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  same.F.resize(256, 3);
  for (int t = 0; t < 256; ++t) same.F.row(t) << 0, 1, 2;
  for (SiblingSearch search : {SiblingSearch::Greedy, SiblingSearch::BranchAndBound}) {
  IncrementalBvh<BV> a(search);
  for (int t = 0; t < 256; ++t) a.insert(t, same.triangle(t));
  std::size_t depth = 0;
  EXPECT_EQ(check_pool(a, same, depth).size(), 256u);
  EXPECT_EQ(depth, 8u);  // log2 256: ties go to the smaller subtree
  // remove every other one and insert them back: still balanced within one level
  for (int t = 0; t < 256; t += 2) a.remove(t);
  for (int t = 0; t < 256; t += 2) a.insert(t, same.triangle(t));
  EXPECT_EQ(check_pool(a, same, depth).size(), 256u);
  EXPECT_LE(depth, 9u);
  }
  std::size_t depth = 0;

  // slivers (needles along x at random heights) and very unequal sizes (1e-4 to 10)
  Rng rng(3);
  TriangleMesh<S> mixed;
  const int n = 400;
  mixed.V.resize(3 * n, 3);
  mixed.F.resize(n, 3);
  for (int t = 0; t < n; ++t) {
    const Eigen::Vector3d c = rng.vec(-1, 1);
    Eigen::Vector3d e0, e1;
    if (t % 2 == 0) {
      e0 = Eigen::Vector3d(2.0, 0, 0);
      e1 = Eigen::Vector3d(1.0, 1e-7, 0);
    } else {
      const double size = std::pow(10.0, rng.uniform(-4, 1));
      e0 = rng.vec(-size, size);
      e1 = rng.vec(-size, size);
    }
    mixed.V.row(3 * t) = c.cast<S>().transpose();
    mixed.V.row(3 * t + 1) = (c + e0).cast<S>().transpose();
    mixed.V.row(3 * t + 2) = (c + e1).cast<S>().transpose();
    mixed.F.row(t) << 3 * t, 3 * t + 1, 3 * t + 2;
  }
  IncrementalBvh<BV> b;
  for (int t = 0; t < n; ++t) b.insert(t, mixed.triangle(t));
  const auto ids = check_pool(b, mixed, depth);
  EXPECT_EQ(ids.size(), std::size_t(n));
  EXPECT_EQ(std::set<int>(ids.begin(), ids.end()).size(), std::size_t(n));
  EXPECT_LE(depth, 40u);
  ASSERT_EQ(check_flat(b.to_bvh(), mixed).size(), std::size_t(n));
}

// The sibling choice minimises the surface-area cost: on a random soup, inserted in random order
// and sorted along x (coherent input, as a scanned mesh's file order), the cost stays near a
// top-down SAH build's; rotations lower the cost of the sorted order by a tenth at least.
TEST(IncrementalBvhQuality, SurfaceAreaCostNearTopDownSah) {
  auto m = random_soup<double>(2000, 41, 1.0, 0.05);
  std::vector<Vec3<double>> centroids;
  std::vector<Aabb<double>> boxes;
  for (int t = 0; t < m.num_triangles(); ++t) {
    const auto tri = m.triangle(t);
    centroids.push_back(tri.centroid());
    boxes.emplace_back(tri.a.cwiseMin(tri.b).cwiseMin(tri.c), tri.a.cwiseMax(tri.b).cwiseMax(tri.c));
  }
  const auto fit = [&](const std::int32_t* ids, std::size_t k) {
    Aabb<double> b;
    for (std::size_t i = 0; i < k; ++i) b.extend(boxes[static_cast<std::size_t>(ids[i])]);
    return b;
  };
  const auto cost = [](const Bvh<Aabb<double>>& t) {
    double c = 0;
    for (const auto& n : t.nodes)
      if (!n.is_leaf()) c += detail::half_area(n.bv);
    return c;
  };
  BuildConfig sah;
  sah.split = SplitRule::Sah;
  const double td_cost = cost(build_top_down<Aabb<double>>(centroids, fit, sah, boxes));
  std::vector<std::int32_t> sorted_ids(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) sorted_ids[i] = std::int32_t(i);
  std::sort(sorted_ids.begin(), sorted_ids.end(), [&](std::int32_t x, std::int32_t y) { return centroids[std::size_t(x)][0] < centroids[std::size_t(y)][0]; });
  double sorted_with_rotations = 0, sorted_without = 0;  // branch and bound (the last with rotations)
  for (const auto& [search, rot, random_bound, sorted_bound] :
       {std::tuple{SiblingSearch::Greedy, true, 1.3, 1.3}, std::tuple{SiblingSearch::BranchAndBound, true, 1.2, 1.2},
        std::tuple{SiblingSearch::BranchAndBound, false, 1.2, 1.5}}) {
    SCOPED_TRACE(std::string(search == SiblingSearch::Greedy ? "greedy" : "branch and bound") + (rot ? " + rotations" : ""));
    IncrementalBvh<Aabb<double>> random_order(search, rot), sorted_order(search, rot);
    for (std::size_t i = 0; i < boxes.size(); ++i) random_order.insert(std::int32_t(i), boxes[i], boxes[i]);  // the soup is random
    for (std::int32_t i : sorted_ids) sorted_order.insert(i, boxes[std::size_t(i)], boxes[std::size_t(i)]);
    const double r_random = random_order.sah_cost() / td_cost, r_sorted = sorted_order.sah_cost() / td_cost;
    EXPECT_LT(r_random, random_bound);
    EXPECT_GT(r_random, 0.8);
    EXPECT_LT(r_sorted, sorted_bound);
    std::printf("%s rot %d: cost / top-down SAH: random order %.3f, sorted %.3f; depth %zu, %zu\n",
                search == SiblingSearch::Greedy ? "greedy" : "b&b", int(rot), r_random, r_sorted,
                bvh_stats(random_order.to_bvh()).max_depth, bvh_stats(sorted_order.to_bvh()).max_depth);
    (rot ? sorted_with_rotations : sorted_without) = r_sorted;
    // the flat copy fitted by build_incremental is the same tree: same inner-node cost
    BuildConfig cfg;
    cfg.method = BuildMethod::Incremental;
    cfg.sibling_search = search;
    cfg.rotations = rot;
    EXPECT_NEAR(cost(build_incremental<Aabb<double>>(centroids, boxes, fit, cfg)), random_order.sah_cost(), 1e-12 * td_cost);
  }
  EXPECT_LT(sorted_with_rotations, 0.9 * sorted_without);  // rotations repair coherent insertion orders
}

// MeshBvh with BuildMethod::Incremental: every query of the library runs on it; leaf sizes above
// one collapse small subtrees.
TEST(IncrementalBvhMesh, MeshBvhQueriesMatchBruteForce) {
  const auto ma = random_soup<double>(300, 51, 1.0, 0.12);
  const auto mb = random_soup<double>(200, 52, 1.0, 0.12);
  for (int leaf : {1, 4}) {
    MeshBvhConfig cfg;
    cfg.build.method = BuildMethod::Incremental;
    cfg.build.leaf_size = leaf;
    const MeshBvh<Aabb<double>> a(ma, cfg), b(mb, cfg);
    for (const auto& n : a.tree().nodes)
      if (n.is_leaf()) {
        EXPECT_LE(n.count, leaf);
      }
    Rng rng(8);
    for (int pose = 0; pose < 10; ++pose) {
      const RigidTransform<double> pb = random_pose(rng, Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
      CollideOptions opt;
      opt.all_pairs = true;
      EXPECT_EQ(sorted(collide(a, RigidTransform<double>{}, b, pb, opt).pairs), brute_force_pairs(ma, RigidTransform<double>{}, mb, pb));
    }
  }
}

// Bad input throws with a reason and leaves the tree as it was.
TEST(IncrementalBvhInput, BadInputThrowsAndChangesNothing) {
  const auto m = random_soup<double>(10, 61);
  IncrementalBvh<Sphere<double>> t;
  for (int i = 0; i < 10; ++i) t.insert(i, m.triangle(i));
  const auto before = t.to_bvh();
  auto expect_throw = [&](auto&& f, const std::string& needle) {
    try {
      f();
      ADD_FAILURE() << "no exception for " << needle;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_EQ(t.size(), 10u);
    const auto after = t.to_bvh();
    ASSERT_EQ(after.primitives, before.primitives);
    ASSERT_EQ(after.nodes.size(), before.nodes.size());
  };
  expect_throw([&] { t.insert(3, m.triangle(3)); }, "already");
  expect_throw([&] { t.insert(-1, m.triangle(3)); }, ">= 0");
  expect_throw([&] { t.remove(11); }, "not in the tree");
  expect_throw([&] { t.remove(-2); }, "not in the tree");
  Triangle<double> bad = m.triangle(0);
  bad.b[1] = std::numeric_limits<double>::quiet_NaN();
  expect_throw([&] { t.insert(20, bad); }, "NaN");
  expect_throw([&] { t.insert(20, Sphere<double>(), Aabb<double>()); }, "not empty");
  EXPECT_FALSE(t.contains(20));
  const std::vector<Vec3<double>> c(3, Vec3<double>::Zero());
  const std::vector<Aabb<double>> boxes(2);
  EXPECT_THROW(build_incremental<Sphere<double>>(c, boxes, [](const std::int32_t*, std::size_t) { return Sphere<double>(); }), InvalidInput);
}
