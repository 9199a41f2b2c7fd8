// SPDX-License-Identifier: MIT
// Mesh–mesh collision against an exact oracle written in the tests (support/brute_force.hpp: the
// triangle pairs decided with arbitrary-precision integers, every pair, no hierarchy), on the family
// that exposed the sphere tree's missed contacts (issue 12, D7): one big triangle touched by small
// ones at a vertex, on an edge or inside its face, or missed by one unit, at random power-of-two
// scales and translations (all exact), float and double, sphere and AABB trees, with identity poses
// (the reported case), with both meshes under the same random pose (B moved into A's frame by a
// rounded near-identity transform, so the culls must cover the transform's rounding), and with the
// big triangle in either mesh (the leaf-versus-node cull runs on both sides). Also every tree type
// (sphere, AABB, oriented box) under poses stretched or sheared up to validate_pose's tolerance.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/mesh_collide.hpp"
#include "support/brute_force.hpp"
#include "support/exact_triangle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace impact;
using namespace impact::test;

namespace {

using IVec3 = Eigen::Matrix<std::int64_t, 3, 1>;

IVec3 ivec(Rng& rng, std::int64_t lo, std::int64_t hi) {
  IVec3 v;
  for (int i = 0; i < 3; ++i) v[i] = lo + static_cast<std::int64_t>(rng.index(static_cast<std::uint64_t>(hi - lo + 1)));
  return v;
}
IVec3 non_parallel(Rng& rng, const IVec3& a, std::int64_t lo, std::int64_t hi) {
  for (;;) {
    const IVec3 b = ivec(rng, lo, hi);
    if (a.cross(b) != IVec3::Zero()) return b;
  }
}

/// The big triangle and a cluster of small ones around a point X of it (integer coordinates below
/// 2^20 in magnitude: exact in float and double after any power-of-two scaling).
struct Family {
  std::vector<IVec3> big;     // 3 vertices
  std::vector<IVec3> small;   // 3 per small triangle
};

Family make_family(Rng& rng) {
  Family f;
  // Half a diagonal h of the cluster's box: the big triangle's normal is made parallel to it, so
  // the cluster's node sphere (fitted around the box's centre) is tangent to the big triangle at
  // the box corner X, the one point where they touch: the case where rounding decides.
  IVec3 h = ivec(rng, 1, 8);
  for (int i = 0; i < 3; ++i)
    if (rng.index(2)) h[i] = -h[i];
  const bool tangent = rng.index(4) != 0;
  const IVec3 P = ivec(rng, -(1 << 17), 1 << 17);
  IVec3 d1, d2;
  if (tangent) {
    do d1 = h.cross(ivec(rng, -3, 3)); while (d1 == IVec3::Zero());
    do d2 = h.cross(ivec(rng, -3, 3)); while (d1.cross(d2) == IVec3::Zero());
  } else {
    do d1 = ivec(rng, -8, 8); while (d1 == IVec3::Zero());
    d2 = non_parallel(rng, d1, -8, 8);
  }
  const std::int64_t m = (1 << 8) + static_cast<std::int64_t>(rng.index(1 << 11));
  f.big = {P, P + m * d1, P + m * d2};
  IVec3 X;
  const auto kind = rng.index(3);
  const std::int64_t j = 1 + static_cast<std::int64_t>(rng.index(static_cast<std::uint64_t>(m - 1)));
  if (kind == 0) {
    X = f.big[rng.index(3)];  // at a vertex
  } else if (kind == 1) {
    const auto e = rng.index(3);  // on an edge
    X = e == 0 ? IVec3(P + j * d1) : (e == 1 ? IVec3(P + j * d2) : IVec3(P + m * d1 + j * (d2 - d1)));
  } else {
    const std::int64_t jj = 1 + static_cast<std::int64_t>(rng.index(static_cast<std::uint64_t>(m - 2)));  // in the face
    const std::int64_t i = 1 + static_cast<std::int64_t>(rng.index(static_cast<std::uint64_t>(m - 1 - jj)));
    X = P + i * d1 + jj * d2;
  }
  if (rng.index(4) == 0) X[static_cast<int>(rng.index(3))] += rng.index(2) ? 1 : -1;  // one unit off
  auto add = [&](const IVec3& p, const IVec3& q, const IVec3& r) {
    f.small.push_back(p);
    f.small.push_back(q);
    f.small.push_back(r);
  };
  const std::int64_t s = std::int64_t(1) << rng.index(5);
  if (tangent) {
    // triangles spanning the box [X, X + 2 s h] (componentwise, with h's signs), X one of their vertices
    const IVec3 D = 2 * s * h;
    auto corner = [&](int x, int y, int z) { return IVec3(X + IVec3(x * D[0], y * D[1], z * D[2])); };
    add(corner(0, 0, 0), corner(1, 0, 0), corner(0, 1, 1));
    add(corner(1, 1, 1), corner(1, 1, 0), corner(0, 0, 1));
    add(corner(0, 1, 0), corner(1, 0, 1), corner(1, 1, 1));
    add(corner(1, 0, 0), corner(1, 1, 1), corner(0, 1, 1));
  } else {
    for (int k = 0; k < 6; ++k) {
      const IVec3 Y = k == 0 ? X : IVec3(X + ivec(rng, -3, 3) * s);  // neighbours in the cluster
      const IVec3 w1 = ivec(rng, -6, 6);
      const IVec3 w2 = w1 == IVec3::Zero() ? ivec(rng, -6, 6) : non_parallel(rng, w1, -6, 6);
      add(Y, Y + s * w1, Y + s * w2);
    }
  }
  return f;
}

template <class S> TriangleMesh<S> to_mesh(const std::vector<IVec3>& pts, const IVec3& shift, int scale_exp) {
  TriangleMesh<S> m;
  const auto n = static_cast<Eigen::Index>(pts.size());
  m.V.resize(n, 3);
  m.F.resize(n / 3, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      m.V(i, c) = static_cast<S>(std::ldexp(static_cast<double>(pts[static_cast<std::size_t>(i)][c] + shift[c]), scale_exp));
  for (Eigen::Index t = 0; t < n / 3; ++t) m.F.row(t) << int(3 * t), int(3 * t + 1), int(3 * t + 2);
  return m;
}

struct Tally {
  int configs = 0, colliding = 0, pairs = 0;
};

template <class BV>
void check_against_exact(const TriangleMesh<typename BvTraits<BV>::Scalar>& A, const TriangleMesh<typename BvTraits<BV>::Scalar>& B,
                         const RigidTransform<typename BvTraits<BV>::Scalar>& pa,
                         const RigidTransform<typename BvTraits<BV>::Scalar>& pb, Tally& tally, const char* what) {
  const MeshBvh<BV> a(A), b(B);
  const auto truth = brute_force_pairs(A, pa, B, pb);
  CollideOptions all;
  all.all_pairs = true;
  const auto r = collide(a, pa, b, pb, all);
  ++tally.configs;
  tally.colliding += truth.empty() ? 0 : 1;
  tally.pairs += static_cast<int>(truth.size());
  ASSERT_EQ(sorted(r.pairs), truth) << what << " (" << BvTraits<BV>::name << ")";
  ASSERT_EQ(collides(a, pa, b, pb), !truth.empty()) << what << " (" << BvTraits<BV>::name << ")";
}

template <class S> void run_family(std::uint64_t seed, int n, int max_exp) {
  Rng rng(seed);
  Tally tally;
  for (int it = 0; it < n; ++it) {
    const Family f = make_family(rng);
    const IVec3 shift = ivec(rng, -(1 << 18), 1 << 18);
    const int e = -max_exp + static_cast<int>(rng.index(static_cast<std::uint64_t>(2 * max_exp + 1)));
    const auto big = to_mesh<S>(f.big, shift, e), small = to_mesh<S>(f.small, shift, e);
    const RigidTransform<S> id;
    // the same random pose for both: the relative transform is the identity up to rounding
    const Eigen::Vector3d t = rng.vec(-1, 1) * std::ldexp(1.0, e + 19);
    const RigidTransform<S> common(rng.rotation().cast<S>(), t.cast<S>());
    for (int swap = 0; swap < 2; ++swap) {
      const auto& A = swap ? small : big;
      const auto& B = swap ? big : small;
      check_against_exact<Sphere<S>>(A, B, id, id, tally, "identity");
      check_against_exact<Aabb<S>>(A, B, id, id, tally, "identity");
      check_against_exact<Sphere<S>>(A, B, common, common, tally, "common pose");
      check_against_exact<Aabb<S>>(A, B, common, common, tally, "common pose");
      if (::testing::Test::HasFatalFailure()) {
        ADD_FAILURE() << "configuration " << it << ", scale 2^" << e << ", swapped " << swap;
        return;
      }
    }
  }
  // the family must hold both answers in numbers, or the test proves little
  EXPECT_GT(tally.colliding, tally.configs / 3);
  EXPECT_LT(tally.colliding, tally.configs);
}

}  // namespace

TEST(MeshCollideExact, BigTriangleTouchedBySmallOnesDouble) { run_family<double>(12001, IMPACT_TEST_SANITIZED ? 60 : 300, 60); }
// float: scales within the validated float range (coordinates and translations up to 2^28)
TEST(MeshCollideExact, BigTriangleTouchedBySmallOnesFloat) { run_family<float>(12002, IMPACT_TEST_SANITIZED ? 60 : 300, 8); }

// The leaf-triangle cull of sphere trees (detail::sphere_may_touch_triangle) on spheres tangent to a
// large triangle, by construction in integers: the centre is X + k w with w a Pythagorean direction
// (|w| an integer, so the radius k |w| is exact) and every vertex V of the triangle has
// (V - X).w <= 0, which makes X the triangle's closest point to the centre (at a vertex, on an edge
// or inside the face). Tangent spheres must be kept; spheres smaller by 2^-10 must be culled (the
// test fails if the cull keeps everything). The triangle either lies in the plane normal to w (the
// normal axis decides) or holds w and an edge normal to it (an edge axis decides).
namespace {

template <class S> void run_tangent_spheres(std::uint64_t seed, int n, int max_exp) {
  Rng rng(seed);
  const IVec3 pyth[] = {IVec3(2, 3, 6), IVec3(1, 4, 8), IVec3(4, 4, 7), IVec3(1, 2, 2), IVec3(2, 6, 9), IVec3(6, 6, 7)};
  const std::int64_t norm[] = {7, 9, 9, 3, 11, 11};
  int kept = 0, culled = 0;
  for (int it = 0; it < n; ++it) {
    const auto pi = rng.index(6);
    IVec3 w = pyth[pi];
    const int perm = static_cast<int>(rng.index(3));
    std::swap(w[0], w[perm]);
    for (int i = 0; i < 3; ++i)
      if (rng.index(2)) w[i] = -w[i];
    const std::int64_t k = 1 + static_cast<std::int64_t>(rng.index(16));
    const IVec3 X = ivec(rng, -(1 << 20), 1 << 20);
    IVec3 d;
    do d = w.cross(ivec(rng, -3, 3)); while (d == IVec3::Zero());
    const std::int64_t m = (1 << 10) + static_cast<std::int64_t>(rng.index(1 << 12));  // |edges| up to about 2^19: products round
    IVec3 V[3];
    const auto kind = rng.index(3);      // X at a vertex, on an edge, inside the face
    const bool in_plane = rng.index(2);  // triangle normal to w, or holding w
    IVec3 e;
    if (in_plane) {
      do e = w.cross(ivec(rng, -3, 3)); while (d.cross(e) == IVec3::Zero());
    } else {
      e = -w;
    }
    if (kind == 0) {
      V[0] = X, V[1] = X + m * d, V[2] = X + m * e;
    } else if (kind == 1) {
      V[0] = X - m * d, V[1] = X + m * d, V[2] = X + m * e;
    } else if (in_plane) {
      V[0] = X - m * (d + e), V[1] = X + m * (2 * d - e), V[2] = X + m * (2 * e - d);
    } else {
      continue;  // a face point holding w cannot be a tangent point
    }
    if (rng.index(2)) std::swap(V[1], V[2]);  // both orientations
    const IVec3 shift = ivec(rng, -(1 << 21), 1 << 21);  // coordinates below 2^23: exact in float
    const int ex = -max_exp + static_cast<int>(rng.index(static_cast<std::uint64_t>(2 * max_exp + 1)));
    auto conv = [&](const IVec3& p) {
      Vec3<S> v;
      for (int i = 0; i < 3; ++i) v[i] = static_cast<S>(std::ldexp(static_cast<double>(p[i] + shift[i]), ex));
      return v;
    };
    const Triangle<S> t(conv(V[0]), conv(V[1]), conv(V[2]));
    const Vec3<S> c = conv(X + k * w);
    const S r = static_cast<S>(std::ldexp(static_cast<double>(k * norm[pi]), ex));
    ASSERT_TRUE(detail::sphere_may_touch_triangle(c, r, t))
        << "tangent sphere culled: configuration " << it << ", kind " << kind << ", in plane " << in_plane << ", 2^" << ex;
    ++kept;
    culled += detail::sphere_may_touch_triangle(c, r - std::ldexp(r, -10), t) ? 0 : 1;
  }
  EXPECT_GT(kept, n / 2);
  EXPECT_EQ(culled, kept) << "spheres apart by 2^-10 of their radius must be culled";
}

}  // namespace

TEST(SphereMayTouchTriangle, TangentSpheresKeptDouble) { run_tangent_spheres<double>(12011, 4000, 60); }
TEST(SphereMayTouchTriangle, TangentSpheresKeptFloat) { run_tangent_spheres<float>(12012, 4000, 30); }

// validate_pose accepts rotations off orthonormal by up to rotation_tolerance (a rotation rounded
// to float passes in double), and the narrow phase moves B's triangles by that very matrix, so the
// node tests must bound B's image under it, not under the nearest rotation. B's pose is a rotation
// (the identity, a quarter turn, a random one) times a stretch I + sigma or a shear I + sigma S (S
// symmetric, zero diagonal), at 0.4 of the tolerance, and B is moved along each axis, from either
// side, until its image overlaps A's face by a quarter of the stretch. Every hierarchy must agree
// with the exact brute force over all triangle pairs (an oriented-box test that took B's axes for
// unit vectors called the roots of two stretched boxes apart).
namespace {
template <class BV> void run_nearly_rigid_poses() {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> half_a(S(1), S(0.5), S(0.25));
  const TriangleMesh<S> box_a = make_box<S>(half_a);
  const MeshBvh<BV> a(box_a);
  const S delta = S(0.4) * rotation_tolerance<S>();
  Mat3<S> quarter_turn;  // 90 degrees about z, exact
  quarter_turn << S(0), S(-1), S(0), S(1), S(0), S(0), S(0), S(0), S(1);
  const Mat3<S> tilted = Eigen::AngleAxis<S>(S(0.7), Vec3<S>(S(1), S(2), S(3)).normalized()).toRotationMatrix();
  Mat3<S> shear;
  shear << S(0), S(1), S(-1), S(1), S(0), S(1), S(-1), S(1), S(0);
  int colliding = 0, poses = 0;
  for (const S size : {S(1), S(0.3)}) {
    const TriangleMesh<S> box_b = make_box<S>(Vec3<S>(half_a * size));
    const MeshBvh<BV> b(box_b);
    for (const Mat3<S>& q : {Mat3<S>(Mat3<S>::Identity()), quarter_turn, tilted})
      for (const Mat3<S>& defect : {Mat3<S>(Mat3<S>::Identity() * delta), Mat3<S>(Mat3<S>::Identity() * -delta), Mat3<S>(shear * (delta / S(2)))})
        for (int axis = 0; axis < 3; ++axis)
          for (const S side : {S(1), S(-1)}) {
            const Mat3<S> r = q * (Mat3<S>::Identity() + defect);
            S extent = 0;  // B's image's half extent along the axis
            for (int v = 0; v < box_b.num_vertices(); ++v) extent = std::max(extent, std::abs((r * box_b.vertex(v))[axis]));
            Vec3<S> t = Vec3<S>::Zero();
            t[axis] = side * (half_a[axis] + extent * (S(1) - delta / S(4)));
            const RigidTransform<S> pose(r, t);
            ASSERT_NO_THROW(validate_pose(pose, "test"));
            const auto expected = brute_force_pairs(box_a, RigidTransform<S>{}, box_b, pose);
            colliding += !expected.empty();
            ++poses;
            CollideOptions all;
            all.all_pairs = true;
            EXPECT_EQ(collides(a, RigidTransform<S>{}, b, pose), !expected.empty()) << BvTraits<BV>::name << " size " << size << " axis " << axis;
            EXPECT_EQ(sorted(collide(a, RigidTransform<S>{}, b, pose, all).pairs), expected) << BvTraits<BV>::name << " axis " << axis;
          }
  }
  // a tilted full-size B can reach past A's face sideways and miss it; the rest overlap by a quarter
  // of the stretch, far above rounding, and must collide
  EXPECT_GE(colliding, poses * 3 / 4);
}
}  // namespace

TEST(MeshCollideExact, NearlyRigidPosesKeepEveryContact) {
  run_nearly_rigid_poses<Sphere<double>>();
  run_nearly_rigid_poses<Aabb<double>>();
  run_nearly_rigid_poses<Obb<double>>();
  run_nearly_rigid_poses<Sphere<float>>();
  run_nearly_rigid_poses<Aabb<float>>();
  run_nearly_rigid_poses<Obb<float>>();
}
