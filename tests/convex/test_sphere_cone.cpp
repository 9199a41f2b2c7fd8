// SPDX-License-Identifier: MIT
// The sphere–cone closed forms (convex/closed_form.hpp: sphere_cone_overlap, _contact, _distance,
// reached through convex_intersect / convex_distance / convex_penetration) against an oracle
// written here that shares nothing with them: the distance from the sphere's centre to the cone's
// boundary surface by sampling that surface (side, base) on a grid and zooming in around the best
// sample (long double), and the inside test from the definition. From it: boolean (signed
// distance <= radius), distance (signed distance - radius) and depth (radius - signed distance).
// Centres outside the side, above the apex, below the base, beyond the rim, inside nearer the
// side or the base, on the axis, on the side, the base, the rim and the apex; a blunt cone and a
// needle (the fuzzing finding: a sphere centred on the axis of a cone 9,000 times longer than
// wide got the radius as its depth along an arbitrary normal); double and float.
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace impact_sphere_cone_test {  // named: the convex tests build as one unity translation unit

using namespace impact;
using L = long double;

struct Oracle {
  L signed_distance;  // from the centre to the cone's boundary: > 0 outside, < 0 inside
  L px, py, pz;       // the boundary point found (cone frame)
};

// The boundary of the cone (base radius R at z = -h, apex at z = h) sampled as side(theta, v) (v
// in [0, 1] from the apex to the rim) and base(phi, s) (s the radius); the best sample of a 32 x 32
// grid per piece, then 30 rounds of a 9 x 9 grid at a third of the spacing about the best point.
Oracle boundary_oracle(L R, L h, L qx, L qy, L qz) {
  const L pi = std::acos(L(-1));
  L best = INFINITY, bx = 0, by = 0, bz = 0;
  for (int piece = 0; piece < 2; ++piece) {
    const L vlo = 0, vhi = piece == 0 ? L(1) : R;
    const auto point = [&](L u, L v, L& x, L& y, L& z) {
      if (piece == 0) {
        x = v * R * std::cos(u), y = v * R * std::sin(u), z = h - v * 2 * h;
      } else {
        x = v * std::cos(u), y = v * std::sin(u), z = -h;
      }
    };
    L pb = INFINITY, pu = 0, pv = 0;
    const auto sample = [&](L u, L v) {
      v = std::min(std::max(v, vlo), vhi);
      L x, y, z;
      point(u, v, x, y, z);
      const L d = std::sqrt((x - qx) * (x - qx) + (y - qy) * (y - qy) + (z - qz) * (z - qz));
      if (d < pb) {
        pb = d;
        pu = u;
        pv = v;
      }
    };
    const int n = 32;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j <= n; ++j) sample(2 * pi * i / n, vlo + (vhi - vlo) * j / n);
    L du = 2 * pi / n, dv = (vhi - vlo) / n;
    for (int round = 0; round < 30; ++round) {
      const L cu = pu, cv = pv;
      for (int i = -4; i <= 4; ++i)
        for (int j = -4; j <= 4; ++j) sample(cu + du * i / 4, cv + dv * j / 4);
      du /= 3;
      dv /= 3;
    }
    if (pb < best) {
      best = pb;
      point(pu, pv, bx, by, bz);
    }
  }
  const bool inside = qz >= -h && qz <= h && std::sqrt(qx * qx + qy * qy) <= R * (h - qz) / (2 * h);
  return {inside ? -best : best, bx, by, bz};
}

template <class S>
struct Case {
  Vec3<S> local;  // the sphere's centre in the cone's frame
  S radius;
  const char* what;
};

