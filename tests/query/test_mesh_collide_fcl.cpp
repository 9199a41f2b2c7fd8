// SPDX-License-Identifier: MIT
// Mesh–mesh collision against FCL 0.7 (BVHModel<OBBRSS>, collide with the default request) on the
// real meshes of the data folder and on a generated pair: zero mismatches in the boolean answer
// over 10,000 random rigid poses per pair, for the sphere tree and the AABB tree. The poses are
// the bench's (tests/support/poses.hpp), with fixed seeds. Without IMPACT_DATA_DIR the data pairs
// are skipped; the generated pair always runs.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/io/load_mesh.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/data.hpp"
#include "support/fcl_oracle.hpp"
#include "support/poses.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <set>

using namespace impact;
using namespace impact::test;

namespace {

constexpr int kPoses = IMPACT_TEST_SANITIZED ? 1000 : 10000;  // instrumented builds: fewer poses, same code paths

struct Counts {
  int colliding = 0, mismatches = 0;
};

template <class BV> Counts compare_with_fcl(const TriangleMesh<double>& A, const TriangleMesh<double>& B, std::uint64_t seed) {
  const auto poses = random_poses_around(A, B, kPoses, seed);
  const auto fa = make_fcl_model<fcl::OBBRSSd>(A);
  const auto fb = make_fcl_model<fcl::OBBRSSd>(B);
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV> ma(A.template cast<S>());
  const MeshBvh<BV> mb(B.template cast<S>());
  Counts c;
  const RigidTransform<double> id;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const bool expected = fcl_collides<fcl::OBBRSSd>(fa, id, fb, poses[k]);
    const bool got = collides(ma, RigidTransform<S>{}, mb, poses[k].template cast<S>());
    c.colliding += expected;
    if (got != expected) {
      ++c.mismatches;
      ADD_FAILURE() << "pose " << k << ": impact says " << got << ", FCL says " << expected;
      if (c.mismatches > 5) break;
    }
  }
  return c;
}

void check_pair(const TriangleMesh<double>& A, const TriangleMesh<double>& B, std::uint64_t seed) {
  for (int bv = 0; bv < 2; ++bv) {
    const Counts c = bv == 0 ? compare_with_fcl<Sphere<double>>(A, B, seed) : compare_with_fcl<Aabb<double>>(A, B, seed);
    EXPECT_EQ(c.mismatches, 0) << (bv == 0 ? "sphere" : "aabb");
    // the pose distribution must exercise both answers
    EXPECT_GT(c.colliding, kPoses / 20);
    EXPECT_LT(c.colliding, kPoses - kPoses / 20);
    ::testing::Test::RecordProperty(bv == 0 ? "colliding_sphere" : "colliding_aabb", c.colliding);
  }
}

TriangleMesh<double> load_data(const std::string& path) { return load_mesh<double>(path); }

}  // namespace

TEST(MeshCollideFcl, EnvRob) {
  IMPACT_REQUIRE_DATA(env, "meshes/env.obj");
  IMPACT_REQUIRE_DATA(rob, "meshes/rob.obj");
  check_pair(load_data(env), load_data(rob), 101);
}

TEST(MeshCollideFcl, BunnyBunny) {
  IMPACT_REQUIRE_DATA(bunny, "meshes/stanford-bunny.obj");
  const auto m = load_data(bunny);
  check_pair(m, m, 102);
}

TEST(MeshCollideFcl, ArmadilloSpot) {
  IMPACT_REQUIRE_DATA(armadillo, "meshes/armadillo.obj");
  IMPACT_REQUIRE_DATA(spot, "meshes/spot.obj");
  check_pair(load_data(armadillo), load_data(spot), 103);
}

TEST(MeshCollideFcl, GeneratedPair) {
  check_pair(make_torus<double>(1.0, 0.35, 96, 48), make_icosphere<double>(0.6, 4), 104);
}

TEST(MeshCollideFcl, FloatTreesAgreeWithFcl) {
  // float trees and triangles on a generated pair: rounding to float moves vertices by ~1e-7
  // relative, so poses within that of touching may differ; everything else must match.
  const auto A = make_torus<double>(1.0, 0.35, 64, 32);
  const auto B = make_icosphere<double>(0.6, 3);
  const Counts c = compare_with_fcl<Sphere<float>>(A.cast<float>().cast<double>(), B.cast<float>().cast<double>(), 105);
  EXPECT_EQ(c.mismatches, 0);
}

