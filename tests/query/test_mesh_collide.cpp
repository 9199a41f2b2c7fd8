// SPDX-License-Identifier: MIT
// Mesh–mesh queries beyond the FCL cross-check: contact information lies on both triangles,
// answers do not depend on the common frame, boolean and all-pairs agree, max_pairs and the
// counters behave, self-collision finds exactly the non-adjacent intersecting pairs (none on a
// clean closed mesh), and float agrees with double away from touching.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/meshes.hpp"
#include "support/poses.hpp"

#include <gtest/gtest.h>

using namespace impact;
using namespace impact::test;

namespace {
double dist_to_triangle(const Eigen::Vector3d& p, const Triangle<double>& t) {
  return (closest_point_on_triangle(p, t).point - p).norm();
}
}  // namespace

TEST(MeshCollide, ContactsLieOnBothTriangles) {
  const auto A = make_torus<double>(1.0, 0.3, 48, 24), B = make_icosphere<double>(0.7, 3);
  MeshBvh<Sphere<double>> a(A), b(B);
  CollideOptions opt;
  opt.all_pairs = true;
  opt.contacts = true;
  int checked = 0;
  for (const auto& p : random_poses_around(A, B, 40, 3)) {
    const RigidTransform<double> pose_a(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix(),
                                        Eigen::Vector3d(5, -2, 1));
    const RigidTransform<double> pose_b = pose_a * p;
    const auto r = collide(a, pose_a, b, pose_b, opt);
    ASSERT_EQ(r.contacts.size(), r.pairs.size());
    for (const auto& c : r.contacts) {
      const Triangle<double> ta = A.triangle(c.triangle_a), tb = B.triangle(c.triangle_b);
      const Triangle<double> wa(pose_a.apply(ta.a), pose_a.apply(ta.b), pose_a.apply(ta.c));
      const Triangle<double> wb(pose_b.apply(tb.a), pose_b.apply(tb.b), pose_b.apply(tb.c));
      EXPECT_LT(dist_to_triangle(c.point, wa), 1e-9);
      EXPECT_LT(dist_to_triangle(c.point, wb), 1e-9);
      EXPECT_NEAR(c.normal_a.norm(), 1.0, 1e-12);
      EXPECT_NEAR(c.normal_a.dot(wa.normal()), 1.0, 1e-9);
      EXPECT_NEAR(c.normal_b.dot(wb.normal()), 1.0, 1e-9);
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

TEST(MeshCollide, FrameIndependentAndModesAgree) {
  const auto A = random_soup<double>(400, 31, 1.0, 0.15), B = random_soup<double>(300, 32, 1.0, 0.15);
  MeshBvh<Sphere<double>> a(A), b(B);
  MeshBvh<Aabb<double>> a2(A), b2(B);
  Rng rng(8);
  CollideOptions all;
  all.all_pairs = true;
  for (const auto& p : random_poses_around(A, B, 50, 4)) {
    const RigidTransform<double> common = random_pose(rng, Eigen::Vector3d::Constant(-100), Eigen::Vector3d::Constant(100));
    const auto base = collide(a, RigidTransform<double>{}, b, p, all);
    const auto moved = collide(a, common, b, common * p, all);
    EXPECT_EQ(sorted(base.pairs).size(), sorted(moved.pairs).size());
    EXPECT_EQ(base.colliding, collides(a, RigidTransform<double>{}, b, p));
    EXPECT_EQ(base.colliding, collide(a, RigidTransform<double>{}, b, p).colliding);
    EXPECT_EQ(sorted(base.pairs), sorted(collide(a2, RigidTransform<double>{}, b2, p, all).pairs));
    // boolean mode reports one pair that is in the full set
    const auto one = collide(a, RigidTransform<double>{}, b, p);
    if (one.colliding) {
      ASSERT_EQ(one.pairs.size(), 1u);
      EXPECT_NE(std::find(base.pairs.begin(), base.pairs.end(), one.pairs[0]), base.pairs.end());
      EXPECT_LE(one.stats.primitive_tests, base.stats.primitive_tests);
    }
    if (base.pairs.size() > 3) {
      CollideOptions capped = all;
      capped.max_pairs = 3;
      EXPECT_EQ(collide(a, RigidTransform<double>{}, b, p, capped).pairs.size(), 3u);
    }
  }
}

TEST(MeshCollide, CountersCountWork) {
  const auto A = random_soup<double>(200, 41), B = random_soup<double>(200, 42);
  MeshBvh<Sphere<double>> a(A), b(B);
  QueryStats st;
  // far apart: one BV test at the roots, no triangle tests
  EXPECT_FALSE(collides(a, RigidTransform<double>{}, b, RigidTransform<double>(Eigen::Matrix3d::Identity(), Eigen::Vector3d(100, 0, 0)), &st));
  EXPECT_EQ(st.bv_tests, 1u);
  EXPECT_EQ(st.primitive_tests, 0u);
}

TEST(MeshCollide, SelfCollisionOfCleanClosedMeshIsEmpty) {
  for (const auto& m : {make_torus<double>(1.0, 0.3, 64, 32), make_icosphere<double>(1.0, 4)}) {
    CollideOptions all;
    all.all_pairs = true;
    EXPECT_TRUE(self_collide(MeshBvh<Sphere<double>>(m), all).pairs.empty());
    EXPECT_TRUE(self_collide(MeshBvh<Aabb<double>>(m), all).pairs.empty());
  }
}

TEST(MeshCollide, SelfCollisionFindsFolds) {
  // one mesh made of two wavy sheets that pass through each other (no shared vertices)
  const auto sheet = make_grid<double>(16, 16, 2.0);
  TriangleMesh<double> g;
  const Eigen::Index nv = sheet.V.rows(), nf = sheet.F.rows();
  g.V.resize(2 * nv, 3);
  g.F.resize(2 * nf, 3);
  for (Eigen::Index i = 0; i < nv; ++i) {
    const double x = sheet.V(i, 0), y = sheet.V(i, 1);
    g.V.row(i) << x, y, 0.2 * std::sin(3 * x);
    g.V.row(nv + i) << x, 0.3 * std::cos(2 * y), y;  // a second sheet standing across the first
  }
  g.F.topRows(nf) = sheet.F;
  g.F.bottomRows(nf) = sheet.F.array() + int(nv);
  CollideOptions all;
  all.all_pairs = true;
  const auto expected = brute_force_self_pairs(g);
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(sorted(self_collide(MeshBvh<Sphere<double>>(g), all).pairs), expected);
  EXPECT_EQ(sorted(self_collide(MeshBvh<Aabb<double>>(g), all).pairs), expected);
  EXPECT_TRUE(self_collide(MeshBvh<Sphere<double>>(g)).colliding);
}

TEST(MeshCollide, LargeCoordinateOffsets) {
  // the same configuration far from the origin: relative transforms keep it well conditioned
  const auto A = make_torus<double>(1.0, 0.3, 48, 24), B = make_icosphere<double>(0.7, 3);
  MeshBvh<Sphere<double>> a(A), b(B);
  const RigidTransform<double> far(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1e6, -1e6, 1e6));
  int agree = 0, total = 0;
  for (const auto& p : random_poses_around(A, B, 100, 6)) {
    agree += collides(a, RigidTransform<double>{}, b, p) == collides(a, far, b, far * p);
    ++total;
  }
  // translating both by 1e6 perturbs B's relative pose by ~1e-10: only near-touching poses may flip
  EXPECT_GE(agree, total - 1);
}

// The boolean queries walk the child nearer the other node first (detail::NearestChildFirst).
// The walk order may change which colliding pair is found and how soon, never the answer. A walk
// that finds nothing visits the same node pairs in any order, so its node tests must be equal.
// On colliding poses the nearer-first walk should reach a colliding pair with clearly fewer node
// tests than the tree's order. A reversed comparison (the farther child first) fails this.
template <class BV> void expect_nearest_first_saves_work() {
  const auto A = make_torus<double>(1.0, 0.3, 96, 48), B = make_icosphere<double>(0.6, 4);
  const MeshBvh<BV> a(A), b(B);
  std::uint64_t nearest_hit = 0, tree_hit = 0;
  int hits = 0, misses = 0;
  for (const auto& p : random_poses_around(A, B, 300, 17)) {
    QueryStats st;
    const bool hit = collides(a, RigidTransform<double>{}, b, p, &st);
    std::uint64_t tree_tests = 0;
    bool tree_found = false;
    const detail::MeshNodeOverlap<BV> overlap(a, b, p, &tree_tests);
    traverse_pair_nodes(a.tree(), b.tree(), overlap, [&](std::int32_t i, std::int32_t j) {
      const Triangle<double>& tb = b.triangle(j);
      tree_found = triangles_intersect(a.triangle(i), Triangle<double>(p.apply(tb.a), p.apply(tb.b), p.apply(tb.c)));
      return !tree_found;
    });
    ASSERT_EQ(hit, tree_found);
    if (hit) {
      nearest_hit += st.bv_tests;
      tree_hit += tree_tests;
      ++hits;
    } else {
      EXPECT_EQ(st.bv_tests, tree_tests);
      ++misses;
    }
  }
  ASSERT_GT(hits, 30);
  ASSERT_GT(misses, 30);
  EXPECT_LT(double(nearest_hit), 0.8 * double(tree_hit)) << "node tests on " << hits << " colliding poses";
}

TEST(MeshCollide, NearestChildFirstReachesCollisionsSooner) {
  expect_nearest_first_saves_work<Aabb<double>>();
  expect_nearest_first_saves_work<Obb<double>>();
  expect_nearest_first_saves_work<Sphere<double>>();
}
