// SPDX-License-Identifier: MIT
// Penetration of cylinders and cones with parallel or antiparallel axes (convex/parallel_axes.hpp):
// coincident, coaxial and side-by-side pairs at scales 1e-3 .. 1e3, near and far from the origin,
// both axis orientations, against an oracle that minimises the overlap f(n) = h_a(n) + h_b(-n)
// over the directions of the meridian plane (where the least overlap of two shapes of revolution
// about parallel axes lies) by nested grids, from the shapes' support functions alone. Each answer
// must close its bracket (depth_gap within twice the tolerance, no limit_reached) and match the
// oracle within 1e-9 of the size. Runtime: about 0.1 s (a few hundred queries and oracle scans; a third of that
// under sanitizers).
#include "impact/convex/query.hpp"
#include "impact/convex/shapes.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using impact::Cone;
using impact::Cylinder;
using impact::RigidTransform;
using Vec = Eigen::Vector3d;

/// min over the unit vectors n = cos(psi) u + sin(psi) axis of the overlap along n: 720 samples,
/// then 21-point grids about the best, each 8 times finer, down to 1e-15 rad.
template <class A, class B>
double meridian_oracle(const A& a, const RigidTransform<double>& pa, const B& b, const RigidTransform<double>& pb) {
  const Vec axis = pa.R.col(2);
  Vec radial = pb.t - pa.t;
  radial -= radial.dot(axis) * axis;
  if (radial.norm() < 1e-9 * (1 + pb.t.norm())) radial = pa.R.col(0);
  const Vec u = radial.normalized();
  const auto f = [&](double psi) {
    return impact::test::overlap_along(a, pa, b, pb, Vec(std::cos(psi) * u + std::sin(psi) * axis));
  };
  const double kPi = 3.14159265358979323846;
  const int n = 720;
  double samples[n];
  for (int k = 0; k < n; ++k) samples[k] = f(2 * kPi * k / n);
  double best = samples[0];
  for (int k = 0; k < n; ++k) {  // every local minimum of the samples (two valleys can compete)
    if (samples[k] > samples[(k + 1) % n] || samples[k] > samples[(k + n - 1) % n]) continue;
    double best_psi = 2 * kPi * k / n, local = samples[k];
    for (double half = 2 * kPi / n; half > 1e-15; half /= 8) {
      const double centre = best_psi;
      for (int j = -10; j <= 10; ++j) {
        const double psi = centre + half * j / 10, v = f(psi);
        if (v < local) {
          local = v;
          best_psi = psi;
        }
      }
    }
    best = std::min(best, local);
  }
  return best;
}

RigidTransform<double> parallel_axes_pose(const RigidTransform<double>& base, bool flip, const Vec& offset) {
  RigidTransform<double> p = base;
  if (flip) p.R = base.R * Eigen::AngleAxisd(3.14159265358979323846, Vec::UnitX()).toRotationMatrix();
  p.t = base.t + base.R * offset;
  return p;
}

template <class A, class B>
void expect_parallel_closed(const A& a, const B& b, const RigidTransform<double>& pa, const RigidTransform<double>& pb, const std::string& what,
                            int& checked) {
  const impact::ConvexQueryOptions<double> options;
  const double scale = impact::detail::query_scale<double>(a, b);
  const double truth = meridian_oracle(a, pa, b, pb);
  if (truth < 1e-6 * scale) return;  // touching or apart: not this test's case
  ++checked;
  const auto c = impact::convex_penetration(a, pa, b, pb, options);
  ASSERT_TRUE(c.intersecting) << what;
  EXPECT_FALSE(c.limit_reached) << what;
  EXPECT_LE(c.depth_gap, 2 * options.relative_tolerance * scale) << what;
  EXPECT_LE(c.iterations, 4) << what;  // the closed form, not EPA
  EXPECT_NEAR(c.depth, truth, 1e-9 * scale) << what;
  // the depth is the overlap along the normal: translating b by it makes them touch
  EXPECT_NEAR(impact::test::overlap_along(a, pa, b, pb, c.normal), c.depth, 1e-12 * scale) << what;
  EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12) << what;
}

constexpr int kParallelPoses = IMPACT_TEST_SANITIZED ? 2 : 6;

template <class A, class B>
void expect_parallel_pairs(const A& unit_a, const B& unit_b, const char* name) {
  impact::test::Rng rng(17);
  int checked = 0;
  for (const double scale : {1e-3, 1.0, 1e3}) {
    const A a(unit_a.radius * scale, unit_a.half_length * scale);
    const B b(unit_b.radius * scale, unit_b.half_length * scale);
    for (const double far : {0.0, 1e3}) {
      for (int k = 0; k < kParallelPoses; ++k) {
        RigidTransform<double> pa;
        pa.R = rng.rotation();
        pa.t = (far * Vec::Ones() + rng.vec(-1, 1)) * scale;
        for (const bool flip : {false, true}) {
          const std::string what = std::string(name) + " scale " + std::to_string(scale) + " far " + std::to_string(far) + " pose " +
                                   std::to_string(k) + (flip ? " antiparallel" : " parallel");
          expect_parallel_closed(a, b, pa, parallel_axes_pose(pa, flip, Vec::Zero()), what + " coincident", checked);
          const Vec axial(0, 0, rng.uniform(-0.8, 0.8) * scale);
          expect_parallel_closed(a, b, pa, parallel_axes_pose(pa, flip, axial), what + " coaxial", checked);
          const Vec side = Vec(rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6)) * scale;
          expect_parallel_closed(a, b, pa, parallel_axes_pose(pa, flip, side), what + " offset", checked);
        }
      }
    }
  }
  EXPECT_GT(checked, 3 * 2 * kParallelPoses * 2 * 3 / 2) << name;  // most of the pairs intersect
}