// Centres in every region of the (rho, z) half plane and on every degenerate feature, for a cone
// of radius R and half length h; the sphere's radius is `r` (a fraction of the cone's size).
template <class S>
std::vector<Case<S>> cases(S R, S h, S r) {
  std::vector<Case<S>> out;
  const auto add = [&](S rho, S phi, S z, S rad, const char* what) {
    out.push_back({Vec3<S>(rho * std::cos(phi), rho * std::sin(phi), z), rad, what});
  };
  const S len = std::sqrt(R * R + 4 * h * h);
  const S mr = 2 * h / len, mz = R / len;  // the side's outward normal in the meridian plane
  const auto radius_at = [&](S z) { return R * (h - z) / (2 * h); };
  for (int k = 0; k < 3; ++k) {
    const S phi = S(2.1) * S(k);
    const S z0 = S(0.2) * h;
    add(radius_at(z0) + S(0.5) * r * mr, phi, z0 + S(0.5) * r * mz, r, "outside the side");
    add(radius_at(z0) + S(1.3) * r * mr, phi, z0 + S(1.3) * r * mz, r, "outside the side, apart");
    add(S(0.1) * r, phi, h + S(0.6) * r, r, "above the apex");
    add(R * S(0.5), phi, -h - S(0.4) * r, r, "below the base");
    add(R * S(0.5), phi, -h - S(1.4) * r, r, "below the base, apart");
    add(R + S(0.3) * r, phi, -h - S(0.3) * r, r, "beyond the rim");
    add(R + S(0.9) * r, phi, -h - S(0.9) * r, r, "beyond the rim, apart");
    add(radius_at(z0) * S(0.8), phi, z0, r, "inside, nearer the side");
    add(radius_at(-h) * S(0.5), phi, -h * S(0.98), r, "inside, nearer the base");
    add(radius_at(z0), phi, z0, r, "on the side");
    add(R * S(0.3), phi, -h, r, "on the base");
    add(R, phi, -h, r, "on the rim");
    add(radius_at(z0) * (S(1) + S(1e-7)), phi, z0, r, "just outside the side");
  }
  add(0, 0, h + S(0.5) * r, r, "on the axis, above the apex");
  add(0, 0, h + S(1.5) * r, r, "on the axis, above, apart");
  add(0, 0, -h - S(0.5) * r, r, "on the axis, below the base");
  add(0, 0, S(0), r, "on the axis, inside");
  add(0, 0, -h * S(0.5), r, "the centroid");
  add(0, 0, h, r, "the apex");
  add(0, 0, -h, r, "the base's centre");
  return out;
}

