// SPDX-License-Identifier: MIT
// The cylinder–cylinder distance (convex/cylinder_pair_distance.hpp, convex_distance's path for the
// pair): poses built so that the nearest features are known (side against side, a cap against the
// other's lowest point, a rim against a side, rim against rim) with the distance in closed form or,
// for tilted rims, by a long-double search over one rim's angle; the answer must match to 1e-12 of
// the size, tighter than GJK's tolerance (1e-10), which only the certified candidates reach, both
// argument orders, under a random rigid motion of the pair. And random cylinders against the
// oracle's certified distance bracket (support/convex_oracle.hpp).
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

using namespace impact;

using Pose = RigidTransform<double>;

// The least distance from b's rim circle (centre c, orthonormal e1, e2, radius rb) to a's rim
// circle (radius ra about z at height za), by a scan of b's angle and golden-section refinement,
// in long double.
long double rim_rim_reference(const Eigen::Vector3d& c, const Eigen::Vector3d& e1, const Eigen::Vector3d& e2, double rb, double ra,
                              double za) {
  const auto g = [&](long double t) {
    const long double x = c.x() + rb * (std::cos(t) * e1.x() + std::sin(t) * e2.x());
    const long double y = c.y() + rb * (std::cos(t) * e1.y() + std::sin(t) * e2.y());
    const long double z = c.z() + rb * (std::cos(t) * e1.z() + std::sin(t) * e2.z());
    const long double q = std::sqrt(x * x + y * y) - ra, h = z - za;
    return std::sqrt(q * q + h * h);
  };
  const int n = 3600;
  int best = 0;
  for (int i = 1; i < n; ++i)
    if (g(2 * M_PIl * i / n) < g(2 * M_PIl * best / n)) best = i;
  long double lo = 2 * M_PIl * (best - 1) / n, hi = 2 * M_PIl * (best + 1) / n;
  for (int k = 0; k < 200; ++k) {
    const long double m1 = lo + (hi - lo) * 0.381966L, m2 = hi - (hi - lo) * 0.381966L;
    if (g(m1) < g(m2))
      hi = m2;
    else
      lo = m1;
  }
  return g((lo + hi) / 2);
}

// The distance of the pose (b at Rb, tb in a's frame) in both argument orders under a random
// rigid motion G of the pair, against `exact`.
void expect_distance(const Cylinder<double>& a, const Cylinder<double>& b, const Eigen::Matrix3d& Rb, const Eigen::Vector3d& tb,
                     double exact, test::Rng& rng, const char* what) {
  const Pose G{rng.rotation(), rng.vec(-2, 2)};
  const Pose pa = G, pb{G.R * Rb, G.apply(tb)};
  const double scale = std::max(shape_size(a), shape_size(b));
  const ConvexDistance<double> ab = convex_distance(a, pa, b, pb), ba = convex_distance(b, pb, a, pa);
  for (const auto* d : {&ab, &ba}) {
    EXPECT_FALSE(d->intersecting) << what;
    EXPECT_FALSE(d->limit_reached) << what;
    EXPECT_NEAR(d->distance, exact, 1e-12 * scale) << what;
    EXPECT_NEAR((d->point_a - d->point_b).norm(), d->distance, 1e-12 * scale) << what;
  }
  // the witnesses are points of their cylinders
  const Eigen::Vector3d xa = pa.R.transpose() * (ab.point_a - pa.t), xb = pb.R.transpose() * (ab.point_b - pb.t);
  EXPECT_LE(std::hypot(xa.x(), xa.y()), a.radius + 1e-12) << what;
  EXPECT_LE(std::abs(xa.z()), a.half_length + 1e-12) << what;
  EXPECT_LE(std::hypot(xb.x(), xb.y()), b.radius + 1e-12) << what;
  EXPECT_LE(std::abs(xb.z()), b.half_length + 1e-12) << what;
}

TEST(CylinderPairDistance, NearestFeaturesInClosedForm) {
  test::Rng rng(1512);
  for (int k = 0; k < 12; ++k) {
    const Cylinder<double> a(rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0)), b(rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0));
    const double ra = a.radius, ha = a.half_length, rb = b.radius, hb = b.half_length;
    {  // side against side: b's axis horizontal at angle al, the common normal (-sin al, cos al, 0)
      const double al = rng.uniform(0.3, 1.3), D = ra + rb + rng.uniform(0.01, 0.5), s = rng.uniform(-0.8, 0.8) * ha;
      const Eigen::Matrix3d Rb = Eigen::AngleAxisd(al, Eigen::Vector3d::UnitZ()).toRotationMatrix() * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
      expect_distance(a, b, Rb, Eigen::Vector3d(-D * std::sin(al), D * std::cos(al), s), D - ra - rb, rng, "side-side");
    }
    {  // a's top cap against b's lowest point, b tilted by phi about x
      const double phi = rng.uniform(0.2, 1.2), gap = rng.uniform(0.01, 0.5);
      const Eigen::Matrix3d Rb = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX()).toRotationMatrix();
      // b's lowest point is (0, hb sin phi - rb cos phi, -hb cos phi - rb sin phi) from its centre
      const double y = 0.3 * ra - (hb * std::sin(phi) - rb * std::cos(phi));
      expect_distance(a, b, Rb, Eigen::Vector3d(0.1 * ra, y, ha + gap + hb * std::cos(phi) + rb * std::sin(phi)), gap, rng, "cap-rim");
    }
    {  // a's top rim against b's side: b's axis along x through (0, ra, ha) + D (cos psi, sin psi)
      const double D = rb + rng.uniform(0.02, 0.5), psi = rng.uniform(0.2, 1.3);
      const Eigen::Matrix3d Rb = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
      expect_distance(a, b, Rb, Eigen::Vector3d(0, ra + D * std::cos(psi), ha + D * std::sin(psi)), D - rb, rng, "rim-side");
    }
    {  // a's top rim against b's bottom rim: b beside a along x and above it, tilted by phi about x
      // (every point of b's rim above a's cap plane and outside its radius, and neither b's side
      // nor its cap facing a)
      const double phi = rng.uniform(-0.3, 0.3), dx = rng.uniform(0.05, 0.4), dz = rb * std::abs(std::sin(phi)) + rng.uniform(0.05, 0.4);
      const Eigen::Matrix3d Rb = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitX()).toRotationMatrix();
      const Eigen::Vector3d tb(ra + rb + dx, 0.1 * rb, ha + hb + dz);
      const long double ref = rim_rim_reference(Eigen::Vector3d(tb - hb * Rb.col(2)), Rb.col(0), Rb.col(1), rb, ra, ha);
      expect_distance(a, b, Rb, tb, double(ref), rng, "rim-rim");
    }
  }
}

