// SPDX-License-Identifier: MIT
// The certified cone–box candidates (convex/cone_box_pair.hpp) and the cone–box penetration
// (convex/query.hpp: candidates, EPA and the local certificate on convex/cone_box_terms.hpp)
// against an oracle: the penetration depth as the least overlap f(n) = h_cone(n) + h_box(-n)
// over unit directions, each support function in closed form in long double (the cone's apex or
// base rim, the box's centre and three abs terms), minimised by test::least_overlap
// (support/convex_oracle.hpp). The oracle's minimum is an upper bound of the true depth, and every
// certified lower bound lies below the true depth, so a certificate that certifies a wrong (too
// large) depth shows as depth - depth_gap above the oracle.
#include "impact/convex/cone_box_pair.hpp"
#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

using namespace impact;
using LD = long double;
using V3L = Eigen::Matrix<LD, 3, 1>;

// The overlap along unit n of cone a (its frame) and box b placed by R, t there, in long double.
LD overlap_ld(const Cone<double>& a, const Box<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const V3L& n) {
  const LD h = a.half_length, r = a.radius;
  const LD cone = std::max(h * n.z(), r * std::sqrt(n.x() * n.x() + n.y() * n.y()) - h * n.z());
  LD box = -(LD(t.x()) * n.x() + LD(t.y()) * n.y() + LD(t.z()) * n.z());
  for (int i = 0; i < 3; ++i) box += LD(b.half[i]) * std::abs(LD(R(0, i)) * n.x() + LD(R(1, i)) * n.y() + LD(R(2, i)) * n.z());
  return cone + box;
}

// The least overlap by test::least_overlap: the kink circles normal to the box's axes (its edges)
// and the cone's side normals (where its apex and base rim tie: n_z = r / sqrt(4h^2 + r^2)), the
// box's six face normals, the cone's axis both ways and `extra` (the normal under test: the search
// may only find lower overlaps than there) as starts.
LD depth_oracle(const Cone<double>& a, const Box<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Eigen::Vector3d& extra) {
  const auto f = [&](const V3L& n) { return overlap_ld(a, b, R, t, n); };
  std::vector<Eigen::Vector3d> starts;
  for (int i = 0; i < 3; ++i) {
    starts.push_back(R.col(i));
    starts.push_back(-R.col(i));
  }
  starts.push_back(Eigen::Vector3d::UnitZ());
  starts.push_back(-Eigen::Vector3d::UnitZ());
  starts.push_back(extra);
  const double side = a.radius / std::sqrt(4 * a.half_length * a.half_length + a.radius * a.radius);
  const std::vector<test::KinkCircle> circles = {{R.col(0), 0}, {R.col(1), 0}, {R.col(2), 0}, {Eigen::Vector3d::UnitZ(), side}};
  return test::least_overlap(f, starts, circles).depth;
}

struct Case {
  Cone<double> cone{0.5, 0.6};
  Box<double> box{Eigen::Vector3d(0.4, 0.3, 0.5)};
  RigidTransform<double> pa, pb;
};

// Cones and boxes of varied proportions (the zoo's first), b about a.
std::vector<Case> cases(int n, std::uint64_t seed) {
  test::Rng rng(seed);
  std::vector<Case> out;
  for (int k = 0; k < n; ++k) {
    Case c;
    if (k % 4 != 0) {
      c.cone = Cone<double>(rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0));
      c.box = Box<double>(Eigen::Vector3d(rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0)));
    }
    const double reach = 0.6 * (shape_size(c.cone) + shape_size(c.box));
    c.pa = {rng.rotation(), rng.vec(-1, 1)};
    c.pb = {rng.rotation(), Eigen::Vector3d(c.pa.t + rng.vec(-reach, reach))};
    out.push_back(c);
  }
  return out;
}

// Each certified candidate: its lower bound below the oracle's depth (an upper bound of the true
// one), its depth within the tolerance of it, its depth the overlap along its normal.
TEST(ConeBoxPair, CertifiedDepthsAgainstTheOracle) {
  int certified = 0, face = 0, body = 0, compared = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 24 : 200, 515)) {
    const double scale = std::max(shape_size(c.cone), shape_size(c.box)), tol = 1e-10 * scale;
    const detail::PairFrame<double> f(c.pa, c.pb);
    ConvexContact<double> k;
    if (!detail::cone_box_contact(c.cone, c.box, f.R, f.t, tol, k)) continue;
    ++certified;
    const double oracle = double(depth_oracle(c.cone, c.box, f.R, f.t, k.normal));
    EXPECT_GT(oracle, 0) << "certified a pair the oracle finds apart";
    EXPECT_LE(k.depth - k.depth_gap, oracle + 1e-12 * scale) << "lower bound above the depth";
    EXPECT_NEAR(k.depth, oracle, 1e-9 * scale);
    EXPECT_NEAR(double(overlap_ld(c.cone, c.box, f.R, f.t, k.normal.cast<LD>())), k.depth, 1e-12 * scale);
    ++compared;
    ++((f.R.transpose() * k.normal).cwiseAbs().maxCoeff() > 1 - 1e-12 ? face : body);
  }
  // both kinds of candidate certified (24 cases under the sanitizers: one or two of each)
  EXPECT_GT(face, IMPACT_TEST_SANITIZED ? 0 : 5);
  EXPECT_GT(body, IMPACT_TEST_SANITIZED ? 0 : 5);
  EXPECT_EQ(compared, certified);
}

