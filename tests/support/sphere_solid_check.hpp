// SPDX-License-Identifier: MIT
// Checks the closed forms of a sphere against a solid of revolution (a cylinder or a cone:
// convex_intersect, convex_distance and convex_penetration, both argument orders) against an
// oracle that shares nothing with them: the distance from the sphere's centre to the solid's
// boundary, found by sampling each piece of the boundary surface on a grid and zooming in about
// the best sample (long double), signed by the solid's inside test. From it: the boolean (signed
// distance <= radius), the distance (signed distance - radius), the depth (radius - signed
// distance), the witness points and the normal. Used by test_sphere_cylinder and test_sphere_cone,
// which give the boundary pieces, the inside test and the centres to try.
#pragma once

#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace impact::test {

struct BoundaryPoint {
  long double signed_distance = 0;  ///< from the query point to the boundary: > 0 outside, < 0 inside
  std::array<long double, 3> point{};  ///< the boundary point found (the solid's frame)
};

/// The boundary point nearest to q, over `pieces` surface pieces, each a map (u, v) -> point with
/// u an angle in [0, 2 pi) and v in range(piece): per piece the best sample of a grid x (grid + 1)
/// grid, then `rounds` rounds of a 9 x 9 grid at a third of the spacing about the best point (v
/// clamped to its range). `point(piece, u, v)` returns the point, `range(piece)` the pair (v_lo,
/// v_hi); `inside` says whether q is in the solid (it signs the distance).
template <class PointFn, class RangeFn>
BoundaryPoint nearest_boundary_point(int pieces, PointFn point, RangeFn range, const std::array<long double, 3>& q, bool inside,
                                     int grid, int rounds) {
  using L = long double;
  const L pi = std::acos(L(-1));
  const auto dist = [&](const std::array<L, 3>& p) {
    return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
  };
  BoundaryPoint best;
  L best_distance = INFINITY;
  for (int piece = 0; piece < pieces; ++piece) {
    const std::pair<L, L> v_range = range(piece);
    L piece_best = INFINITY, pu = 0, pv = 0;
    const auto sample = [&](L u, L v) {
      v = std::min(std::max(v, v_range.first), v_range.second);
      const L d = dist(point(piece, u, v));
      if (d < piece_best) {
        piece_best = d;
        pu = u;
        pv = v;
      }
    };
    for (int i = 0; i < grid; ++i)
      for (int j = 0; j <= grid; ++j) sample(2 * pi * i / grid, v_range.first + (v_range.second - v_range.first) * j / grid);
    L du = 2 * pi / grid, dv = (v_range.second - v_range.first) / grid;
    for (int round = 0; round < rounds; ++round) {
      const L cu = pu, cv = pv;
      for (int i = -4; i <= 4; ++i)
        for (int j = -4; j <= 4; ++j) sample(cu + du * i / 4, cv + dv * j / 4);
      du /= 3;
      dv /= 3;
    }
    if (piece_best < best_distance) {
      best_distance = piece_best;
      best.point = point(piece, pu, pv);
    }
  }
  best.signed_distance = inside ? -best_distance : best_distance;
  return best;
}

template <class S>
struct SphereCase {
  Vec3<S> local;  ///< the sphere's centre in the solid's frame
  S radius;
  const char* what;
};

/// What check_sphere_solid allows beyond `tol` (the answers' tolerance in S): `witness_slack` on
/// the witness points (the oracle's precision along the boundary, where the distance is flat), and
/// the normal of an outside centre compared with the oracle's direction only when the centre is
/// more than 1e-3 `scale` out, within 1e3 tol / scale (the oracle's direction is as good as its
/// point over that distance).
template <class S>
struct SphereSolidTolerance {
  S tol;
  S witness_slack = S(0);
  S scale = S(1);
};

struct SphereSolidCounts {
  int outside = 0;  ///< intersecting with the centre outside the solid
  int inside = 0;   ///< intersecting with the centre inside
  int apart = 0;
};

