// SPDX-License-Identifier: MIT
// The root slabs of oriented-box trees (MeshBvh::root_slabs, tried by the mesh queries on the root
// pair when its 15 axes fail): they decide poses at the roots that the two root boxes cannot, and
// never lose a contact: touching and near-touching poses (exact corner on corner, and found by
// bisection on the exact brute force) against the brute force, float and double, scaled and moved
// far from the origin, each tree as A and as B.
#include "impact/convex/convex_hull.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <type_traits>
#include <vector>

using namespace impact;
using namespace impact::test;

namespace {

/// A convex polytope symmetric under x -> -x, y -> -y, z -> -z (so its covariance, and its root
/// box's axes, are the coordinate axes): the tips (+-4, 0, 0), (0, +-3, 0), (0, 0, +-2) and the
/// corners (+-2.5, +-1.75, +-1.25), which stick out along the diagonals: its box is [-4, 4] x
/// [-3, 3] x [-2, 2] and along (1, 1, 1) it reaches 5.5, at a corner inside the box's extents.
/// Every coordinate is a short binary fraction, so the corner-on-corner poses below are exact.
TriangleMesh<double> corner_polytope() {
  Vertices<double> P(14, 3);
  int r = 0;
  for (int s : {1, -1}) {
    P.row(r++) << 4 * s, 0, 0;
    P.row(r++) << 0, 3 * s, 0;
    P.row(r++) << 0, 0, 2 * s;
  }
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) P.row(r++) << 2.5 * sx, 1.75 * sy, 1.25 * sz;
  const ConvexHull<double> h = convex_hull(P);
  return TriangleMesh<double>(h.vertices, h.triangles);
}

/// A box of half extents h centred at the origin: its root box is the box itself, so the slabs of
/// the other tree meet it exactly.
TriangleMesh<double> box_mesh(const Eigen::Vector3d& h) {
  Vertices<double> P(8, 3);
  int r = 0;
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) P.row(r++) << h.x() * sx, h.y() * sy, h.z() * sz;
  const ConvexHull<double> hull = convex_hull(P);
  return TriangleMesh<double>(hull.vertices, hull.triangles);
}

template <class S> TriangleMesh<S> scaled(const TriangleMesh<double>& m, double s) { return TriangleMesh<S>((m.V * s).cast<S>(), m.F); }

/// A random convex polytope: the hull of points on an ellipsoid of semi-axes 3, 2, 1, rotated.
TriangleMesh<double> random_polytope(Rng& rng, int n) {
  Vertices<double> P(n, 3);
  const Eigen::Matrix3d Q = random_pose(rng, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()).R;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d u(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    u.normalize();
    P.row(i) = (Q * Eigen::Vector3d(3 * u.x(), 2 * u.y(), u.z())).transpose();
  }
  const ConvexHull<double> h = convex_hull(P);
  return TriangleMesh<double>(h.vertices, h.triangles);
}

}  // namespace

template <class S> class RootSlabsTest : public ::testing::Test {};
using RootSlabScalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(RootSlabsTest, RootSlabScalars);

