// SPDX-License-Identifier: MIT
// The sphere–cylinder closed forms (convex/closed_form.hpp: sphere_cylinder_overlap, _contact,
// _distance, reached through convex_intersect / convex_distance / convex_penetration) against the
// sampled-boundary oracle of support/sphere_solid_check.hpp, given the cylinder's surface (side,
// caps) and its inside test. Centres outside every face, region and corner, inside, on the axis,
// on the rim, on the side and on a cap; double and float.
#include "support/sphere_solid_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace impact_sphere_cylinder_test {  // named: the convex tests build as one unity translation unit

using namespace impact;
using L = long double;

// The boundary of the cylinder (radius R, half length h): piece 0 the side (u = theta, v = z),
// pieces 1 and 2 the caps z = +-h (u = phi, v = the radius in [0, R]); a 64 x 64 grid per piece,
// then 40 rounds of zooming in.
test::BoundaryPoint boundary_oracle(L R, L h, const std::array<L, 3>& q) {
  const auto point = [&](int piece, L u, L v) {
    if (piece == 0) return std::array<L, 3>{R * std::cos(u), R * std::sin(u), v};
    return std::array<L, 3>{v * std::cos(u), v * std::sin(u), piece == 1 ? h : -h};
  };
  const auto range = [&](int piece) { return piece == 0 ? std::pair<L, L>(-h, h) : std::pair<L, L>(0, R); };
  const bool inside = std::sqrt(q[0] * q[0] + q[1] * q[1]) <= R && std::abs(q[2]) <= h;
  return test::nearest_boundary_point(3, point, range, q, inside, 64, 40);
}

// Centres in every region of the (rho, z) half plane and on every degenerate feature, for a
// cylinder of radius R and half length h.
template <class S>
std::vector<test::SphereCase<S>> cases(S R, S h) {
  std::vector<test::SphereCase<S>> out;
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
  const auto oracle = [&](const std::array<L, 3>& q) { return boundary_oracle(cyl.radius, cyl.half_length, q); };
  const test::SphereSolidCounts n = test::check_sphere_solid(cyl, cases<S>(cyl.radius, cyl.half_length), oracle, {tol}, 41);
  EXPECT_GT(n.outside, 30);
  EXPECT_GT(n.inside, 20);
  EXPECT_GT(n.apart, 20);
}

TEST(ConvexSphereCylinder, ClosedFormsAgainstSampledBoundaryDouble) { check_sphere_cylinder<double>(1e-12); }
TEST(ConvexSphereCylinder, ClosedFormsAgainstSampledBoundaryFloat) { check_sphere_cylinder<float>(1e-5f); }

// The closed form answers without an iteration, and its depth is the least overlap over
// directions (the direction-search oracle, one-sided) and the overlap along its normal.
TEST(ConvexSphereCylinder, NoIterationsAndTheLeastOverlap) {
  EXPECT_GT(test::check_sphere_least_overlap(test::zoo().sphere, test::zoo().cylinder, 97), 20);
}

}  // namespace impact_sphere_cylinder_test