/// Every case placed by a random pose of `solid` (a Cylinder<S> or a Cone<S>), its answers checked
/// against `oracle(local centre)` (a BoundaryPoint). Returns how many cases fell in each class, for
/// the caller to assert its coverage.
template <template <class> class Solid, class S, class Oracle>
SphereSolidCounts check_sphere_solid(const Solid<S>& solid, const std::vector<SphereCase<S>>& cases, Oracle oracle,
                                     const SphereSolidTolerance<S>& tolerance, unsigned seed) {
  using L = long double;
  const S tol = tolerance.tol;
  const Solid<double> solid_d(double(solid.radius), double(solid.half_length));
  Rng rng(seed);
  SphereSolidCounts n;
  for (const auto& k : cases) {
    // a random pose of the solid; the sphere's centre placed by it
    const RigidTransform<double> pd{rng.rotation(), rng.vec(-2, 2)};
    const RigidTransform<S> pb = pd.cast<S>();
    const Vec3<S> centre = pb.apply(k.local);
    const Sphere<S> sphere(Vec3<S>::Zero(), k.radius);
    const Eigen::Matrix3d ra = rng.rotation();
    const RigidTransform<S> pa{ra.cast<S>(), centre};
    const BoundaryPoint o = oracle(std::array<L, 3>{L(k.local.x()), L(k.local.y()), L(k.local.z())});
    const Vec3<S> ob = pb.apply(Vec3<S>(S(o.point[0]), S(o.point[1]), S(o.point[2])));
    const L sd = o.signed_distance, rad = k.radius;
    const char* what = k.what;

    // boolean (away from touching)
    if (std::abs(sd - rad) > L(tol)) {
      EXPECT_EQ(convex_intersect(sphere, pa, solid, pb), sd <= rad) << what;
      EXPECT_EQ(convex_intersect(solid, pb, sphere, pa), sd <= rad) << what;
    }
    // distance and witness points
    const auto d = convex_distance(sphere, pa, solid, pb);
    const auto e = convex_distance(solid, pb, sphere, pa);
    if (sd - rad > L(tol)) {
      ++n.apart;
      EXPECT_FALSE(d.intersecting) << what;
      EXPECT_NEAR(double(d.distance), double(sd - rad), double(tol)) << what;
      EXPECT_NEAR(double(e.distance), double(sd - rad), double(tol)) << what;
      EXPECT_NEAR((d.point_b - d.point_a).norm(), d.distance, tol) << what;
      // the solid's witness is the boundary point the oracle found
      EXPECT_LE((d.point_b - ob).norm(), S(100) * tol + tolerance.witness_slack) << what;
      EXPECT_LE((e.point_a - ob).norm(), S(100) * tol + tolerance.witness_slack) << what;
      EXPECT_NEAR((d.point_a - centre).norm(), k.radius, tol) << what;
    } else if (sd - rad < -L(tol)) {
      EXPECT_TRUE(d.intersecting) << what;
      EXPECT_EQ(d.distance, S(0)) << what;
      EXPECT_TRUE(e.intersecting) << what;
    }
    // penetration: depth r - sd, in closed form; b moved by the depth along the normal just touches
    const auto c = convex_penetration(sphere, pa, solid, pb);
    const auto f = convex_penetration(solid, pb, sphere, pa);
    if (rad - sd > L(tol)) {
      (sd > 0 ? n.outside : n.inside) += 1;
      EXPECT_TRUE(c.intersecting) << what;
      EXPECT_TRUE(f.intersecting) << what;
      if (!c.intersecting || !f.intersecting) continue;
      EXPECT_EQ(c.iterations, 0) << what;
      EXPECT_NEAR(double(c.depth), double(rad - sd), double(tol)) << what;
      EXPECT_NEAR(double(f.depth), double(rad - sd), double(tol)) << what;
      EXPECT_NEAR(c.normal.norm(), S(1), tol) << what;
      EXPECT_LE((f.normal + c.normal).norm(), tol) << what;  // swapped roles: the opposite normal
      const double overlap = overlap_along(Sphere<double>(Eigen::Vector3d::Zero(), double(k.radius)), pa.template cast<double>(), solid_d,
                                           pb.template cast<double>(), Eigen::Vector3d(c.normal.template cast<double>()));
      EXPECT_NEAR(overlap, double(c.depth), 4 * double(tol)) << what << ": depth is not the overlap along the normal";
      // the deepest points: the sphere's along the normal, the solid's on its boundary
      EXPECT_NEAR((c.point_a() - centre).norm(), k.radius, 4 * tol) << what;
      if (sd > L(1e-3) * L(tolerance.scale)) {  // outside: the normal points at the closest boundary point
        EXPECT_LE((c.normal - (ob - centre).normalized()).norm(), S(1e3) * tol / tolerance.scale) << what;
        EXPECT_LE((c.point_b() - ob).norm(), S(100) * tol + tolerance.witness_slack) << what;
      }
    } else if (rad - sd < -L(tol)) {
      EXPECT_FALSE(c.intersecting) << what;
      EXPECT_FALSE(f.intersecting) << what;
    }
  }
  return n;
}

/// On 80 random poses of `sphere` and `solid` (double): the closed form answers without an
/// iteration, and its depth is never above the least overlap over directions (the direction-search
/// oracle) and is the overlap along its normal. Returns the number of intersecting poses.
template <class Solid>
int check_sphere_least_overlap(const Sphere<double>& sphere, const Solid& solid, unsigned seed) {
  int n = 0;
  for (const auto& [pa, pb] : convex_poses(80, 0.6 * (shape_size(sphere) + shape_size(solid)), seed)) {
    const auto c = convex_penetration(sphere, pa, solid, pb);
    EXPECT_EQ(c.iterations, 0);
    EXPECT_EQ(c.depth_gap, 0.0);
    if (!c.intersecting) continue;
    ++n;
    const auto o = signed_distance_oracle(sphere, pa, solid, pb);
    EXPECT_LE(c.depth, -o.value + 1e-12);
    EXPECT_NEAR(overlap_along(sphere, pa, solid, pb, c.normal), c.depth, 1e-12);
  }
  return n;
}

}  // namespace impact::test
