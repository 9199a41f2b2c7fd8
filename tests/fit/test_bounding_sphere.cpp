// SPDX-License-Identifier: MIT
// Bounding spheres: every method encloses every point (float and double), on random, duplicate,
// collinear, coplanar and cospherical point sets; the exact method is minimal (checked against a
// brute force over all support sets of up to four points on small inputs) and never larger than
// the approximate methods.
#include "impact/fit/bounding_sphere.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace impact;
using impact::test::Rng;

namespace {

template <class S> using Points = std::vector<Vec3<S>>;

constexpr SphereFit kMethods[] = {SphereFit::AabbCenter, SphereFit::Centroid, SphereFit::Ritter, SphereFit::Exact};

template <class S> void expect_encloses(const Sphere<S>& s, const Points<S>& pts, const char* what) {
  for (const auto& p : pts) ASSERT_LE((p - s.center).norm(), s.radius) << what << " misses " << p.transpose();
}

template <class S> std::vector<Points<S>> point_sets() {
  std::vector<Points<S>> sets;
  Rng rng(42);
  for (int n : {1, 2, 3, 4, 5, 10, 100, 1000}) {
    Points<S> p;
    for (int i = 0; i < n; ++i) p.push_back(rng.vec(-1, 1).cast<S>());
    sets.push_back(p);
  }
  // duplicates
  sets.push_back(Points<S>(50, Vec3<S>(S(0.3), S(-2), S(7))));
  {
    Points<S> p;
    for (int i = 0; i < 40; ++i) p.push_back(Vec3<S>(S(i % 3), S(0), S(1)));
    sets.push_back(p);
  }
  // collinear
  {
    Points<S> p;
    for (int i = 0; i < 60; ++i) p.push_back(Vec3<S>(S(1), S(2), S(3)) + S(rng.uniform(-5, 5)) * Vec3<S>(S(1), S(-1), S(0.5)));
    sets.push_back(p);
  }
  // coplanar
  {
    Points<S> p;
    for (int i = 0; i < 80; ++i) p.push_back(Vec3<S>(S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), S(4)));
    sets.push_back(p);
  }
  // cospherical (many points on one sphere, including exact repeats)
  {
    Points<S> p;
    for (int i = 0; i < 200; ++i) {
      Eigen::Vector3d d = rng.vec(-1, 1);
      if (d.norm() < 1e-3) continue;
      p.push_back((Eigen::Vector3d(10, 10, 10) + 3.0 * d.normalized()).cast<S>());
    }
    p.push_back(p.front());
    sets.push_back(p);
  }
  // cube corners: 8 cospherical points with 4-point degenerate support sets
  {
    Points<S> p;
    for (int i = 0; i < 8; ++i) p.push_back(Vec3<S>(S(i & 1), S((i >> 1) & 1), S((i >> 2) & 1)));
    sets.push_back(p);
  }
  // large offset from the origin
  {
    Points<S> p;
    for (int i = 0; i < 100; ++i) p.push_back((Eigen::Vector3d(1e4, -1e4, 1e4) + rng.vec(-1, 1)).cast<S>());
    sets.push_back(p);
  }
  return sets;
}

/// Brute-force minimal ball radius over support sets of 1..4 points (small n only), in double.
double brute_force_min_radius(const Points<double>& p) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t n = p.size();
  auto consider = [&](const detail::Ball<double>& b) {
    const double r = std::sqrt(b.r2);
    if (r >= best) return;
    for (const auto& q : p)
      if ((q - b.c).norm() > r * (1 + 1e-9) + 1e-12) return;
    best = r;
  };
  for (std::size_t i = 0; i < n; ++i) {
    consider({p[i], 0.0});
    for (std::size_t j = i + 1; j < n; ++j) {
      consider(detail::ball_on_2(p[i], p[j]));
      for (std::size_t k = j + 1; k < n; ++k) {
        consider(detail::ball_on_3(p[i], p[j], p[k]));
        for (std::size_t l = k + 1; l < n; ++l) consider(detail::ball_on_4(p[i], p[j], p[k], p[l]));
      }
    }
  }
  return best;
}

}  // namespace

template <class S> class BoundingSphereTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(BoundingSphereTest, Scalars);

TYPED_TEST(BoundingSphereTest, EveryMethodEnclosesEveryPoint) {
  using S = TypeParam;
  for (const auto& pts : point_sets<S>()) {
    for (SphereFit m : kMethods) {
      const Sphere<S> s = bounding_sphere(pts, m);
      ASSERT_FALSE(s.empty());
      expect_encloses(s, pts, "method");
    }
  }
}

TYPED_TEST(BoundingSphereTest, ExactIsNeverLargerThanApproximations) {
  using S = TypeParam;
  for (const auto& pts : point_sets<S>()) {
    const S exact = bounding_sphere(pts, SphereFit::Exact).radius;
    for (SphereFit m : {SphereFit::AabbCenter, SphereFit::Centroid, SphereFit::Ritter}) {
      const S r = bounding_sphere(pts, m).radius;
      EXPECT_LE(exact, r * (S(1) + S(1e-5))) << "n=" << pts.size();
    }
  }
}

TYPED_TEST(BoundingSphereTest, EmptyInputGivesEmptySphere) {
  using S = TypeParam;
  EXPECT_TRUE(bounding_sphere(Points<S>{}, SphereFit::Exact).empty());
  EXPECT_TRUE(bounding_sphere(Points<S>{}).empty());
}

TEST(BoundingSphereExact, MatchesBruteForceMinimalBall) {
  Rng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + int(rng.index(9));
    Points<double> p;
    for (int i = 0; i < n; ++i) p.push_back(rng.vec(-1, 1));
    if (trial % 4 == 0) p.push_back(p[0]);                     // duplicate
    if (trial % 5 == 0) p.push_back(0.5 * (p[0] + p[1]));      // collinear
    const double expected = brute_force_min_radius(p);
    const double got = bounding_sphere(p, SphereFit::Exact).radius;
    EXPECT_NEAR(got, expected, 1e-9 * (1 + expected)) << "trial " << trial;
  }
}

TEST(BoundingSphereExact, KnownAnswers) {
  // regular tetrahedron corners of a cube: the minimal ball is the circumsphere
  Points<double> tet{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  auto s = bounding_sphere(tet, SphereFit::Exact);
  EXPECT_NEAR(s.radius, std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(s.center.norm(), 0.0, 1e-12);
  // right-angle corner: minimal ball is the circle of the opposite face, not the circumsphere
  Points<double> corner{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  s = bounding_sphere(corner, SphereFit::Exact);
  EXPECT_NEAR(s.radius, std::sqrt(2.0 / 3.0), 1e-12);
  // two points: the diametral ball
  s = bounding_sphere(Points<double>{{0, 0, 0}, {2, 0, 0}}, SphereFit::Exact);
  EXPECT_NEAR(s.radius, 1.0, 1e-12);
  EXPECT_NEAR((s.center - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-12);
}