// The local certificate on the body inside the cone along a side ruling (cone_box_side_certificate,
// convex/cone_box_terms.hpp), at each box edge's side normal as the edge candidate takes it
// (the side normal orthogonal to the edge): where it holds as the query accepts it (the overlap
// along its normal within the tolerance of its lower bound), that bound is at most the oracle's
// overlap (long double) at its normal and at every direction sampled in its cap (random ones
// and ones along the two kink circles through it: the ruling's side normals and the directions
// normal to the edge), so the certificate is a true bound there. Checked to fail: the body's disc
// as large as the base (add_cone_side_body's radius rc instead of rc (1 - s1): a body outside
// the cone).
TEST(ConeBoxPair, SideCertificatesBoundTheOverlapOnTheirCaps) {
  test::Rng rng(518);
  int held = 0, sampled = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 40 : 300, 517)) {
    const double scale = std::max(shape_size(c.cone), shape_size(c.box)), tol = 1e-10 * scale;
    const detail::PairFrame<double> f(c.pa, c.pb);
    const auto overlap = [&](const Eigen::Vector3d& w) { return overlap_ld(c.cone, c.box, f.R, f.t, w.cast<LD>()); };
    const double r = c.cone.radius, h = c.cone.half_length, L = std::sqrt(4 * h * h + r * r);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d d = f.R.col(i);
      const double m2 = d.x() * d.x() + d.y() * d.y(), k = -r * d.z() / (2 * h);
      if (!(m2 > 1e-12) || k * k >= m2) continue;
      for (const double sign : {1.0, -1.0}) {
        const double along = k / m2, across = std::sqrt(m2 - k * k) / m2;
        const double ux = along * d.x() - sign * across * d.y(), uy = along * d.y() + sign * across * d.x();
        const Eigen::Vector3d n(2 * h * ux / L, 2 * h * uy / L, r / L);
        const auto lc = detail::cone_box_side_certificate(c.cone, c.box, f.R, f.t, n);
        if (!lc.ok || !(double(overlap(lc.normal)) - lc.lower <= tol)) continue;
        ++held;
        EXPECT_LE(lc.lower, double(overlap(lc.normal)) + 1e-12 * scale) << "bound above the overlap at its normal";
        EXPECT_NEAR(lc.upper, double(overlap(lc.normal)), 1e-12 * scale);
        // directions in the cap: n* + y, |y| <= tan(cap), y normal to n*
        const Eigen::Vector3d e1 = detail::any_orthogonal(lc.normal), e2 = lc.normal.cross(e1);
        const double T = std::tan(lc.cap);
        std::vector<Eigen::Vector3d> dirs;
        for (int j = 0; j < 24; ++j) {
          const double a = rng.uniform(0, 2 * M_PI), rad = T * std::sqrt(rng.uniform(0, 1));
          dirs.push_back((lc.normal + rad * (std::cos(a) * e1 + std::sin(a) * e2)).normalized());
        }
        // along the ruling's side normals (azimuth turned) and normal to the edge (about d)
        const Eigen::Vector3d az(lc.normal.x(), lc.normal.y(), 0);
        for (int j = 1; j <= 6; ++j) {
          const double a = lc.cap * j / 6.0;
          for (const double s : {a, -a}) {
            const Eigen::Vector3d u = Eigen::AngleAxisd(s, Eigen::Vector3d::UnitZ()) * az.normalized();
            dirs.push_back(Eigen::Vector3d(2 * h * u.x() / L, 2 * h * u.y() / L, r / L));
            dirs.push_back(Eigen::AngleAxisd(s, d) * lc.normal);
          }
        }
        for (const Eigen::Vector3d& w : dirs) {
          if (!(w.dot(lc.normal) >= lc.cos_cap)) continue;
          ++sampled;
          EXPECT_LE(lc.lower, double(overlap(w)) + 1e-12 * scale) << "bound above the overlap in its cap";
        }
      }
    }
  }
  EXPECT_GT(held, IMPACT_TEST_SANITIZED ? 3 : 40);
  EXPECT_GT(sampled, 20 * held);
}

// The whole query, both argument orders, on every intersecting pose (candidates, EPA with the
// local certificate): depth within 1e-9 of the size of the oracle's, never a lower bound above it.
TEST(ConeBoxPair, PenetrationAgainstTheOracle) {
  int hits = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 16 : 120, 516)) {
    const double scale = std::max(shape_size(c.cone), shape_size(c.box));
    const detail::PairFrame<double> f(c.pa, c.pb);
    const auto p = convex_penetration(c.cone, c.pa, c.box, c.pb);
    const auto q = convex_penetration(c.box, c.pb, c.cone, c.pa);
    const double oracle = double(depth_oracle(c.cone, c.box, f.R, f.t, p.intersecting ? Eigen::Vector3d(c.pa.R.transpose() * p.normal) : Eigen::Vector3d(Eigen::Vector3d::UnitZ())));
    if (std::abs(oracle) < 1e-6 * scale) continue;  // touching: either answer
    EXPECT_EQ(p.intersecting, oracle > 0);
    EXPECT_EQ(q.intersecting, oracle > 0);
    if (oracle < 0 || !p.intersecting || !q.intersecting) continue;
    ++hits;
    for (const auto& r : {p, q}) {
      EXPECT_LE(r.depth - r.depth_gap, oracle + 1e-12 * scale) << "lower bound above the depth";
      EXPECT_NEAR(r.depth, oracle, 1e-9 * scale);
      EXPECT_FALSE(r.limit_reached);
    }
  }
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 3 : 30);
}

}  // namespace
