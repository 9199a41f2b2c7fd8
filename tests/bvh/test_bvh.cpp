// SPDX-License-Identifier: MIT
// The hierarchy: structural invariants of the top-down build (every triangle in exactly one leaf,
// leaf sizes, each node's BV holds all its triangles' vertices, an AABB node's box is exactly
// theirs), termination on degenerate input,
// refit after deformation, and the traversals against brute force: pair traversal under random
// rigid poses and self traversal report exactly the brute-force triangle pairs. Sphere, AABB and
// oriented box, float and double, every split rule (middle, median, SAH) and construction (top-down,
// bottom-up, incremental). The traversal stack keeps its order past its fixed slots.
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/node_layout.hpp"
#include "impact/bvh/traversal_stack.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/meshes.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <type_traits>

using namespace impact;
using namespace impact::test;

namespace {

template <class BV> struct Case {
  using Bv = BV;
};

/// Checks that node i's BV holds every vertex of every triangle below it; returns the triangle count.
template <class BV> std::int32_t check_node(const MeshBvh<BV>& m, std::int32_t i, std::vector<int>& seen, int leaf_size, int& leaves) {
  using S = typename BvTraits<BV>::Scalar;
  const auto& tree = m.tree();
  const auto& node = tree.nodes[static_cast<std::size_t>(i)];
  std::vector<std::int32_t> prims;
  // collect primitives below i
  {
    std::vector<std::int32_t> stack{i};
    while (!stack.empty()) {
      auto k = stack.back();
      stack.pop_back();
      const auto& n = tree.nodes[static_cast<std::size_t>(k)];
      if (n.is_leaf())
        for (auto p = n.first; p < n.first + n.count; ++p) prims.push_back(tree.primitives[static_cast<std::size_t>(p)]);
      else
        stack.push_back(n.left()), stack.push_back(n.right());
    }
  }
  const S slack = S(1e-5) * (std::is_same_v<S, float> ? S(10) : S(1e-6));
  Aabb<S> tight;  // the box of the triangles below: an AABB node's box is exactly this (every builder)
  for (auto p : prims)
    for (int v = 0; v < 3; ++v) tight.extend(m.triangle(p)[v]);
  if constexpr (std::is_same_v<BV, Aabb<S>>) {
    EXPECT_EQ(node.bv.min, tight.min) << "node " << i;
    EXPECT_EQ(node.bv.max, tight.max) << "node " << i;
  }
  for (auto p : prims) {
    const Triangle<S>& t = m.triangle(p);
    for (int v = 0; v < 3; ++v) {
      const Vec3<S> x = t[v];
      if constexpr (std::is_same_v<BV, Sphere<S>>) {
        EXPECT_LE((x - node.bv.center).norm(), node.bv.radius + slack);
      } else if constexpr (std::is_same_v<BV, Obb<S>>) {
        const Eigen::Vector3d h = node.bv.axes.template cast<double>().fullPivLu().solve((x - node.bv.center).template cast<double>());
        EXPECT_TRUE((h.cwiseAbs().array() <= node.bv.half.template cast<double>().array()).all());
      } else {
        EXPECT_TRUE(node.bv.contains(x));
      }
    }
  }
  if (node.is_leaf()) {
    ++leaves;
    // larger leaves hold copies of one triangle only (the top-down build gathers them)
    if (node.count > leaf_size) {
      for (auto p = node.first + 1; p < node.first + node.count; ++p)
        EXPECT_TRUE(test::same_shape(m.triangle(p), m.triangle(node.first))) << "leaf " << i << " of " << node.count;
    }
    for (auto p = node.first; p < node.first + node.count; ++p) ++seen[static_cast<std::size_t>(tree.primitives[static_cast<std::size_t>(p)])];
  } else {
    EXPECT_GT(node.left(), i);
    check_node(m, node.left(), seen, leaf_size, leaves);
    check_node(m, node.right(), seen, leaf_size, leaves);
  }
  return static_cast<std::int32_t>(prims.size());
}

}  // namespace

