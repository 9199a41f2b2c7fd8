// SPDX-License-Identifier: MIT
// GJK's separation distance (convex/gjk_distance.hpp, through convex_distance) against closed forms
// on poses where a flat side of one shape faces a flat side of the other, parallel or nearly so:
//   - two parallel cylinders (b spun about its axis, or flipped), shifted side by side, cap over
//     cap, or rim past rim: distance = hypot(max(0, rho - ra - rb), max(0, |dz| - ha - hb)), rho
//     and dz the offset of b's centre across and along a's axis;
//   - a cylinder's cap or a cone's base tilted by 1e-4 .. 1e-12 rad over a cylinder's cap or a
//     box's top face (1e-4 .. 3e-5 in float), its lowest point above that face: distance = the height of the lowest point
//     of b's disc (centre c, axis u, radius r: c.z - r |u_xy|) above the face.
// A flat disc's support points are rim points, never the face's inner points, so near the closest
// point the Minkowski difference offers GJK no vertices: GJK stopped there when a step's closest
// point came no nearer within the rounding of |v|^2, 3.7e-9 of the size from the distance on the
// nearly parallel caps (the tolerance is 1e-10). Stated tolerance here: the distance within
// relative_tolerance of the size (1e-10 double, 1e-5 float) plus rounding, never below the truth
// by more than rounding; the witness points that distance apart.
#include "impact/convex/query.hpp"
#include "impact/convex/signed_volumes.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <type_traits>

namespace {

using namespace impact;

template <class S>
struct GjkClosedFormStats {
  double worst = 0;  // the largest |distance - closed form| relative to the size
  int count = 0;
};

template <class S, class A, class B>
void expect_gjk_distance(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, double exact,
                         GjkClosedFormStats<S>& stats, const char* name) {
  const ConvexQueryOptions<S> o;
  const double scale = std::max(double(shape_size(a)), double(shape_size(b)));
  const double rounding = (std::is_same_v<S, float> ? 64.0 : 1e4) * std::numeric_limits<S>::epsilon() * scale;
  const double tol = double(o.relative_tolerance) * scale;
  for (int order = 0; order < 2; ++order) {
    const ConvexDistance<S> d = order == 0 ? convex_distance(a, pa, b, pb) : convex_distance(b, pb, a, pa);
    const double err = double(d.distance) - exact;
    stats.worst = std::max(stats.worst, std::abs(err) / scale);
    ++stats.count;
    EXPECT_FALSE(d.intersecting) << name;
    EXPECT_FALSE(d.limit_reached) << name;
    EXPECT_LE(err, tol + rounding) << name << (order ? " (swapped)" : "") << ": distance " << d.distance << ", closed form " << exact;
    EXPECT_GE(err, -rounding) << name << (order ? " (swapped)" : "") << ": distance " << d.distance << ", closed form " << exact;
    EXPECT_NEAR(double((d.point_b - d.point_a).norm()), double(d.distance), tol + rounding) << name;
  }
}

template <class S>
Mat3<S> gjk_random_rotation(test::Rng& rng) {
  Eigen::Quaternion<S> q(S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)));
  q.normalize();
  return q.toRotationMatrix();
}

template <class S>
Mat3<S> spin_about_axis(double angle) {
  return Eigen::AngleAxis<S>(S(angle), Vec3<S>::UnitZ()).toRotationMatrix();
}

template <class S>
void parallel_cylinders(int n, std::uint64_t seed) {
  test::Rng rng(seed);
  GjkClosedFormStats<S> stats;
  for (int i = 0; i < n; ++i) {
    const double ra = rng.uniform(0.2, 0.7), ha = rng.uniform(0.2, 0.7), rb = rng.uniform(0.2, 0.7), hb = rng.uniform(0.2, 0.7);
    const Cylinder<S> a{S(ra), S(ha)}, b{S(rb), S(hb)};
    const Mat3<S> R = gjk_random_rotation<S>(rng);
    Mat3<S> Rb = R * spin_about_axis<S>(rng.uniform(-3, 3));
    if (i % 2) Rb = Rb * Eigen::AngleAxis<S>(S(3.141592653589793), Vec3<S>::UnitX()).toRotationMatrix();
    double rho = 0, dz = 0;
    switch (i % 3) {
      case 0:  // side by side
        rho = ra + rb + rng.uniform(0.01, 0.6);
        dz = (ha + hb) * rng.uniform(-0.99, 0.99);
        break;
      case 1:  // cap over cap
        rho = (ra + rb) * rng.uniform(0, 0.99);
        dz = (ha + hb + rng.uniform(0.01, 0.6)) * (rng.uniform(0, 1) < 0.5 ? -1 : 1);
        break;
      default:  // rim past rim
        rho = ra + rb + rng.uniform(0.01, 0.6);
        dz = (ha + hb + rng.uniform(0.01, 0.6)) * (rng.uniform(0, 1) < 0.5 ? -1 : 1);
    }
    const double angle = rng.uniform(-3, 3);
    const Vec3<S> offset(S(rho * std::cos(angle)), S(rho * std::sin(angle)), S(dz));
    const Vec3<S> ta(S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)));
    const RigidTransform<S> pa(R, ta), pb(Rb, Vec3<S>(ta + R * offset));
    // the closed form from the offset as the poses hold it (b's centre in a's frame)
    const Vec3<S> c = pa.inverse().apply(pb.t);
    const double r = std::hypot(double(c.x()), double(c.y()));
    const double exact = std::hypot(std::max(0.0, r - ra - rb), std::max(0.0, std::abs(double(c.z())) - ha - hb));
    expect_gjk_distance(a, pa, b, pb, exact, stats, "parallel cylinders");
  }
  std::printf("parallel cylinders (%s): %d distances, max error %.2e of the size\n", std::is_same_v<S, float> ? "float" : "double",
              stats.count, stats.worst);
}