// The corner polytope and a box of half extents 0.5 whose lowest corner along (1, 1, 1) is moved
// onto the polytope's highest, (2.5, 1.75, 1.25): the root boxes overlap (and their balls), only
// the polytope's diagonal slabs separate them once they part. Touching is a contact; a hair apart
// is decided at the roots. Both orders: the slabs of tree A (against B's box) and of tree B.
TYPED_TEST(RootSlabsTest, DiagonalCornerTouchesOrPartsAtTheRoots) {
  using S = TypeParam;
  // apart by well above the pads of the node test: they cover a relative transform off a rotation
  // by up to the poses' tolerance (ObbPairFrame::validated_product_defect: 7e-6 in double, 2.5e-3
  // in float) times the boxes' sizes, and grow with the distance to the origin
  const double eps = std::is_same_v<S, float> ? 1e-1 : 1e-3;
  Rng rng(17101);
  int decided = 0;
  for (double scale : {1e-3, 1.0, 1e4}) {
    const TriangleMesh<S> poly = scaled<S>(corner_polytope(), scale), box = scaled<S>(box_mesh(Eigen::Vector3d::Constant(0.5)), scale);
    const MeshBvh<Obb<S>> tp(poly), tb(box);
    ASSERT_TRUE(tp.root_slabs().valid);
    for (const double offset : {0.0, std::is_same_v<S, float> ? 10.0 : 1e3}) {
      for (int rot = 0; rot < 2; ++rot) {
        // both meshes under one pose: rotated and moved far away (identity first)
        RigidTransform<double> base = rot == 0 ? RigidTransform<double>() : random_pose(rng, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
        base.t = Eigen::Vector3d(1, -2, 0.5) * offset * scale;
        const Eigen::Vector3d corner = Eigen::Vector3d(2.5, 1.75, 1.25) * scale, half = Eigen::Vector3d::Constant(0.5 * scale);
        for (double f : {1.0 - eps, 1.0, 1.0 + eps, 1.0 + 1.5 * eps}) {  // the boxes overlap up to f = 1.2
          RigidTransform<double> pb = base;
          pb.t = base.t + base.R * (corner * f + half);
          const RigidTransform<S> pa_s = base.template cast<S>(), pb_s = pb.template cast<S>();
          const bool expected = !brute_force_pairs(poly, pa_s, box, pb_s).empty();
          // the other order moves the polytope into the box's frame: rounded otherwise at a touch
          const bool expected_swapped = !brute_force_pairs(box, pb_s, poly, pa_s).empty();
          QueryStats st, st_swapped;
          EXPECT_EQ(collides(tp, pa_s, tb, pb_s, &st), expected) << "scale " << scale << " offset " << offset << " f " << f;
          EXPECT_EQ(collides(tb, pb_s, tp, pa_s, &st_swapped), expected_swapped) << "scale " << scale << " offset " << offset << " f " << f;
          CollideOptions all;
          all.all_pairs = true;
          EXPECT_EQ(sorted(collide(tp, pa_s, tb, pb_s, all).pairs), brute_force_pairs(poly, pa_s, box, pb_s));
          if (f == 1.0 && offset == 0 && rot == 0 && scale == 1.0) {
            EXPECT_TRUE(expected);  // exact: the corners coincide
          }
          if (f > 1.0) {
            EXPECT_FALSE(expected);
            EXPECT_FALSE(expected_swapped);
            // apart along a diagonal of the polytope's box only: decided by the first node test
            EXPECT_EQ(st.bv_tests, 1u) << "scale " << scale << " offset " << offset << " f " << f;
            EXPECT_EQ(st_swapped.bv_tests, 1u) << "scale " << scale << " offset " << offset << " f " << f;
            decided += st.bv_tests == 1 && st_swapped.bv_tests == 1;
          }
        }
      }
    }
  }
  EXPECT_EQ(decided, 3 * 2 * 2 * 2);
}

// Random convex polytopes against random boxes (whose root box is exact, so the polytope's slabs
// meet it closely), the box rotated at random and moved along a random direction to the last pose
// the exact brute force finds touching (bisection): at that pose and at poses just apart (where
// the roots' slabs are near their limit) the queries agree with it, in both orders.
TYPED_TEST(RootSlabsTest, NearTouchingPosesAgreeWithBruteForce) {
  using S = TypeParam;
  Rng rng(17102);
  int cases = 0;
  for (double scale : {1e-3, 1.0, 1e4}) {
    for (int trial = 0; trial < 2; ++trial) {
      const TriangleMesh<double> A0 = random_polytope(rng, 16),
                                 B0 = box_mesh(Eigen::Vector3d(rng.uniform(0.2, 1.5), rng.uniform(0.2, 1.5), rng.uniform(0.2, 1.5)));
      const TriangleMesh<S> A = scaled<S>(A0, scale), B = scaled<S>(B0, scale);
      const MeshBvh<Obb<S>> a(A), b(B);
      RigidTransform<double> pa;
      pa.t = Eigen::Vector3d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)) * 1e3 * scale;
      const Eigen::Matrix3d rb = random_pose(rng, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()).R;
      Eigen::Vector3d dir(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
      dir.normalize();
      auto pose_at = [&](double lambda) {
        RigidTransform<double> pb;
        pb.R = rb;
        pb.t = pa.t + dir * (lambda * scale);
        return pb.template cast<S>();
      };
      const RigidTransform<S> pa_s = pa.template cast<S>();
      auto touching = [&](double lambda) { return !brute_force_pairs(A, pa_s, B, pose_at(lambda)).empty(); };
      double lo = 0, hi = 20;  // touching at 0 (the centres coincide), apart at 20 (sizes at most 3 + 3)
      if (!touching(lo) || touching(hi)) continue;
      for (int it = 0; it < 50 && hi - lo > 1e-14 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (touching(mid) ? lo : hi) = mid;
      }
      ++cases;
      // just apart, then apart by more than the node test's pads (see above)
      const double r0 = std::is_same_v<S, float> ? 1e-5 : 1e-12, r1 = std::is_same_v<S, float> ? 1e-2 : 1e-4;
      for (double lambda : {lo, hi, hi * (1 + r0), hi * (1 + r1), hi * (1 + 10 * r1), hi * (1 + 100 * r1), lo * (1 - r0)}) {
        const RigidTransform<S> pb = pose_at(lambda);
        const auto expected = brute_force_pairs(A, pa_s, B, pb);
        EXPECT_EQ(collides(a, pa_s, b, pb), !expected.empty()) << "scale " << scale << " trial " << trial << " lambda " << lambda;
        CollideOptions all;
        all.all_pairs = true;
        EXPECT_EQ(sorted(collide(a, pa_s, b, pb, all).pairs), expected);
        EXPECT_EQ(collides(b, pb, a, pa_s), !brute_force_pairs(B, pb, A, pa_s).empty())
            << "scale " << scale << " trial " << trial << " lambda " << lambda;
      }
    }
  }
  EXPECT_GE(cases, 4);
}