template <class BV> class BvhTest : public ::testing::Test {};
using BvTypes = ::testing::Types<Sphere<float>, Sphere<double>, Aabb<float>, Aabb<double>, Obb<float>, Obb<double>>;
TYPED_TEST_SUITE(BvhTest, BvTypes);

TYPED_TEST(BvhTest, BuildInvariants) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const auto mesh = random_soup<S>(500, 1);
  for (SplitRule rule : {SplitRule::SpatialMiddle, SplitRule::CentroidMedian, SplitRule::Sah}) {
    for (int leaf : {1, 2, 4, 8}) {
      for (BuildMethod method : {BuildMethod::TopDown, BuildMethod::BottomUp, BuildMethod::Incremental}) {
        if (method != BuildMethod::TopDown && rule != SplitRule::SpatialMiddle) continue;  // the split rule is top-down's
        if (method == BuildMethod::Incremental && (leaf == 2 || leaf == 8)) continue;       // (time under ASan)
        MeshBvhConfig cfg;
        cfg.build.split = rule;
        cfg.build.method = method;
        cfg.build.leaf_size = leaf;
        MeshBvh<BV> m(mesh, cfg);
        std::vector<int> seen(static_cast<std::size_t>(m.num_triangles()), 0);
        int leaves = 0;
        EXPECT_EQ(check_node(m, 0, seen, leaf, leaves), 500);
        for (int s : seen) ASSERT_EQ(s, 1);
        EXPECT_EQ(static_cast<std::size_t>(2 * leaves - 1), m.tree().nodes.size());
        // leaf positions map back to distinct rows of F
        std::vector<int> rows(500, 0);
        for (std::int32_t k = 0; k < 500; ++k) ++rows[static_cast<std::size_t>(m.triangle_id(k))];
        for (int r : rows) ASSERT_EQ(r, 1);
      }
    }
  }
}

TYPED_TEST(BvhTest, DegenerateSplitsTerminate) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  // 64 copies of one triangle: all centroids equal
  TriangleMesh<S> m;
  m.V.resize(3, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  m.F.resize(64, 3);
  for (int t = 0; t < 64; ++t) m.F.row(t) << 0, 1, 2;
  // top-down: copies of one triangle are gathered in one leaf (no cut by centroids can separate
  // them), each marked as repeating the one before it
  MeshBvh<BV> tree(m);
  EXPECT_EQ(bvh_stats(tree.tree()).leaves, 1u);
  EXPECT_EQ(tree.tree().nodes[0].count, 64);
  EXPECT_FALSE(tree.repeats_previous(0));
  for (std::int32_t k = 1; k < 64; ++k) EXPECT_TRUE(tree.repeats_previous(k)) << k;
  // bottom-up: equal primitives pair up, so the tree is balanced (depth log2 64)
  MeshBvhConfig bottom_up;
  bottom_up.build.method = BuildMethod::BottomUp;
  const MeshBvh<BV> bu(m, bottom_up);
  EXPECT_EQ(bvh_stats(bu.tree()).leaves, 64u);
  EXPECT_EQ(bvh_stats(bu.tree()).max_depth, 6u);
  // incremental: ties go to the smaller subtree, balanced too
  MeshBvhConfig incremental;
  incremental.build.method = BuildMethod::Incremental;
  const MeshBvh<BV> inc(m, incremental);
  EXPECT_EQ(bvh_stats(inc.tree()).leaves, 64u);
  EXPECT_EQ(bvh_stats(inc.tree()).max_depth, 6u);
  // zero-area triangles (all three vertices equal) are allowed
  TriangleMesh<S> z;
  z.V = Vertices<S>::Zero(1, 3);
  z.F = Faces::Zero(10, 3);
  MeshBvh<BV> zt(z);
  EXPECT_EQ(bvh_stats(zt.tree()).leaves, 1u);
  EXPECT_TRUE(collides(zt, RigidTransform<S>{}, tree, RigidTransform<S>{}));
  // two shapes with exactly the same centroid (1, 1, 0), 30 copies each in three vertex orders,
  // interleaved: the range is cut between the shapes, each shape one leaf, its copies sorted by
  // vertex order (one run per order: 30 - 3 marked per shape)
  TriangleMesh<S> two;
  two.V.resize(6, 3);
  two.V << 0, 0, 0, 3, 0, 0, 0, 3, 0, 2, 2, 0, 1, -1, 0, 0, 2, 0;
  two.F.resize(60, 3);
  for (int t = 0; t < 60; ++t) {
    const int b = t % 2 ? 3 : 0, r = (t / 2) % 3;
    two.F.row(t) << b + r, b + (r + 1) % 3, b + (r + 2) % 3;
  }
  const MeshBvh<BV> tt(two);
  EXPECT_EQ(bvh_stats(tt.tree()).leaves, 2u);
  int marked = 0;
  for (std::int32_t k = 0; k < 60; ++k) marked += tt.repeats_previous(k);
  EXPECT_EQ(marked, 54);
  std::vector<int> seen(60, 0);
  int leaves = 0;
  check_node(tt, 0, seen, 1, leaves);
}