// b's flat bottom (a cylinder's cap or a cone's base: radius rb at -hb along its axis) tilted by
// `tilt` over the top face of a (at height top_a, holding the disc of radius inner_a about its
// axis), its lowest point over that disc.
template <class S, class A, class B>
void tilted_disc_over_face(const char* name, const A& a, double top_a, double inner_a, const B& b, double rb, double hb, int n,
                           double min_tilt_exponent, std::uint64_t seed) {
  test::Rng rng(seed);
  GjkClosedFormStats<S> stats;
  for (int i = 0; i < n; ++i) {
    const double tilt = std::pow(10.0, rng.uniform(min_tilt_exponent, -4.0));
    const double phi = rng.uniform(-3, 3);
    const Mat3<S> Rl = Eigen::AngleAxis<S>(S(tilt), Vec3<S>(S(std::cos(phi)), S(std::sin(phi)), S(0))).toRotationMatrix() *
                       spin_about_axis<S>(rng.uniform(-3, 3));
    const Vec3<S> u = Rl.col(2);  // b's axis in a's frame
    // the lowest point of b's bottom disc at (x, y, top_a + gap): the disc's centre is rb up the slope from it
    const double gap = rng.uniform(0.01, 0.8), rad = inner_a * rng.uniform(0, 0.95), ang = rng.uniform(-3, 3);
    const double uxy = std::hypot(double(u.x()), double(u.y()));
    const Vec3<S> downhill(S(double(u.z()) * double(u.x()) / uxy), S(double(u.z()) * double(u.y()) / uxy), S(-uxy));
    const Vec3<S> lowest(S(rad * std::cos(ang)), S(rad * std::sin(ang)), S(top_a + gap));
    const Vec3<S> centre = lowest - S(rb) * downhill + S(hb) * u;
    const Mat3<S> R = gjk_random_rotation<S>(rng);
    const Vec3<S> ta(S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)));
    const RigidTransform<S> pa(R, ta), pb(R * Rl, Vec3<S>(ta + R * centre));
    // the closed form from the poses as they hold b, in double (in a's frame: bottom centre c, axis w)
    const RigidTransform<double> rel = RigidTransform<double>(pa.R.template cast<double>(), pa.t.template cast<double>()).inverse() *
                                       RigidTransform<double>(pb.R.template cast<double>(), pb.t.template cast<double>());
    const Eigen::Vector3d w = rel.R.col(2), c = rel.t - hb * w;
    const double wxy = std::hypot(w.x(), w.y());
    const double exact = c.z() - rb * wxy - top_a;
    const double low_x = c.x() + rb * w.z() * w.x() / wxy, low_y = c.y() + rb * w.z() * w.y() / wxy;
    ASSERT_LT(std::hypot(low_x, low_y), inner_a) << name << ": the lowest point must lie over the face";
    expect_gjk_distance(a, pa, b, pb, exact, stats, name);
  }
  std::printf("%-22s (%s): %d distances, max error %.2e of the size\n", name, std::is_same_v<S, float> ? "float" : "double", stats.count,
              stats.worst);
}

template <class S>
void tilted_discs(int n, double min_tilt_exponent) {
  const Cylinder<S> cyl(S(0.4), S(0.5));
  const Cone<S> cone(S(0.5), S(0.6));
  const Box<S> box(Vec3<S>(S(0.5), S(0.4), S(0.3)));
  tilted_disc_over_face<S>("cylinder over cylinder", cyl, 0.5, 0.4, cyl, 0.4, 0.5, n, min_tilt_exponent, 1);
  tilted_disc_over_face<S>("cone over cylinder", cyl, 0.5, 0.4, cone, 0.5, 0.6, n, min_tilt_exponent, 2);
  tilted_disc_over_face<S>("cylinder over box", box, 0.3, 0.4, cyl, 0.4, 0.5, n, min_tilt_exponent, 3);
  tilted_disc_over_face<S>("cone over box", box, 0.3, 0.4, cone, 0.5, 0.6, n, min_tilt_exponent, 4);
}

