// SPDX-License-Identifier: MIT
// Mesh queries over oriented-box trees (MeshBvh<Obb<S>>): boolean and all-pairs mesh–mesh,
// self-collision and refit, against brute force over all triangle pairs and against FCL's OBB and
// OBBRSS trees on the real meshes, including exact touching configurations that a BV test rounded
// the wrong way would miss; float and double.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/io/load_mesh.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/data.hpp"
#include "support/fcl_oracle.hpp"
#include "support/meshes.hpp"
#include "support/poses.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

using namespace impact;
using namespace impact::test;

namespace {
constexpr int kObbPoses = IMPACT_TEST_SANITIZED ? 300 : 2000;
}

template <class S> class ObbTreeTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ObbTreeTest, Scalars);

TYPED_TEST(ObbTreeTest, AllPairsMatchBruteForceOnSoups) {
  using S = TypeParam;
  const auto A = random_soup<double>(300, 41, 1.0, 0.2).cast<S>(), B = random_soup<double>(200, 42, 1.0, 0.25).cast<S>();
  for (int leaf : {1, 4}) {
    MeshBvhConfig cfg;
    cfg.build.leaf_size = leaf;
    const MeshBvh<Obb<S>> a(A, cfg), b(B, cfg);
    CollideOptions all;
    all.all_pairs = true;
    int nonempty = 0;
    for (const auto& p : random_poses_around(A.template cast<double>(), B.template cast<double>(), 40, 43)) {
      const RigidTransform<S> ps = p.template cast<S>();
      const auto expected = brute_force_pairs(A, RigidTransform<S>{}, B, ps);
      nonempty += !expected.empty();
      const auto got = collide(a, RigidTransform<S>{}, b, ps, all);
      EXPECT_EQ(sorted(got.pairs), expected);
      EXPECT_EQ(collides(a, RigidTransform<S>{}, b, ps), !expected.empty());
    }
    EXPECT_GT(nonempty, 4);
  }
}

TYPED_TEST(ObbTreeTest, TouchingTrianglesAreNeverMissed) {
  using S = TypeParam;
  // One big triangle and many small ones that touch it exactly (a shared vertex, a vertex on its
  // interior, an edge lying in its plane), far from the origin and at several scales, identity
  // poses, so the exact triangle test sees the coordinates as given: every touching pair is a
  // collision and the tree must find each one.
  Rng rng(44);
  int touching = 0;
  for (double scale : {1e-3, 1.0, 1e4}) {
    for (double off : {0.0, 1e3}) {
      const Eigen::Vector3d o = Eigen::Vector3d(0.3, -0.7, 0.5) * off * scale;
      const Eigen::Vector3d p0 = o, p1 = o + Eigen::Vector3d(10, 0, 0) * scale, p2 = o + Eigen::Vector3d(0, 10, 0) * scale;
      TriangleMesh<S> big;
      big.V.resize(3, 3);
      big.V << p0.transpose().cast<S>(), p1.transpose().cast<S>(), p2.transpose().cast<S>();
      big.F.resize(1, 3);
      big.F << 0, 1, 2;
      TriangleMesh<S> small;
      const int n = 200;
      small.V.resize(3 * n, 3);
      small.F.resize(n, 3);
      for (int i = 0; i < n; ++i) {
        // the touching point: a vertex of the big triangle, or a grid point of its plane (exact in S)
        Vec3<S> q;
        if (i % 3 == 0) {
          q = big.V.row(i % 9 / 3).transpose();
        } else {
          q = Vec3<S>(big.V(0, 0) + S(std::ldexp(double(1 + rng.index(60)), -3) * scale), big.V(0, 1) + S(std::ldexp(double(1 + rng.index(20)), -3) * scale),
                      big.V(0, 2));
        }
        const Vec3<S> d1 = (rng.vec(-1, 1) * 0.01 * scale).cast<S>(), d2 = (rng.vec(-1, 1) * 0.01 * scale).cast<S>();
        const Vec3<S> up(S(0), S(0), S((i % 2 ? 1 : -1) * 0.01 * scale));
        small.V.row(3 * i) = q.transpose();
        small.V.row(3 * i + 1) = (q + up + d1).transpose();
        small.V.row(3 * i + 2) = (q + up + d2).transpose();
        small.F.row(i) << 3 * i, 3 * i + 1, 3 * i + 2;
      }
      const auto expected = brute_force_pairs(big, RigidTransform<S>{}, small, RigidTransform<S>{});
      touching += int(expected.size());
      const MeshBvh<Obb<S>> a(big), b(small);
      CollideOptions all;
      all.all_pairs = true;
      EXPECT_EQ(sorted(collide(a, RigidTransform<S>{}, b, RigidTransform<S>{}, all).pairs), expected) << scale << " " << off;
      EXPECT_EQ(sorted(collide(b, RigidTransform<S>{}, a, RigidTransform<S>{}, all).pairs).size(), expected.size());
      // a single small triangle at a time: the boolean query finds each touching one
      EXPECT_TRUE(collides(a, RigidTransform<S>{}, b, RigidTransform<S>{}));
    }
  }
  EXPECT_GT(touching, 600);
}

