// SPDX-License-Identifier: MIT
// The convex queries against FCL 0.7 on the same shapes and poses (support/convex_fcl.hpp: FCL's
// primitives with its default libccd-based solver): boolean answers must match wherever the
// certified distance bracket of support/convex_oracle.hpp puts the pair more than 1e-6 of the
// shape size from touching; distances must never exceed FCL's (both are upper bounds) and agree
// within FCL's accuracy, 1e-3 of the shape size (FCL's GJK distance is off by up to 1.4e-4 on
// cylinder–cylinder here, where ours lies inside the oracle's certified bracket to 1e-9:
// tests/convex/test_convex_query.cpp).
#include "impact/convex/query.hpp"
#include "support/convex_fcl.hpp"
#include "support/convex_oracle.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

namespace {

using namespace impact;
using impact::test::zoo;
using impact::test::FclShapePair;

template <class A, class B>
void check_against_fcl(const char* name, const A& a, const B& b, std::uint64_t seed, bool compare_distance = true) {
  const int n = IMPACT_TEST_SANITIZED ? 16 : 150;
  const FclShapePair fcl{test::to_fcl_shape(a), test::to_fcl_shape(b)};
  const double scale = std::max(shape_size(a), shape_size(b));
  int compared = 0, hits = 0;
  for (const auto& [pa, pb] : test::convex_poses(n, 0.75 * (shape_size(a) + shape_size(b)), seed)) {
    const auto br = test::distance_bracket(a, pa, b, pb, 800);
    const bool ours = convex_intersect(a, pa, b, pb);
    const bool theirs = fcl.collide(pa, pb);
    // separated: certified by the bracket; intersecting: the bracket says not separated and the
    // grid search finds no direction of overlap below 1e-6
    const bool separated = br.lower > 1e-6 * scale;
    const bool intersecting =
        !separated && br.upper < 1e-9 * scale && test::signed_distance_oracle(a, pa, b, pb, 1500, 1).value < -1e-6 * scale;
    if (separated || intersecting) {
      ++compared;
      hits += theirs;
      EXPECT_EQ(ours, theirs) << name << ": impact " << ours << ", FCL " << theirs << ", distance in [" << br.lower << ", " << br.upper << "]";
    }
    if (compare_distance && br.lower > 1e-6 * scale) {
      const double d = convex_distance(a, pa, b, pb).distance;
      const double dfcl = fcl.distance(pa, pb);
      // FCL's GJK returns an upper bound as ours does: ours must never be farther than FCL's, and the
      // two agree within FCL's accuracy (up to 1.4e-4 of the size off on cylinder-cylinder here)
      EXPECT_LE(d, dfcl + 1e-9 * scale) << name;
      EXPECT_NEAR(d, dfcl, 1e-3 * scale) << name;
    }
  }
  EXPECT_GT(compared, n / 2) << name;
  EXPECT_GE(hits, std::max(1, n / 20)) << name;
  EXPECT_LT(hits, compared) << name;
}

TEST(ConvexFcl, BooleanAndDistanceMatch) {
  const auto& z = zoo();
  check_against_fcl("sphere-sphere", z.sphere, z.sphere, 101);
  check_against_fcl("sphere-capsule", z.sphere, z.capsule, 102);
  check_against_fcl("capsule-capsule", z.capsule, z.capsule, 103);
  check_against_fcl("sphere-box", z.sphere, z.box, 104);
  check_against_fcl("box-box", z.box, z.box, 105);
  check_against_fcl("capsule-box", z.capsule, z.box, 106);
  check_against_fcl("sphere-cylinder", z.sphere, z.cylinder, 107);
  check_against_fcl("cylinder-cylinder", z.cylinder, z.cylinder, 108);
  check_against_fcl("cone-box", z.cone, z.box, 109);
  check_against_fcl("cylinder-cone", z.cylinder, z.cone, 110);
  check_against_fcl("hull-hull", z.hull, z.hull, 111);
  check_against_fcl("capsule-hull", z.capsule, z.hull, 112);
}

// FCL's depth for the pairs it answers in closed form (sphere–sphere, sphere–capsule, sphere–box,
// box–box) is the true penetration depth: ours must agree to 1e-9 of the size.
TEST(ConvexFcl, ClosedFormDepthsMatch) {
  const auto& z = zoo();
  const auto run = [&](const char* name, const auto& a, const auto& b, std::uint64_t seed) {
    const FclShapePair fcl{test::to_fcl_shape(a), test::to_fcl_shape(b)};
    int compared = 0;
    for (const auto& [pa, pb] : test::convex_poses(IMPACT_TEST_SANITIZED ? 40 : 150, 0.7 * (shape_size(a) + shape_size(b)), seed)) {
      double depth;
      Eigen::Vector3d normal, point;
      const auto c = convex_penetration(a, pa, b, pb);
      if (!fcl.penetration(pa, pb, depth, normal, point) || !c.intersecting || depth < 1e-6) continue;
      ++compared;
      EXPECT_NEAR(c.depth, depth, 1e-9) << name;
      EXPECT_LE((c.normal - normal).norm(), 1e-6) << name << ": normal " << c.normal.transpose() << " FCL " << normal.transpose();
    }
    EXPECT_GT(compared, 10) << name;
  };
  run("sphere-sphere", z.sphere, z.sphere, 201);
  run("sphere-box", z.sphere, z.box, 203);
}

}  // namespace