// GJK's simplex solver alone (detail::sv_closest, convex/signed_volumes.hpp) on slivers whose
// closest point to the origin is inside: a segment, or a triangle whose apex lies at a height h of
// 1e-6 .. 1e-1 of its base L above the base (1e-3 .. 1e-1 in float), the origin's foot between the base and the apex, all
// in a plane at distance d from the origin, turned at random. The distance is d up to the points'
// rounding (the foot's height over the plane is a convex combination of the vertices' heights, so
// rounding a vertex by e moves it by at most e), so |v| must be d within a few ulps of the points.
// Formed as l1 s1 + l2 s2 + l3 s3 (weights that do not sum to 1 scale v) the error grew as L / h:
// up to 185,000 ulps here in double, 205 in float; some 1,000 ulps of |v|^2 on a 1e-3 sliver were
// enough to stop GJK early on one compiler's rounding and not the other's; now 3 and 1 ulps.
template <class S>
void sliver_closest_points(int n, double min_height_exponent, std::uint64_t seed) {
  test::Rng rng(seed);
  double worst = 0;  // the largest | |v| - d | in ulps of the largest point
  for (int i = 0; i < n; ++i) {
    const double d = rng.uniform(0.05, 1), l1 = rng.uniform(0.5, 1), l2 = rng.uniform(0.5, 1);
    const double h = (l1 + l2) * std::pow(10.0, rng.uniform(min_height_exponent, -1)), f = rng.uniform(0.05, 0.5);
    const double apex_x = rng.uniform(-0.3 * l1, 0.3 * l2);
    const bool segment = i % 4 == 0;
    // local frame: the base along x at y = -f h, the apex at y = (1 - f) h, the plane z = d
    const Eigen::Vector3d local[3] = {{-l1, segment ? 0 : -f * h, d}, {l2, segment ? 0 : -f * h, d}, {apex_x, (1 - f) * h, d}};
    const Eigen::Matrix3d R = gjk_random_rotation<double>(rng);
    detail::SimplexPoint<S> p[3];
    double size = 0;
    for (int k = 0; k < 3; ++k) {
      p[k].w = (R * local[k]).template cast<S>();
      p[k].a = p[k].w;
      p[k].b = Vec3<S>::Zero();
      size = std::max(size, double(p[k].w.norm()));
    }
    detail::SimplexClosest<S> r;
    ASSERT_TRUE(detail::sv_closest(p, segment ? 2 : 3, r));
    ASSERT_EQ(r.m, segment ? 2 : 3) << "the origin's foot is inside";
    double sum = 0;
    for (int k = 0; k < r.m; ++k) {
      EXPECT_GT(r.lambda[k], S(0));
      sum += double(r.lambda[k]);
    }
    const double ulp = std::numeric_limits<S>::epsilon() * size;
    EXPECT_NEAR(sum, 1.0, 4 * std::numeric_limits<S>::epsilon());
    const double err = std::abs(std::sqrt(double(r.vv)) - d);
    worst = std::max(worst, err / ulp);
    EXPECT_LE(err, 8 * ulp) << (segment ? "segment" : "triangle") << " h/L " << h / (l1 + l2) << ": |v| " << std::sqrt(double(r.vv))
                            << ", distance " << d;
  }
  std::printf("sliver closest points (%s): %d simplices, max error %.1f ulps of the points\n", std::is_same_v<S, float> ? "float" : "double", n,
              worst);
}

constexpr int kGjkClosedFormPoses = IMPACT_TEST_SANITIZED ? 200 : 2000;

TEST(GjkClosedForm, SliverSimplexClosestPointDouble) { sliver_closest_points<double>(kGjkClosedFormPoses, -6, 33); }
TEST(GjkClosedForm, SliverSimplexClosestPointFloat) { sliver_closest_points<float>(kGjkClosedFormPoses, -3, 34); }

TEST(GjkClosedForm, ParallelCylindersDouble) { parallel_cylinders<double>(kGjkClosedFormPoses, 31); }
TEST(GjkClosedForm, ParallelCylindersFloat) { parallel_cylinders<float>(kGjkClosedFormPoses, 32); }
TEST(GjkClosedForm, NearlyParallelFlatSidesDouble) { tilted_discs<double>(kGjkClosedFormPoses, -12.0); }
// float's rotations carry 1e-7 of noise: tilts down to 3e-5
TEST(GjkClosedForm, NearlyParallelFlatSidesFloat) { tilted_discs<float>(kGjkClosedFormPoses, -4.5); }

}  // namespace