template <class S>
void check_sphere_cone(S R, S h, S r, S tol) {
  const Cone<S> cone(R, h);
  test::Rng rng(43);
  int outside = 0, inside = 0, apart = 0;
  for (const auto& k : cases<S>(R, h, r)) {
    // a random pose of the cone; the sphere's centre placed by it
    const RigidTransform<double> pd{rng.rotation(), rng.vec(-2, 2)};
    const RigidTransform<S> pb = pd.cast<S>();
    const Vec3<S> centre = pb.apply(k.local);
    const Sphere<S> sphere(Vec3<S>::Zero(), k.radius);
    const Eigen::Matrix3d ra = rng.rotation();
    const RigidTransform<S> pa{ra.cast<S>(), centre};
    const Oracle o = boundary_oracle(R, h, k.local.x(), k.local.y(), k.local.z());
    const L sd = o.signed_distance, rad = k.radius;
    const bool hit = sd <= rad;
    const char* what = k.what;

    // boolean (away from touching)
    if (std::abs(sd - rad) > L(tol)) {
      EXPECT_EQ(convex_intersect(sphere, pa, cone, pb), hit) << what;
      EXPECT_EQ(convex_intersect(cone, pb, sphere, pa), hit) << what;
    }
    // distance and witness points
    const auto d = convex_distance(sphere, pa, cone, pb);
    const auto e = convex_distance(cone, pb, sphere, pa);
    if (sd - rad > L(tol)) {
      ++apart;
      EXPECT_FALSE(d.intersecting) << what;
      EXPECT_NEAR(double(d.distance), double(sd - rad), double(tol)) << what;
      EXPECT_NEAR(double(e.distance), double(sd - rad), double(tol)) << what;
      EXPECT_NEAR((d.point_b - d.point_a).norm(), d.distance, tol) << what;
      // the cone's witness is the boundary point the oracle found (to the oracle's precision along
      // the boundary, where the distance is flat: about 1e-10 in long double)
      const Vec3<S> ob = pb.apply(Vec3<S>(S(o.px), S(o.py), S(o.pz)));
      EXPECT_LE((d.point_b - ob).norm(), S(100) * tol + S(1e-9)) << what;
      EXPECT_LE((e.point_a - ob).norm(), S(100) * tol + S(1e-9)) << what;
      EXPECT_NEAR((d.point_a - centre).norm(), k.radius, tol) << what;
    } else if (sd - rad < -L(tol)) {
      EXPECT_TRUE(d.intersecting) << what;
      EXPECT_EQ(d.distance, S(0)) << what;
      EXPECT_TRUE(e.intersecting) << what;
    }
    // penetration: depth r - sd; b moved by the depth along the normal just touches
    const auto c = convex_penetration(sphere, pa, cone, pb);
    const auto f = convex_penetration(cone, pb, sphere, pa);
    if (rad - sd > L(tol)) {
      (sd > 0 ? outside : inside) += 1;
      ASSERT_TRUE(c.intersecting) << what;
      ASSERT_TRUE(f.intersecting) << what;
      EXPECT_EQ(c.iterations, 0) << what;
      EXPECT_NEAR(double(c.depth), double(rad - sd), double(tol)) << what;
      EXPECT_NEAR(double(f.depth), double(rad - sd), double(tol)) << what;
      EXPECT_NEAR(c.normal.norm(), S(1), tol) << what;
      EXPECT_LE((f.normal + c.normal).norm(), tol) << what;  // swapped roles: the opposite normal
      const double overlap = test::overlap_along(Sphere<double>(Eigen::Vector3d::Zero(), double(k.radius)), pa.template cast<double>(),
                                                 Cone<double>(double(R), double(h)), pb.template cast<double>(),
                                                 Eigen::Vector3d(c.normal.template cast<double>()));
      EXPECT_NEAR(overlap, double(c.depth), 4 * double(tol)) << what << ": depth is not the overlap along the normal";
      EXPECT_NEAR((c.point_a() - centre).norm(), k.radius, 4 * tol) << what;
      if (sd > L(1e-3) * L(r)) {  // outside: the normal points at the closest boundary point
        const Vec3<S> ob = pb.apply(Vec3<S>(S(o.px), S(o.py), S(o.pz)));
        EXPECT_LE((c.normal - (ob - centre).normalized()).norm(), S(1e3) * tol / r) << what;
        EXPECT_LE((c.point_b() - ob).norm(), S(100) * tol + S(1e-9)) << what;
      }
    } else if (rad - sd < -L(tol)) {
      EXPECT_FALSE(c.intersecting) << what;
      EXPECT_FALSE(f.intersecting) << what;
    }
  }
  EXPECT_GT(outside, 8);
  EXPECT_GT(inside, 5);
  EXPECT_GT(apart, 8);
}

TEST(ConvexSphereCone, ClosedFormsAgainstSampledBoundaryDouble) { check_sphere_cone<double>(0.4, 0.5, 0.3, 1e-12); }
TEST(ConvexSphereCone, ClosedFormsAgainstSampledBoundaryFloat) { check_sphere_cone<float>(0.4f, 0.5f, 0.3f, 1e-5f); }
// a needle 4,000 times longer than wide, and a sphere far larger than its width
TEST(ConvexSphereCone, NeedleConeDouble) { check_sphere_cone<double>(2.5e-4, 1.0, 0.05, 1e-12); }

// The closed form answers without an iteration, and its depth is the least overlap over
// directions (the direction-search oracle, one-sided) and the overlap along its normal.
TEST(ConvexSphereCone, NoIterationsAndTheLeastOverlap) {
  const auto& z = test::zoo();
  int n = 0;
  for (const auto& [pa, pb] : test::convex_poses(80, 0.6 * (shape_size(z.sphere) + shape_size(z.cone)), 98)) {
    const auto c = convex_penetration(z.sphere, pa, z.cone, pb);
    EXPECT_EQ(c.iterations, 0);
    EXPECT_EQ(c.depth_gap, 0.0);
    if (!c.intersecting) continue;
    ++n;
    const auto o = test::signed_distance_oracle(z.sphere, pa, z.cone, pb);
    EXPECT_LE(c.depth, -o.value + 1e-12);  // never above the least overlap the oracle found
    EXPECT_NEAR(test::overlap_along(z.sphere, pa, z.cone, pb, c.normal), c.depth, 1e-12);
  }
  EXPECT_GT(n, 20);
}

}  // namespace impact_sphere_cone_test