// The default split resolves per BV (DefaultSplitRule): SAH for oriented boxes, the middle split
// for spheres and AABBs. A default-built tree equals, node for node, the tree of the rule named
// explicitly, and differs from the other rule's on this mesh (so the comparison can fail).
TYPED_TEST(BvhTest, DefaultSplitIsTheBvsOwn) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  constexpr SplitRule expected = std::is_same_v<BV, Obb<S>> ? SplitRule::Sah : SplitRule::SpatialMiddle;
  static_assert(resolve_split_rule<BV>(SplitRule::Default) == expected);
  static_assert(resolve_split_rule<BV>(SplitRule::CentroidMedian) == SplitRule::CentroidMedian);
  EXPECT_EQ(BuildConfig{}.split, SplitRule::Default);
  const auto m = random_soup<S>(300, 11, 1.0, 0.12);
  MeshBvhConfig named, other;
  named.build.split = expected;
  other.build.split = expected == SplitRule::Sah ? SplitRule::SpatialMiddle : SplitRule::Sah;
  const MeshBvh<BV> by_default(m), by_name(m, named), by_other(m, other);
  const auto same_tree = [&](const MeshBvh<BV>& x, const MeshBvh<BV>& y) {
    if (x.tree().nodes.size() != y.tree().nodes.size()) return false;
    for (std::size_t i = 0; i < x.tree().nodes.size(); ++i) {
      const auto &p = x.tree().nodes[i], &q = y.tree().nodes[i];
      if (p.first != q.first || p.count != q.count || BvTraits<BV>::center(p.bv) != BvTraits<BV>::center(q.bv)) return false;
    }
    for (std::int32_t k = 0; k < x.num_triangles(); ++k)
      if (x.triangle_id(k) != y.triangle_id(k)) return false;
    return true;
  };
  EXPECT_TRUE(same_tree(by_default, by_name));
  EXPECT_FALSE(same_tree(by_default, by_other));
}

