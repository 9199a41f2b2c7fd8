// SPDX-License-Identifier: MIT
// The sphere–cylinder closed forms (convex/closed_form.hpp: sphere_cylinder_overlap, _contact,
// _distance, reached through convex_intersect / convex_distance / convex_penetration) against an
// oracle written here that shares nothing with them: the distance from the sphere's centre to the
// cylinder's boundary surface by sampling that surface (side, caps) on a grid and zooming in
// around the best sample (long double), and the inside test from the definition. From it:
// boolean (signed distance <= radius), distance (signed distance - radius) and depth (radius -
// signed distance). Centres outside every face, region and corner, inside, on the axis, on the
// rim, on the side and on a cap; double and float.
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using namespace impact;
using L = long double;

struct Oracle {
  L signed_distance;  // from the centre to the cylinder's boundary: > 0 outside, < 0 inside
  L px, py, pz;       // the boundary point found (cylinder frame)
};

// The boundary of the cylinder (radius R, half length h) sampled as side(theta, z) and caps(s,
// phi) (s the radius); the best sample of a 64 x 64 grid per piece, then 40 rounds of a 9 x 9
// grid at a third of the spacing about the best point (clamped to the piece).
Oracle boundary_oracle(L R, L h, L qx, L qy, L qz) {
  const L pi = std::acos(L(-1));
  L best = INFINITY, bx = 0, by = 0, bz = 0;
  const auto consider = [&](L x, L y, L z) {
    const L d = std::sqrt((x - qx) * (x - qx) + (y - qy) * (y - qy) + (z - qz) * (z - qz));
    if (d < best) {
      best = d;
      bx = x;
      by = y;
      bz = z;
    }
  };
  // piece 0: side (u = theta, v = z); pieces 1, 2: caps z = +-h (u = phi, v = s in [0, R])
  for (int piece = 0; piece < 3; ++piece) {
    const L ulo = 0, uhi = 2 * pi;
    const L vlo = piece == 0 ? -h : L(0), vhi = piece == 0 ? h : R;
    const auto point = [&](L u, L v, L& x, L& y, L& z) {
      if (piece == 0) {
        x = R * std::cos(u), y = R * std::sin(u), z = v;
      } else {
        x = v * std::cos(u), y = v * std::sin(u), z = piece == 1 ? h : -h;
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
    const int n = 64;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j <= n; ++j) sample(ulo + (uhi - ulo) * i / n, vlo + (vhi - vlo) * j / n);
    L du = (uhi - ulo) / n, dv = (vhi - vlo) / n;
    for (int round = 0; round < 40; ++round) {
      const L cu = pu, cv = pv;
      for (int i = -4; i <= 4; ++i)
        for (int j = -4; j <= 4; ++j) sample(cu + du * i / 4, cv + dv * j / 4);
      du /= 3;
      dv /= 3;
    }
    L x, y, z;
    point(pu, pv, x, y, z);
    consider(x, y, z);
  }
  const bool inside = std::sqrt(qx * qx + qy * qy) <= R && std::abs(qz) <= h;
  return {inside ? -best : best, bx, by, bz};
}

template <class S>
struct Case {
  Vec3<S> local;  // the sphere's centre in the cylinder's frame
  S radius;
  const char* what;
};

// Centres in every region of the (rho, z) half plane and on every degenerate feature, for a
// cylinder of radius R and half length h.
template <class S>
std::vector<Case<S>> cases(S R, S h) {
  std::vector<Case<S>> out;
  const S r = S(0.3);
  const auto add = [&](S rho, S phi, S z, S rad, const char* what) {
    out.push_back({Vec3<S>(rho * std::cos(phi), rho * std::sin(phi), z), rad, what});
  };
  for (int k = 0; k < 7; ++k) {
    const S phi = S(0.9) * S(k);
    add(R + S(0.2), phi, S(0.1), r, "outside the side");
    add(R + S(0.31), phi, S(-0.2), r, "outside the side, apart");
    add(R * S(0.5), phi, h + S(0.25), r, "above the cap");
    add(R * S(0.5), phi, -h - S(0.35), r, "below the cap, apart");
    add(R + S(0.1), phi, h + S(0.15), r, "beyond the rim");
    add(R + S(0.25), phi, -h - S(0.25), r, "beyond the rim, apart");
    add(R * S(0.7), phi, S(0.2), r, "inside, nearer the side");
    add(R * S(0.1), phi, h * S(0.9), r, "inside, nearer the cap");
    add(R, phi, S(0.1), r, "on the side");
    add(R * S(0.3), phi, h, r, "on the cap");
    add(R, phi, h, r, "on the rim");
    add(R, phi, -h, S(0.05), "on the lower rim, small");
    add(R * (S(1) + S(1e-7)), phi, S(0), r, "just outside the side");
  }
  add(0, 0, h + S(0.2), r, "on the axis, above");
  add(0, 0, -h - S(0.5), r, "on the axis, apart");
  add(0, 0, S(0.1), r, "on the axis, inside");
  add(0, 0, 0, r, "the centre");
  add(0, 0, h, r, "the cap's centre");
  return out;
}

template <class S>
void check_sphere_cylinder(S tol) {
  const Cylinder<S> cyl(S(0.4), S(0.5));
  test::Rng rng(41);
  int outside = 0, inside = 0, apart = 0;
  for (const auto& k : cases<S>(cyl.radius, cyl.half_length)) {
    // a random pose of the cylinder; the sphere's centre placed by it
    const RigidTransform<double> pd{rng.rotation(), rng.vec(-2, 2)};
    const RigidTransform<S> pb = pd.cast<S>();
    const Vec3<S> centre = pb.apply(k.local);
    const Sphere<S> sphere(Vec3<S>::Zero(), k.radius);
    const Eigen::Matrix3d ra = rng.rotation();
    const RigidTransform<S> pa{ra.cast<S>(), centre};
    const Sphere<double> sphere_d(Eigen::Vector3d::Zero(), double(k.radius));
    const Cylinder<double> cyl_d(double(cyl.radius), double(cyl.half_length));
    const Oracle o = boundary_oracle(cyl.radius, cyl.half_length, k.local.x(), k.local.y(), k.local.z());
    const L sd = o.signed_distance, r = k.radius;
    const bool hit = sd <= r;
    const char* what = k.what;

    // boolean (away from touching)
    if (std::abs(sd - r) > L(tol)) {
      EXPECT_EQ(convex_intersect(sphere, pa, cyl, pb), hit) << what;
      EXPECT_EQ(convex_intersect(cyl, pb, sphere, pa), hit) << what;
    }
    // distance and witness points
    const auto d = convex_distance(sphere, pa, cyl, pb);
    const auto e = convex_distance(cyl, pb, sphere, pa);
    if (sd - r > L(tol)) {
      ++apart;
      EXPECT_FALSE(d.intersecting) << what;
      EXPECT_NEAR(double(d.distance), double(sd - r), double(tol)) << what;
      EXPECT_NEAR(double(e.distance), double(sd - r), double(tol)) << what;
      EXPECT_NEAR((d.point_b - d.point_a).norm(), d.distance, tol) << what;
      // the cylinder's witness is the boundary point the oracle found
      const Vec3<S> ob = pb.apply(Vec3<S>(S(o.px), S(o.py), S(o.pz)));
      EXPECT_LE((d.point_b - ob).norm(), S(100) * tol) << what;
      EXPECT_LE((e.point_a - ob).norm(), S(100) * tol) << what;
      EXPECT_NEAR((d.point_a - centre).norm(), k.radius, tol) << what;
    } else if (sd - r < -L(tol)) {
      EXPECT_TRUE(d.intersecting) << what;
      EXPECT_EQ(d.distance, S(0)) << what;
      EXPECT_TRUE(e.intersecting) << what;
    }
    // penetration: depth r - sd; the normal such that b moved by depth along it just touches
    const auto c = convex_penetration(sphere, pa, cyl, pb);
    const auto f = convex_penetration(cyl, pb, sphere, pa);
    if (r - sd > L(tol)) {
      (sd > 0 ? outside : inside) += 1;
      ASSERT_TRUE(c.intersecting) << what;
      ASSERT_TRUE(f.intersecting) << what;
      EXPECT_NEAR(double(c.depth), double(r - sd), double(tol)) << what;
      EXPECT_NEAR(double(f.depth), double(r - sd), double(tol)) << what;
      EXPECT_NEAR(c.normal.norm(), S(1), tol) << what;
      EXPECT_LE((f.normal + c.normal).norm(), tol) << what;  // swapped roles: the opposite normal
      const double overlap = test::overlap_along(sphere_d, pa.template cast<double>(), cyl_d, pb.template cast<double>(),
                                               Eigen::Vector3d(c.normal.template cast<double>()));
      EXPECT_NEAR(overlap, double(c.depth), 4 * double(tol)) << what << ": depth is not the overlap along the normal";
      // the deepest points: the sphere's along the normal, the cylinder's on its boundary
      EXPECT_NEAR((c.point_a() - centre).norm(), k.radius, 4 * tol) << what;
      if (sd > L(1e-3)) {  // outside (by more than the rounding of the reference direction): the normal points at the closest boundary point
        const Vec3<S> ob = pb.apply(Vec3<S>(S(o.px), S(o.py), S(o.pz)));
        EXPECT_LE((c.normal - (ob - centre).normalized()).norm(), S(1e3) * tol) << what;
        EXPECT_LE((c.point_b() - ob).norm(), S(100) * tol) << what;
      }
    } else if (r - sd < -L(tol)) {
      EXPECT_FALSE(c.intersecting) << what;
      EXPECT_FALSE(f.intersecting) << what;
    }
  }
  EXPECT_GT(outside, 30);
  EXPECT_GT(inside, 20);
  EXPECT_GT(apart, 20);
}

TEST(ConvexSphereCylinder, ClosedFormsAgainstSampledBoundaryDouble) { check_sphere_cylinder<double>(1e-12); }
TEST(ConvexSphereCylinder, ClosedFormsAgainstSampledBoundaryFloat) { check_sphere_cylinder<float>(1e-5f); }

// The closed form answers without an iteration, and equals what the general path (GJK on the
// centre, EPA when the centre is inside) gave within its tolerance: the same poses through a
// cylinder-shaped hull would not be exact, so the comparison is with the definition instead:
// the depth is the least overlap over directions (the direction-search oracle), one-sided.
TEST(ConvexSphereCylinder, NoIterationsAndTheLeastOverlap) {
  const auto& z = test::zoo();
  int n = 0;
  for (const auto& [pa, pb] : test::convex_poses(80, 0.6 * (shape_size(z.sphere) + shape_size(z.cylinder)), 97)) {
    const auto c = convex_penetration(z.sphere, pa, z.cylinder, pb);
    EXPECT_EQ(c.iterations, 0);
    EXPECT_EQ(c.depth_gap, 0.0);
    if (!c.intersecting) continue;
    ++n;
    const auto o = test::signed_distance_oracle(z.sphere, pa, z.cylinder, pb);
    EXPECT_LE(c.depth, -o.value + 1e-12);  // never above the least overlap the oracle found
    EXPECT_NEAR(test::overlap_along(z.sphere, pa, z.cylinder, pb, c.normal), c.depth, 1e-12);
  }
  EXPECT_GT(n, 20);
}

}  // namespace