TEST(ParallelAxes, CylinderCylinder) {
  expect_parallel_pairs(Cylinder<double>(1, 1), Cylinder<double>(1, 1), "cylinder-cylinder equal");
  expect_parallel_pairs(Cylinder<double>(1, 0.6), Cylinder<double>(0.7, 1.3), "cylinder-cylinder");
}

TEST(ParallelAxes, CylinderCone) {
  expect_parallel_pairs(Cylinder<double>(1, 1), Cone<double>(1, 1), "cylinder-cone");
  expect_parallel_pairs(Cone<double>(0.8, 1.2), Cylinder<double>(1, 0.6), "cone-cylinder");
}

TEST(ParallelAxes, ConeCone) {
  expect_parallel_pairs(Cone<double>(1, 1), Cone<double>(1, 1), "cone-cone equal");
  expect_parallel_pairs(Cone<double>(1, 0.6), Cone<double>(0.8, 1.2), "cone-cone");
}

// The closed form in the same case as the brief's defect: two coincident cylinders r = h = 1, and
// r = h = 0.0019 far from the origin, depth 2r across the axis or along it (a tie).
TEST(ParallelAxes, CoincidentCylindersExact) {
  for (const double r : {1.0, 0.0019}) {
    const Cylinder<double> c(r, r);
    RigidTransform<double> p;
    p.R = Eigen::AngleAxisd(0.7, Vec(1, 2, 3).normalized()).toRotationMatrix();
    p.t = r == 1.0 ? Vec(0.3, -0.2, 0.1) : Vec(-16, -16, -16);
    const auto hit = impact::convex_penetration(c, p, c, p);
    ASSERT_TRUE(hit.intersecting);
    EXPECT_FALSE(hit.limit_reached);
    EXPECT_NEAR(hit.depth, 2 * r, 1e-12 * r);
    EXPECT_LE(hit.depth_gap, 1e-10 * r);
  }
}

// A tilt between the axes beyond what the closed form certifies goes on to the other methods: the
// answer is still bracketed (depth an upper bound, depth - depth_gap a lower bound of the truth).
TEST(ParallelAxes, TiltedAxesStillBracketed) {
  const Cylinder<double> a(1, 0.6), b(0.7, 1.3);
  RigidTransform<double> pa;
  pa.R = Eigen::AngleAxisd(0.4, Vec(3, -1, 2).normalized()).toRotationMatrix();
  for (const double tilt : {1e-6, 1e-4}) {
    RigidTransform<double> pb = parallel_axes_pose(pa, false, Vec(0.3, 0.2, 0.1));
    pb.R = pb.R * Eigen::AngleAxisd(tilt, Vec(1, 1, 0).normalized()).toRotationMatrix();
    const auto c = impact::convex_penetration(a, pa, b, pb);
    ASSERT_TRUE(c.intersecting);
    // the support of b moves by at most tilt * |x| (x over b) from the parallel pair's
    const double parallel = meridian_oracle(a, pa, b, parallel_axes_pose(pa, false, Vec(0.3, 0.2, 0.1)));
    const double slack = tilt * std::sqrt(b.radius * b.radius + b.half_length * b.half_length) + 1e-9;
    EXPECT_LE(c.depth - c.depth_gap, parallel + slack) << tilt;
    EXPECT_GE(c.depth, parallel - slack) << tilt;
    EXPECT_GE(c.depth_gap, 0.0);
  }
}

// Coaxial shapes whose axes are tilted by a little more than the closed form accepts at the
// tolerance: their least-overlap normals nearly form a circle and EPA stops at its bound with a
// bracket of about 7.5e-5 of the size (1e-9 rad, after about 515 support calls). The closed form's
// bracket, about twice the tilt times b's reach, is the narrower and is the one returned.
template <class A, class B>
void expect_coaxial_tilt_bracketed(const A& a, const B& b, const std::string& what) {
  RigidTransform<double> pa;
  pa.R = Eigen::AngleAxisd(0.3, Vec(1, -2, 2).normalized()).toRotationMatrix();
  pa.t = Vec(0.25, -0.5, 1);
  const double reach = std::sqrt(b.radius * b.radius + b.half_length * b.half_length);
  for (const double tilt : {1e-9, 1e-8, 1e-7}) {
    RigidTransform<double> pb = parallel_axes_pose(pa, false, Vec::Zero());
    const double parallel = meridian_oracle(a, pa, b, pb);
    pb.R = pb.R * Eigen::AngleAxisd(tilt, Vec(1, 1, 0).normalized()).toRotationMatrix();
    const auto c = impact::convex_penetration(a, pa, b, pb);
    ASSERT_TRUE(c.intersecting) << what;
    const double slack = tilt * reach + 1e-12;
    EXPECT_LE(c.depth - c.depth_gap, parallel + slack) << what << " " << tilt;
    EXPECT_GE(c.depth, parallel - slack) << what << " " << tilt;
    EXPECT_LE(c.depth_gap, 4 * tilt * reach + 1e-12) << what << " " << tilt;
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12) << what;
  }
}

TEST(ParallelAxes, CoaxialTiltGetsTheClosedFormsBracket) {
  expect_coaxial_tilt_bracketed(Cylinder<double>(0.5, 2), Cylinder<double>(0.5, 2), "cylinders");
  expect_coaxial_tilt_bracketed(Cylinder<double>(0.5, 2), Cylinder<double>(0.7, 2.5), "cylinders of two sizes");
  expect_coaxial_tilt_bracketed(Cylinder<double>(0.5, 2), Cone<double>(0.7, 2.5), "cylinder and cone");
  expect_coaxial_tilt_bracketed(Cone<double>(0.5, 2), Cone<double>(0.7, 2.5), "cones");
}

}  // namespace