TEST(MeshCollideFcl, AllPairsMatchBruteForceOnRealMeshes) {
  IMPACT_REQUIRE_DATA(knight, "meshes/knight.off");
  IMPACT_REQUIRE_DATA(rob, "meshes/rob.obj");
  IMPACT_REQUIRE_DATA(spot, "meshes/spot.obj");
  // knight (closed), rob (triangle soup), knight against spot (closed, 6k triangles)
  for (const auto& [pa, pb] : {std::pair{knight, knight}, std::pair{rob, rob}, std::pair{knight, spot}}) {
    const auto A = load_data(pa), B = load_data(pb);
    const auto poses = random_poses_around(A, B, 16, 7);
    MeshBvh<Sphere<double>> sa(A), sb(B);
    MeshBvh<Aabb<double>> aa(A), ab(B);
    CollideOptions all;
    all.all_pairs = true;
    int nonempty = 0;
    for (const auto& p : poses) {
      const auto expected = brute_force_pairs(A, RigidTransform<double>{}, B, p);
      nonempty += !expected.empty();
      EXPECT_EQ(sorted(collide(sa, RigidTransform<double>{}, sb, p, all).pairs), expected);
      EXPECT_EQ(sorted(collide(aa, RigidTransform<double>{}, ab, p, all).pairs), expected);
    }
    EXPECT_GT(nonempty, 0);
  }
}

namespace {

/// All-pairs sets of both trees against FCL's (BVHModel<OBBRSS>, num_max_contacts unlimited) on
/// the same poses; returns the number of pairs found.
int all_pairs_against_fcl(const TriangleMesh<double>& A, const TriangleMesh<double>& B, int poses, std::uint64_t seed) {
  const auto fa = make_fcl_model<fcl::OBBRSSd>(A);
  const auto fb = make_fcl_model<fcl::OBBRSSd>(B);
  const MeshBvh<Sphere<double>> sa(A), sb(B);
  const MeshBvh<Aabb<double>> aa(A), ab(B);
  CollideOptions all;
  all.all_pairs = true;
  int pairs = 0;
  for (const auto& p : random_poses_around(A, B, poses, seed)) {
    const auto f = fcl_all_pairs<fcl::OBBRSSd>(fa, RigidTransform<double>{}, fb, p);
    const std::set<std::pair<int, int>> expected(f.begin(), f.end());
    const auto gs = collide(sa, RigidTransform<double>{}, sb, p, all).pairs;
    const auto ga = collide(aa, RigidTransform<double>{}, ab, p, all).pairs;
    using PairSet = std::set<std::pair<int, int>>;
    EXPECT_EQ(PairSet(gs.begin(), gs.end()), expected) << "sphere tree";
    EXPECT_EQ(PairSet(ga.begin(), ga.end()), expected) << "aabb tree";
    pairs += int(expected.size());
  }
  return pairs;
}

}  // namespace

TEST(MeshCollideFcl, AllPairsMatchFclPairSets) {
  IMPACT_REQUIRE_DATA(env, "meshes/env.obj");
  IMPACT_REQUIRE_DATA(rob, "meshes/rob.obj");
  EXPECT_GT(all_pairs_against_fcl(load_data(env), load_data(rob), 300, 9), 0);
}

TEST(MeshCollideFcl, AllPairsMatchFclPairSetsBunny) {
  IMPACT_REQUIRE_DATA(bunny, "meshes/stanford-bunny.obj");
  const auto m = load_data(bunny);
  EXPECT_GT(all_pairs_against_fcl(m, m, IMPACT_TEST_SANITIZED ? 10 : 60, 10), 0);
}

TEST(MeshCollideFcl, MeshInsideClosedMeshDoesNotCollide) {
  // FCL's surface semantics, which impact matches by default: a small sphere strictly inside a big
  // one has no intersecting triangles.
  const auto big = make_icosphere<double>(2.0, 3), small = make_icosphere<double>(0.5, 2);
  const auto fa = make_fcl_model<fcl::OBBRSSd>(big);
  const auto fb = make_fcl_model<fcl::OBBRSSd>(small);
  EXPECT_FALSE(fcl_collides<fcl::OBBRSSd>(fa, RigidTransform<double>{}, fb, RigidTransform<double>{}));
  EXPECT_FALSE(collides(MeshBvh<Sphere<double>>(big), RigidTransform<double>{}, MeshBvh<Sphere<double>>(small), RigidTransform<double>{}));
}
