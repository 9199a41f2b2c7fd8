// SPDX-License-Identifier: MIT
// The certified cone–box candidates (convex/cone_box_pair.hpp) and the cone–box penetration
// (convex/query.hpp: candidates, EPA and the local certificate on convex/cone_box_terms.hpp)
// against an oracle written here: the penetration depth as the least overlap
// f(n) = h_cone(n) + h_box(-n) over unit directions, each support function in closed form in long
// double (the cone's apex or base rim, the box's centre and three abs terms), minimised by
// Fibonacci samples and grids about the best ones (each moved while it improves, then shrunk). The oracle's minimum is an upper bound
// of the true depth, and every certified lower bound lies below the true depth, so a certificate
// that certifies a wrong (too large) depth shows as depth - depth_gap above the oracle.
#include "impact/convex/cone_box_pair.hpp"
#include "impact/convex/query.hpp"
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

// The least overlap found: 1500 Fibonacci directions, then about each of the 3 best, the box's
// six face normals and `extra` (the normal under test: the search may only find lower overlaps
// than there) a 13 x 13 grid over a cap (moved to its best point while that improves) shrinking
// threefold per level to 1e-13 rad.
LD depth_oracle(const Cone<double>& a, const Box<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Eigen::Vector3d& extra) {
  const int samples = 1500;
  std::vector<std::pair<LD, V3L>> coarse;
  const LD golden = LD(M_PI) * (3 - std::sqrt(LD(5)));
  for (int i = 0; i < samples; ++i) {
    const LD z = 1 - (2 * i + LD(1)) / samples, rr = std::sqrt(1 - z * z);
    const V3L n(rr * std::cos(golden * i), rr * std::sin(golden * i), z);
    coarse.emplace_back(overlap_ld(a, b, R, t, n), n);
  }
  std::partial_sort(coarse.begin(), coarse.begin() + 3, coarse.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  for (int i = 0; i < 3; ++i) {  // the box's face normals and the answer under test start too
    for (const double sign : {1.0, -1.0}) coarse[static_cast<std::size_t>(3 + 2 * i + (sign < 0))] = {overlap_ld(a, b, R, t, (sign * R.col(i)).cast<LD>()), (sign * R.col(i)).cast<LD>()};
  }
  coarse[9] = {overlap_ld(a, b, R, t, extra.cast<LD>()), extra.cast<LD>()};
  LD best = coarse[0].first;
  for (int s = 0; s < 10; ++s) {
    V3L n = coarse[static_cast<std::size_t>(s)].second;
    LD fn = coarse[static_cast<std::size_t>(s)].first;
    for (LD cap = LD(0.2); cap > LD(1e-13); cap /= 3) {
      // the grid about n, moved while it finds a lower value (so that it follows the valleys of f
      // along its ridges), then shrunk
      for (int moves = 0; moves < 64; ++moves) {
        const V3L e1 = (std::abs(n.x()) < LD(0.6) ? V3L(1, 0, 0) : V3L(0, 1, 0)).cross(n).normalized(), e2 = n.cross(e1);
        V3L next = n;
        for (int i = -6; i <= 6; ++i) {
          for (int j = -6; j <= 6; ++j) {
            const V3L m = (n + (cap * i / 6) * e1 + (cap * j / 6) * e2).normalized();
            const LD fm = overlap_ld(a, b, R, t, m);
            if (fm < fn) {
              fn = fm;
              next = m;
            }
          }
        }
        if (next == n) break;
        n = next;
      }
    }
    best = std::min(best, fn);
  }
  return best;
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
