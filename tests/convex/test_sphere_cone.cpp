// SPDX-License-Identifier: MIT
// The sphere–cone closed forms (convex/closed_form.hpp: sphere_cone_overlap, _contact, _distance,
// reached through convex_intersect / convex_distance / convex_penetration) against the
// sampled-boundary oracle of support/sphere_solid_check.hpp, given the cone's surface (side, base)
// and its inside test. Centres outside the side, above the apex, below the base, beyond the rim,
// inside nearer the side or the base, on the axis, on the side, the base, the rim and the apex; a
// blunt cone and a needle (the fuzzing finding: a sphere centred on the axis of a cone 9,000 times
// longer than wide got the radius as its depth along an arbitrary normal); double and float.
#include "support/sphere_solid_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace impact_sphere_cone_test {  // named: the convex tests build as one unity translation unit

using namespace impact;
using L = long double;

// The boundary of the cone (base radius R at z = -h, apex at z = h): piece 0 the side (u = theta,
// v in [0, 1] from the apex to the rim), piece 1 the base (u = phi, v = the radius in [0, R]); a
// 32 x 32 grid per piece, then 30 rounds of zooming in.
test::BoundaryPoint boundary_oracle(L R, L h, const std::array<L, 3>& q) {
  const auto point = [&](int piece, L u, L v) {
    if (piece == 0) return std::array<L, 3>{v * R * std::cos(u), v * R * std::sin(u), h - v * 2 * h};
    return std::array<L, 3>{v * std::cos(u), v * std::sin(u), -h};
  };
  const auto range = [&](int piece) { return piece == 0 ? std::pair<L, L>(0, 1) : std::pair<L, L>(0, R); };
  const bool inside = q[2] >= -h && q[2] <= h && std::sqrt(q[0] * q[0] + q[1] * q[1]) <= R * (h - q[2]) / (2 * h);
  return test::nearest_boundary_point(2, point, range, q, inside, 32, 30);
}

// Centres in every region of the (rho, z) half plane and on every degenerate feature, for a cone
// of radius R and half length h; the sphere's radius is `r` (a fraction of the cone's size).
template <class S>
std::vector<test::SphereCase<S>> cases(S R, S h, S r) {
  std::vector<test::SphereCase<S>> out;
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

// The cone's witness points are checked to the oracle's precision along the boundary, where the
// distance is flat (about 1e-10 in long double); the normal's check scales with the sphere.
template <class S>
void check_sphere_cone(S R, S h, S r, S tol) {
  const Cone<S> cone(R, h);
  const auto oracle = [&](const std::array<L, 3>& q) { return boundary_oracle(R, h, q); };
  const test::SphereSolidCounts n = test::check_sphere_solid(cone, cases<S>(R, h, r), oracle, {tol, S(1e-9), r}, 43);
  EXPECT_GT(n.outside, 8);
  EXPECT_GT(n.inside, 5);
  EXPECT_GT(n.apart, 8);
}

TEST(ConvexSphereCone, ClosedFormsAgainstSampledBoundaryDouble) { check_sphere_cone<double>(0.4, 0.5, 0.3, 1e-12); }
TEST(ConvexSphereCone, ClosedFormsAgainstSampledBoundaryFloat) { check_sphere_cone<float>(0.4f, 0.5f, 0.3f, 1e-5f); }
// a needle 4,000 times longer than wide, and a sphere far larger than its width
TEST(ConvexSphereCone, NeedleConeDouble) { check_sphere_cone<double>(2.5e-4, 1.0, 0.05, 1e-12); }

// The closed form answers without an iteration, and its depth is the least overlap over
// directions (the direction-search oracle, one-sided) and the overlap along its normal.
TEST(ConvexSphereCone, NoIterationsAndTheLeastOverlap) {
  EXPECT_GT(test::check_sphere_least_overlap(test::zoo().sphere, test::zoo().cone, 98), 20);
}

}  // namespace impact_sphere_cone_test