TEST(CylinderPairDistance, MatchesTheOracleBracket) {
  test::Rng rng(1515);
  const int n = IMPACT_TEST_SANITIZED ? 40 : 300;
  int compared = 0;
  for (int k = 0; k < n; ++k) {
    const Cylinder<double> a(rng.uniform(0.02, 1.0), rng.uniform(0.02, 1.0)), b(rng.uniform(0.02, 1.0), rng.uniform(0.02, 1.0));
    const double scale = std::max(shape_size(a), shape_size(b)), reach = 1.2 * (shape_size(a) + shape_size(b));
    const Pose pa{rng.rotation(), rng.vec(-2, 2)};
    const Pose pb{k % 10 == 0 ? pa.R : rng.rotation(), Eigen::Vector3d(pa.t + rng.vec(-reach, reach))};
    const auto br = test::distance_bracket(a, pa, b, pb, 600);
    if (!(br.lower > 1e-6 * scale)) continue;
    ++compared;
    const ConvexDistance<double> d = convex_distance(a, pa, b, pb);
    EXPECT_FALSE(d.intersecting) << "pose " << k;
    EXPECT_GE(d.distance, br.lower - 1e-12 * scale) << "pose " << k;
    EXPECT_LE(d.distance, br.upper + 1e-10 * scale) << "pose " << k;
  }
  EXPECT_GT(compared, n / 2);
}

// max_iterations is one budget for the whole query (the boolean test's GJK, the coarse run and the
// run to the tolerance share it): on the random poses that need more than 12 support calls (the
// run to the tolerance after the candidates; and every hundredth of the rest), under every bound
// from 1 to 2 past the full query's calls, the reported calls stay within the bound; a bound above
// the full query's calls (and the certificate's one) changes nothing; and a bounded answer without
// limit_reached is the full one.
TEST(CylinderPairDistance, IterationBoundIsOneBudget) {
  test::Rng rng(1516);
  const int n = IMPACT_TEST_SANITIZED ? 1000 : 4000;
  int checked = 0, limited = 0;
  for (int k = 0; k < n; ++k) {
    const Cylinder<double> a(rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0)), b(rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0));
    const double scale = std::max(shape_size(a), shape_size(b)), reach = 0.8 * (shape_size(a) + shape_size(b));
    const Pose pa{rng.rotation(), rng.vec(-2, 2)};
    const Pose pb{rng.rotation(), Eigen::Vector3d(pa.t + rng.vec(-reach, reach))};
    const ConvexDistance<double> full = convex_distance(a, pa, b, pb);
    ASSERT_FALSE(full.limit_reached) << "pose " << k;
    if (full.iterations <= 12 && k % 100 != 0) continue;
    ++checked;
    for (int m = 1; m <= full.iterations + 2; ++m) {
      ConvexQueryOptions<double> o;
      o.max_iterations = m;
      const ConvexDistance<double> d = convex_distance(a, pa, b, pb, o);
      EXPECT_LE(d.iterations, m) << "pose " << k << " bound " << m;
      if (d.limit_reached) {
        ++limited;
        if (!d.intersecting) {
          EXPECT_GE(d.distance, full.distance - 1e-10 * scale) << "pose " << k << " bound " << m;  // an upper bound
        }
        continue;
      }
      EXPECT_EQ(d.intersecting, full.intersecting) << "pose " << k << " bound " << m;
      EXPECT_NEAR(d.distance, full.distance, 1e-10 * scale) << "pose " << k << " bound " << m;
      if (full.iterations + 1 <= m) {
        EXPECT_EQ(d.distance, full.distance) << "pose " << k << " bound " << m;
        EXPECT_EQ(d.iterations, full.iterations) << "pose " << k << " bound " << m;
      }
    }
  }
  EXPECT_GT(checked, n / 50);
  EXPECT_GT(limited, 2 * checked);
}

}  // namespace