TYPED_TEST(BvhTest, PairTraversalMatchesBruteForce) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  const auto ma = random_soup<S>(300, 11, 1.0, 0.12);
  const auto mb = random_soup<S>(200, 12, 1.0, 0.12);
  MeshBvh<BV> a(ma), b(mb);
  MeshBvhConfig sah;  // the split rule that is not the BV's default (middle for OBB trees, SAH otherwise)
  sah.build.split = resolve_split_rule<BV>(SplitRule::Default) == SplitRule::Sah ? SplitRule::SpatialMiddle : SplitRule::Sah;
  MeshBvh<BV> a_sah(ma, sah), b_sah(mb, sah);
  MeshBvhConfig bottom_up;
  bottom_up.build.method = BuildMethod::BottomUp;
  MeshBvh<BV> a_bu(ma, bottom_up), b_bu(mb, bottom_up);
  MeshBvhConfig incremental;
  incremental.build.method = BuildMethod::Incremental;
  MeshBvh<BV> a_inc(ma, incremental), b_inc(mb, incremental);
  Rng rng(99);
  int colliding = 0;
  for (int pose = 0; pose < 30; ++pose) {
    const RigidTransform<S> pa = random_pose(rng, Eigen::Vector3d::Constant(-1.0), Eigen::Vector3d::Constant(1.0)).template cast<S>();
    const RigidTransform<S> pb = random_pose(rng, Eigen::Vector3d::Constant(-1.8), Eigen::Vector3d::Constant(1.8)).template cast<S>();
    const auto expected = brute_force_pairs(ma, pa, mb, pb);
    CollideOptions opt;
    opt.all_pairs = true;
    const auto got = collide(a, pa, b, pb, opt);
    ASSERT_EQ(sorted(got.pairs), expected) << "pose " << pose;
    ASSERT_EQ(sorted(collide(a_sah, pa, b_sah, pb, opt).pairs), expected) << "pose " << pose << " (the other split)";
    ASSERT_EQ(sorted(collide(a_bu, pa, b_bu, pb, opt).pairs), expected) << "pose " << pose << " (bottom-up)";
    ASSERT_EQ(sorted(collide(a_inc, pa, b_inc, pb, opt).pairs), expected) << "pose " << pose << " (incremental)";
    EXPECT_EQ(got.colliding, !expected.empty());
    EXPECT_EQ(collides(a, pa, b, pb), !expected.empty());
    colliding += !expected.empty();
  }
  EXPECT_GT(colliding, 5);  // the poses exercise both answers
  EXPECT_LT(colliding, 30);
}

TYPED_TEST(BvhTest, SelfTraversalMatchesBruteForce) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  for (int leaf : {1, 3}) {
    auto mesh = random_soup<S>(400, 5, 1.0, 0.15);
    // share some vertices so adjacency exclusion is exercised
    for (int t = 1; t < 400; t += 7) mesh.F(t, 0) = mesh.F(t - 1, 1);
    MeshBvhConfig cfg;
    cfg.build.leaf_size = leaf;
    MeshBvh<BV> m(mesh, cfg);
    CollideOptions opt;
    opt.all_pairs = true;
    const auto got = self_collide(m, opt);
    const auto expected = brute_force_self_pairs(mesh);
    ASSERT_FALSE(expected.empty());
    EXPECT_EQ(sorted(got.pairs), expected);
  }
}

TYPED_TEST(BvhTest, RefitFollowsDeformation) {
  using BV = TypeParam;
  using S = typename BvTraits<BV>::Scalar;
  auto mesh = random_soup<S>(300, 21, 1.0, 0.1);
  auto other = random_soup<S>(300, 22, 1.0, 0.1);
  for (RefitMode mode : {RefitMode::Merge, RefitMode::Fit}) {
    MeshBvh<BV> a(mesh), b(other);
    Rng rng(5);
    for (int step = 0; step < 5; ++step) {
      Vertices<S> V = a.mesh().V;
      for (Eigen::Index i = 0; i < V.rows(); ++i) V.row(i) += (rng.vec(-0.05, 0.05) + Eigen::Vector3d(0.02, 0, 0)).cast<S>().transpose();
      a.set_vertices(V, mode);
      std::vector<int> seen(300, 0);
      int leaves = 0;
      check_node(a, 0, seen, 1, leaves);
      CollideOptions opt;
      opt.all_pairs = true;
      const TriangleMesh<S> moved(V, mesh.F);
      EXPECT_EQ(sorted(collide(a, RigidTransform<S>{}, b, RigidTransform<S>{}, opt).pairs),
                brute_force_pairs(moved, RigidTransform<S>{}, other, RigidTransform<S>{}));
    }
  }
}

