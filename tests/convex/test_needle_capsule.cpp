// SPDX-License-Identifier: MIT
// A needle capsule (about 1e9 times longer than wide) crossing a cone far from its ends: depth,
// boolean and distance against an oracle written here in long double. Where the axis crosses the
// cone far from the capsule's ends, any direction with a component along the axis overlaps by the
// half length times that component, so the least overlap lies among the directions normal to the
// axis: depth = r + min over phi of [n . p0 - min_{x in cone} n . x], n = cos(phi) e1 + sin(phi) e2
// (p0 the capsule's centre), a 1-D minimisation (a grid, then ternary search) on the cone's own
// support written below; when negative, minus it is the distance. Before the capsule was cut to
// the part of it that decides (capsule_window in convex/query.hpp), the depth along a normal that
// rounding tilted by 1e-7 was off by up to 8.7e-6 of the size, and the boolean missed contacts
// 0.07 inside the radius. Runtime: about 0.05 s (64 poses, each oracle about 2,300 evaluations).
#include "impact/convex/query.hpp"
#include "impact/convex/shapes.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace {

using impact::Capsule;
using impact::Cone;
using impact::RigidTransform;
using LD = long double;
using VL = Eigen::Matrix<LD, 3, 1>;

/// The cone's support (apex (0,0,h), base rim of radius r at z = -h) in its own frame.
VL cone_support(LD r, LD h, const VL& d) {
  const LD rho = std::sqrt(d.x() * d.x() + d.y() * d.y());
  if (rho == 0 || h * d.z() >= r * rho - h * d.z()) return VL(0, 0, h);
  return VL(r * d.x() / rho, r * d.y() / rho, -h);
}

struct NeedleOracle {
  VL p0, u, e1, e2, tb;
  Eigen::Matrix<LD, 3, 3> Rb;
  LD rc = 0, rk = 0, hk = 0, h = 0;
  /// The capsule's overlap with the cone along the unit direction n (long double).
  LD overlap(const VL& n) const {
    const VL low = Rb * cone_support(rk, hk, VL(-(Rb.transpose() * n))) + tb;
    return n.dot(p0) + h * std::abs(n.dot(u)) + rc - n.dot(low);
  }
  /// min over the directions normal to the axis.
  LD least_normal_overlap() const {
    const LD two_pi = 2 * 3.14159265358979323846264338327950288L;
    const auto g = [&](LD phi) { return overlap(VL(std::cos(phi) * e1 + std::sin(phi) * e2)); };
    const int n = 2048;
    LD best = g(0), best_phi = 0;
    for (int k = 1; k < n; ++k) {
      const LD v = g(two_pi * k / n);
      if (v < best) {
        best = v;
        best_phi = two_pi * k / n;
      }
    }
    LD lo = best_phi - two_pi / n, hi = best_phi + two_pi / n;
    for (int it = 0; it < 120; ++it) {
      const LD m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
      if (g(m1) < g(m2)) {
        hi = m2;
      } else {
        lo = m1;
      }
    }
    return std::min(best, g((lo + hi) / 2));
  }
};

TEST(ConvexNeedle, CapsuleAcrossACone) {
  impact::test::Rng rng(15);
  const double rc = 4, h = 4.3e9, rk = 32, hk = 24;
  const Capsule<double> cap(rc, h);
  const Cone<double> cone(rk, hk);
  const double size = impact::detail::query_scale<double>(cap, cone);
  int contacts = 0, apart = 0;
  for (int i = 0; i < 64; ++i) {
    const RigidTransform<double> pa(rng.rotation(), rng.vec(-10, 10));
    const Eigen::Vector3d u = pa.R.col(2), e1 = u.unitOrthogonal(), e2 = u.cross(e1);
    // the cone about the axis, anywhere along its middle half: the crossing is far from the ends
    const RigidTransform<double> pb(rng.rotation(),
                                    pa.t + rng.uniform(-0.5, 0.5) * h * u + rng.uniform(-45, 45) * e1 + rng.uniform(-45, 45) * e2);
    NeedleOracle o;
    o.p0 = pa.t.cast<LD>();
    o.u = u.cast<LD>();
    o.e1 = e1.cast<LD>();
    o.e2 = e2.cast<LD>();
    o.Rb = pb.R.cast<LD>();
    o.tb = pb.t.cast<LD>();
    o.rc = rc;
    o.rk = rk;
    o.hk = hk;
    o.h = h;
    const double depth = double(o.least_normal_overlap());
    for (const bool swap : {false, true}) {
      const auto c = swap ? impact::convex_penetration(cone, pb, cap, pa) : impact::convex_penetration(cap, pa, cone, pb);
      const bool hit = swap ? impact::convex_intersect(cone, pb, cap, pa) : impact::convex_intersect(cap, pa, cone, pb);
      const auto d = swap ? impact::convex_distance(cone, pb, cap, pa) : impact::convex_distance(cap, pa, cone, pb);
      if (std::abs(depth) > 1e-9 * size) {
        EXPECT_EQ(hit, depth > 0) << "pose " << i << " swap " << swap << " depth " << depth;
        EXPECT_EQ(c.intersecting, depth > 0) << "pose " << i << " swap " << swap << " depth " << depth;
      }
      if (depth > 0 && c.intersecting) {
        ++contacts;
        EXPECT_NEAR(c.depth, depth, 1e-11 * size) << "pose " << i << " swap " << swap;
        // translating the cone by depth * normal makes them touch: the overlap along the normal
        // (a normal tilted towards the axis by e overlaps by h e more) is the depth
        const VL n = (swap ? -c.normal : c.normal).cast<LD>();
        EXPECT_NEAR(double(o.overlap(n)), c.depth, 1e-11 * size) << "pose " << i << " swap " << swap;
        EXPECT_FALSE(c.limit_reached);
      }
      if (depth < 0) {
        ++apart;
        EXPECT_NEAR(d.distance, -depth, 1e-11 * size) << "pose " << i << " swap " << swap;
      }
    }
  }
  EXPECT_GE(contacts, 40);  // both kinds of pose occur (about half and half)
  EXPECT_GE(apart, 40);
}

}  // namespace