// A tree refit to new vertices measures its slabs again: moved far away and stretched, the mesh is
// still found touching a box placed corner on corner, and parted from it at the roots.
TEST(RootSlabs, FollowSetVertices) {
  const TriangleMesh<double> m = corner_polytope(), box = box_mesh(Eigen::Vector3d::Constant(0.5));
  MeshBvh<Obb<double>> moving(m);
  const MeshBvh<Obb<double>> fixed(box);
  const ObbSlabs<double> before = moving.root_slabs();
  Vertices<double> V = m.V;
  V.col(0) *= 1.25;  // stretched along x (exactly): the corners at x = +-3.125, the tips at +-5
  V.rowwise() += Eigen::RowVector3d(100, 0, 0);
  moving.set_vertices(V);
  ASSERT_TRUE(moving.root_slabs().valid);
  EXPECT_NE(moving.root_slabs().hi[6], before.hi[6]);
  const TriangleMesh<double> moved(V, m.F);
  // moving's lowest corner along (1, 1, 1), (96.875, -1.75, -1.25), onto the box's highest, (0.5, 0.5, 0.5)
  RigidTransform<double> pose;
  pose.t = Eigen::Vector3d(0.5 - 96.875, 2.25, 1.75);
  const RigidTransform<double> id;
  EXPECT_TRUE(!brute_force_pairs(box, id, moved, pose).empty());
  EXPECT_TRUE(collides(fixed, id, moving, pose));
  pose.t += Eigen::Vector3d::Constant(0.05);  // well beyond the node test's pads
  QueryStats st;
  EXPECT_TRUE(brute_force_pairs(box, id, moved, pose).empty());
  EXPECT_FALSE(collides(fixed, id, moving, pose, &st));
  EXPECT_EQ(st.bv_tests, 1u);
}