TYPED_TEST(ObbTreeTest, SelfCollisionAndRefitMatchBruteForce) {
  using S = TypeParam;
  auto M = random_soup<double>(400, 45, 1.0, 0.2).cast<S>();
  MeshBvh<Obb<S>> m(M);
  CollideOptions all;
  all.all_pairs = true;
  EXPECT_EQ(sorted(self_collide(m, all).pairs), brute_force_self_pairs(M));
  // deform and refit both ways: the answers follow the new vertices
  Rng rng(46);
  for (RefitMode mode : {RefitMode::Merge, RefitMode::Fit}) {
    for (int k = 0; k < M.V.rows(); ++k) M.V.row(k) += (rng.vec(-0.05, 0.05)).cast<S>().transpose();
    m.set_vertices(M.V, mode);
    EXPECT_EQ(sorted(self_collide(m, all).pairs), brute_force_self_pairs(M));
  }
  // a closed generated mesh has no self-intersections
  EXPECT_FALSE(self_collide(MeshBvh<Obb<S>>(make_torus<S>(S(1), S(0.3), 48, 24))).colliding);
}

namespace {
/// Boolean answers of the OBB tree against FCL's OBB tree on random poses: zero mismatches.
void check_against_fcl(const TriangleMesh<double>& A, const TriangleMesh<double>& B, std::uint64_t seed) {
  const auto fa = make_fcl_model<fcl::OBBd>(A), fb = make_fcl_model<fcl::OBBd>(B);
  const MeshBvh<Obb<double>> a(A), b(B);
  int colliding = 0, mismatches = 0;
  for (const auto& p : random_poses_around(A, B, kObbPoses, seed)) {
    const bool expected = fcl_collides<fcl::OBBd>(fa, RigidTransform<double>{}, fb, p);
    colliding += expected;
    if (collides(a, RigidTransform<double>{}, b, p) != expected && ++mismatches <= 5) ADD_FAILURE() << "mismatch with FCL";
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(colliding, kObbPoses / 20);
  EXPECT_LT(colliding, kObbPoses - kObbPoses / 20);
}
}  // namespace

TEST(ObbTreeFcl, EnvRob) {
  IMPACT_REQUIRE_DATA(env, "meshes/env.obj");
  IMPACT_REQUIRE_DATA(rob, "meshes/rob.obj");
  check_against_fcl(load_mesh<double>(env), load_mesh<double>(rob), 201);
}

TEST(ObbTreeFcl, BunnyBunny) {
  IMPACT_REQUIRE_DATA(bunny, "meshes/stanford-bunny.obj");
  const auto m = load_mesh<double>(bunny);
  check_against_fcl(m, m, 202);
}

TEST(ObbTreeFcl, GeneratedPair) { check_against_fcl(make_torus<double>(1.0, 0.35, 96, 48), make_icosphere<double>(0.6, 4), 203); }

TEST(ObbTreeFcl, AllPairsMatchFclPairSets) {
  IMPACT_REQUIRE_DATA(env, "meshes/env.obj");
  IMPACT_REQUIRE_DATA(rob, "meshes/rob.obj");
  const auto A = load_mesh<double>(env), B = load_mesh<double>(rob);
  const auto fa = make_fcl_model<fcl::OBBRSSd>(A), fb = make_fcl_model<fcl::OBBRSSd>(B);
  const MeshBvh<Obb<double>> a(A), b(B);
  CollideOptions all;
  all.all_pairs = true;
  int pairs = 0;
  for (const auto& p : random_poses_around(A, B, 100, 204)) {
    const auto expected = sorted(fcl_all_pairs<fcl::OBBRSSd>(fa, RigidTransform<double>{}, fb, p));
    EXPECT_EQ(sorted(collide(a, RigidTransform<double>{}, b, p, all).pairs), expected);
    pairs += int(expected.size());
  }
  EXPECT_GT(pairs, 0);
}