TEST(MeshBvhInput, BadInputThrowsWithReason) {
  Vertices<double> V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  Faces F(1, 3);
  F << 0, 1, 2;
  EXPECT_NO_THROW(MeshBvh<Sphere<double>>(V, F));
  auto expect_throw = [](const Vertices<double>& v, const Faces& f, const std::string& needle) {
    try {
      MeshBvh<Sphere<double>> m(v, f);
      ADD_FAILURE() << "no exception for " << needle;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  Vertices<double> nan = V;
  nan(1, 2) = std::numeric_limits<double>::quiet_NaN();
  expect_throw(nan, F, "vertex 1");
  Vertices<double> inf = V;
  inf(2, 0) = -std::numeric_limits<double>::infinity();
  expect_throw(inf, F, "NaN or infinite");
  Faces out = F;
  out(0, 2) = 3;
  expect_throw(V, out, "index 3");
  Faces neg = F;
  neg(0, 0) = -1;
  expect_throw(V, neg, "index -1");
  expect_throw(V, Faces(0, 3), "empty");
  expect_throw(Vertices<double>(0, 3), F, "empty");
  // set_vertices validates too, and leaves the model usable
  MeshBvh<Sphere<double>> m(V, F);
  EXPECT_THROW(m.set_vertices(nan), InvalidInput);
  EXPECT_THROW(m.set_vertices(Vertices<double>::Zero(5, 3)), InvalidInput);
  EXPECT_TRUE(all_finite(m.mesh().V));
}

TEST(BvhMeshBvh, RevisionChangesWithEveryEditAndFollowsCopies) {
  // the stamp the particles' free-ball cache reads to see set_vertices() at the same address
  const auto mesh = random_soup<double>(20, 5);
  MeshBvh<Aabb<double>> a(mesh);
  const MeshBvh<Aabb<double>> b(mesh);
  EXPECT_NE(a.revision(), 0u);
  EXPECT_NE(a.revision(), b.revision());  // two constructions of the same mesh: two stamps
  const std::uint64_t r0 = a.revision();
  a.set_vertices(mesh.V * 2.0);
  const std::uint64_t r1 = a.revision();
  EXPECT_NE(r1, r0);
  EXPECT_NE(r1, b.revision());
  a.set_vertices(mesh.V);  // the old coordinates again: still a new stamp (no content comparison)
  EXPECT_NE(a.revision(), r1);
  EXPECT_NE(a.revision(), r0);
  const MeshBvh<Aabb<double>> c = a;  // a copy holds the same contents
  EXPECT_EQ(c.revision(), a.revision());
  a = b;
  EXPECT_EQ(a.revision(), b.revision());
  // a failed edit leaves the stamp (and the tree) as they were
  Vertices<double> nan = mesh.V;
  nan(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(a.set_vertices(nan), InvalidInput);
  EXPECT_EQ(a.revision(), b.revision());
}

TEST(BvhSingleTree, TraverseVisitsExactlyTheOverlappingPrimitives) {
  const auto mesh = random_soup<double>(1000, 3);
  MeshBvh<Sphere<double>> m(mesh);
  const Sphere<double> probe(Eigen::Vector3d(0.2, -0.1, 0.3), 0.4);
  std::vector<int> got;
  traverse(
      m.tree(), [&](const Sphere<double>& s) { return overlap(s, probe); },
      [&](std::int32_t k) {
        const auto& t = m.triangle(k);
        if ((t.centroid() - probe.center).norm() <= probe.radius) got.push_back(m.triangle_id(k));
        return true;
      });
  std::vector<int> expected;
  for (int t = 0; t < mesh.num_triangles(); ++t)
    if ((mesh.triangle(t).centroid() - probe.center).norm() <= probe.radius) expected.push_back(t);
  EXPECT_EQ(sorted(got), expected);
  EXPECT_FALSE(expected.empty());
}

// The traversal stack is LIFO across its fixed slots and its heap overflow, for plain and pair
// entries, through repeated fill and drain.
TEST(TraversalStack, LifoAcrossTheOverflow) {
  detail::TraversalStack<std::pair<double, std::int32_t>, 4> stack;
  for (int round = 0; round < 3; ++round) {
    EXPECT_TRUE(stack.empty());
    const int n = 3 + 5 * round;  // below, then well beyond the 4 fixed slots
    for (int i = 0; i < n; ++i) stack.push({0.5 * i, i});
    for (int i = n - 1; i >= 0; --i) {
      ASSERT_FALSE(stack.empty());
      const auto [key, node] = stack.pop();
      EXPECT_EQ(node, i);
      EXPECT_EQ(key, 0.5 * i);
    }
    EXPECT_TRUE(stack.empty());
  }
}

// Without an overflow (StackOverflow::None, the wide ray cast's stack) the stack is LIFO over
// its N slots, filled to the last one, through repeated fill and drain.
TEST(TraversalStack, FixedModeIsLifoToItsCapacity) {
  detail::TraversalStack<std::pair<float, std::int32_t>, 6, detail::StackOverflow::None> stack;
  for (int round = 0; round < 3; ++round) {
    EXPECT_TRUE(stack.empty());
    const int n = 2 + 2 * round;  // 2, 4, 6 = every slot
    for (int i = 0; i < n; ++i) stack.push({0.25f * float(i), 10 * i + round});
    for (int i = n - 1; i >= 0; --i) {
      ASSERT_FALSE(stack.empty());
      const auto [key, value] = stack.pop();
      EXPECT_EQ(value, 10 * i + round);
      EXPECT_EQ(key, 0.25f * float(i));
    }
    EXPECT_TRUE(stack.empty());
  }
}

// D14: a mesh's tree keeps nothing of its build (the fitting scratch is a local) and the sphere and
// AABB trees stay within 120 bytes per triangle beyond the mesh's own arrays (nodes, primitive
// permutation and triangle ids; the triangles are read from the mesh), before and after a refit.
template <class BV> void expect_tree_bytes_within(const TriangleMesh<typename BvTraits<BV>::Scalar>& m, double bound) {
  MeshBvh<BV> t(m);
  const double per_tri = double(t.tree_bytes()) / double(t.num_triangles());
  EXPECT_LE(per_tri, bound) << BvTraits<BV>::name;
  EXPECT_GT(per_tri, 8.0) << BvTraits<BV>::name;  // counts the nodes at least
  EXPECT_EQ(t.mesh_bytes(), std::size_t(m.V.size()) * sizeof(typename BvTraits<BV>::Scalar) + std::size_t(m.F.size()) * sizeof(int));
  EXPECT_EQ(t.memory_bytes(), t.mesh_bytes() + t.tree_bytes());
  const std::size_t before = t.tree_bytes();
  t.set_vertices(m.V * typename BvTraits<BV>::Scalar(2), RefitMode::Fit);
  EXPECT_EQ(t.tree_bytes(), before) << BvTraits<BV>::name;
}

TEST(MeshBvhMemory, SphereAndAabbTreesWithin120BytesPerTriangle) {
  const auto m = random_soup<double>(3000, 91);
  expect_tree_bytes_within<Sphere<double>>(m, 120);
  expect_tree_bytes_within<Aabb<double>>(m, 120);
  const auto mf = random_soup<float>(3000, 92);
  expect_tree_bytes_within<Sphere<float>>(mf, 120);
  expect_tree_bytes_within<Aabb<float>>(mf, 120);
}

// The node layout (bvh/node_layout.hpp): a mesh's tree is stored in treelets. From every node at a
// depth that is a multiple of L (the root, and the nodes L, 2L, ... levels below it), the nodes 1
// to L levels below it fill one contiguous block of the node array, level by level. The builders'
// depth-first order does not: there a right child's descendants follow the whole left subtree.
template <class BV> void expect_treelets(const MeshBvh<BV>& m) {
  const auto& nodes = m.tree().nodes;
  const int levels = treelet_levels(sizeof(BvhNode<BV>));
  std::vector<int> depth(nodes.size(), 0);
  for (std::size_t k = 0; k < nodes.size(); ++k)
    if (!nodes[k].is_leaf()) depth[static_cast<std::size_t>(nodes[k].left())] = depth[static_cast<std::size_t>(nodes[k].right())] = depth[k] + 1;
  int treelets = 0;
  for (std::size_t r = 0; r < nodes.size(); ++r) {
    if (nodes[r].is_leaf() || depth[r] % levels != 0) continue;
    ++treelets;
    std::vector<std::int32_t> level{static_cast<std::int32_t>(r)}, below;
    for (int d = 0; d < levels; ++d) {
      std::vector<std::int32_t> next;
      for (std::int32_t k : level)
        if (!nodes[static_cast<std::size_t>(k)].is_leaf()) next.insert(next.end(), {nodes[static_cast<std::size_t>(k)].left(), nodes[static_cast<std::size_t>(k)].right()});
      below.insert(below.end(), next.begin(), next.end());
      level = next;
    }
    // the block: exactly the indices first child .. first child + count - 1, in level order
    for (std::size_t k = 0; k < below.size(); ++k)
      ASSERT_EQ(below[k], nodes[r].left() + static_cast<std::int32_t>(k)) << "treelet at node " << r << ", depth " << depth[r];
  }
  EXPECT_GT(treelets, 10);
}

TEST(BvhNodeLayout, MeshTreesAreStoredInPageSizedTreelets) {
  static_assert(treelet_levels(136) == 4 && treelet_levels(56) == 5 && treelet_levels(40) == 5 && treelet_levels(4096) == 1);
  const auto md = random_soup<double>(1500, 93);
  const auto mf = random_soup<float>(1500, 94);
  expect_treelets(MeshBvh<Obb<double>>(md));
  expect_treelets(MeshBvh<Aabb<double>>(md));
  expect_treelets(MeshBvh<Sphere<float>>(mf));
  MeshBvhConfig cfg;
  cfg.build.method = BuildMethod::BottomUp;
  expect_treelets(MeshBvh<Obb<float>>(mf, cfg));
}

// Renumbering keeps the tree: from the root down, the same BVs bit for bit, the same children (left
// and right), the same leaf ranges, whatever the treelet height.
template <class BV> void expect_same_tree(const Bvh<BV>& x, std::int32_t i, const Bvh<BV>& y, std::int32_t j, int& nodes) {
  const auto& a = x.nodes[static_cast<std::size_t>(i)];
  const auto& b = y.nodes[static_cast<std::size_t>(j)];
  ++nodes;
  ASSERT_EQ(std::memcmp(&a.bv, &b.bv, sizeof(BV)), 0) << "node " << i << " / " << j;
  ASSERT_EQ(a.count, b.count);
  if (a.is_leaf()) {
    ASSERT_EQ(a.first, b.first);
    return;
  }
  ASSERT_GT(b.left(), j);  // children after their parent
  expect_same_tree(x, a.left(), y, b.left(), nodes);
  expect_same_tree(x, a.right(), y, b.right(), nodes);
}

TEST(BvhNodeLayout, RenumberingKeepsTheTree) {
  const auto md = random_soup<double>(1000, 95);
  for (int leaf : {1, 3}) {
    MeshBvhConfig cfg;
    cfg.build.leaf_size = leaf;
    const MeshBvh<Obb<double>> m(md, cfg);
    const MeshBvh<Aabb<double>> ma(md, cfg);
    for (int levels : {1, 2, 3, 7}) {
      Bvh<Obb<double>> t = m.tree();
      lay_out_in_treelets(t, levels);
      int n = 0;
      expect_same_tree(m.tree(), 0, t, 0, n);
      EXPECT_EQ(static_cast<std::size_t>(n), t.nodes.size());
      Bvh<Aabb<double>> ta = ma.tree();
      lay_out_in_treelets(ta, levels);
      n = 0;
      expect_same_tree(ma.tree(), 0, ta, 0, n);
      EXPECT_EQ(static_cast<std::size_t>(n), ta.nodes.size());
    }
  }
}
