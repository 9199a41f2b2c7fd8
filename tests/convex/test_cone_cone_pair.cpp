// SPDX-License-Identifier: MIT
// The certified cone–cone candidates (convex/cone_cone_pair.hpp) and the cone–cone penetration
// (convex/query.hpp: candidates, EPA and the local certificate on cone_cone_terms) against an
// oracle: the penetration depth as the least overlap f(n) = h_a(n) + h_b(-n) over unit
// directions, each cone's support function in closed form in long double (the apex or the base
// rim), minimised by test::least_overlap (support/convex_oracle.hpp). The oracle's minimum is an
// upper bound of the true depth and every certified lower bound lies below the true depth, so a
// certificate that certifies a wrong (too large) depth shows as depth - depth_gap above the oracle.
#include "impact/convex/certified_pair.hpp"
#include "impact/convex/cone_cone_pair.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

// (its own namespace: the convex tests build as one unity source, beside test_cone_box_pair.cpp)
namespace {
namespace cone_cone_pair_test {

using namespace impact;
using LD = long double;
using V3L = Eigen::Matrix<LD, 3, 1>;

// Cone c's support function along n (its frame), long double.
LD cone_h(const Cone<double>& c, const V3L& n) {
  const LD h = c.half_length, r = c.radius;
  return std::max(h * n.z(), r * std::sqrt(n.x() * n.x() + n.y() * n.y()) - h * n.z());
}

// The overlap along unit n of cone a (its frame) and cone b placed by R, t there, in long double.
LD overlap_ld(const Cone<double>& a, const Cone<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const V3L& n) {
  const V3L m = -(R.cast<LD>().transpose() * n);
  return cone_h(a, n) - t.cast<LD>().dot(n) + cone_h(b, m);
}

// The least overlap by test::least_overlap: the kink circles of each cone's side normals (where
// its apex and base rim tie: n . axis = r / sqrt(4h^2 + r^2), for b along -n), both axes both ways
// and `extra` (the normal under test: the search may only find lower overlaps than there) as
// starts.
LD depth_oracle(const Cone<double>& a, const Cone<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Eigen::Vector3d& extra) {
  const auto f = [&](const V3L& n) { return overlap_ld(a, b, R, t, n); };
  const std::vector<Eigen::Vector3d> starts = {Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ(), R.col(2), -R.col(2), extra};
  const auto side = [](const Cone<double>& c) { return c.radius / std::sqrt(4 * c.half_length * c.half_length + c.radius * c.radius); };
  const std::vector<test::KinkCircle> circles = {{Eigen::Vector3d::UnitZ(), side(a)}, {R.col(2), -side(b)}};
  return test::least_overlap(f, starts, circles).depth;
}

using test::overlap_terms_value;

struct Case {
  Cone<double> a{0.5, 0.6}, b{0.5, 0.6};
  RigidTransform<double> pa, pb;
};

// Cones of varied proportions (every fourth pair the zoo's), b about a, `scale` times the size
// and `offset` from the origin.
std::vector<Case> cases(int n, std::uint64_t seed, double scale = 1, double offset = 0, double spread = 0.6) {
  test::Rng rng(seed);
  std::vector<Case> out;
  for (int k = 0; k < n; ++k) {
    Case c;
    if (k % 4 != 0) {
      c.a = Cone<double>(rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0));
      c.b = Cone<double>(rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0));
    }
    c.a = Cone<double>(c.a.radius * scale, c.a.half_length * scale);
    c.b = Cone<double>(c.b.radius * scale, c.b.half_length * scale);
    const double reach = spread * (shape_size(c.a) + shape_size(c.b));
    c.pa = {rng.rotation(), Eigen::Vector3d(rng.vec(-scale, scale) + Eigen::Vector3d::Constant(offset))};
    c.pb = {rng.rotation(), Eigen::Vector3d(c.pa.t + rng.vec(-reach, reach))};
    out.push_back(c);
  }
  return out;
}

// Each certified candidate: its lower bound below the oracle's depth (an upper bound of the true
// one), its depth within the tolerance of it, its depth the overlap along its normal. Checked to
// fail: a's apex pushed out along -push (the wrong way) and the ruling balls' radius doubled.
TEST(ConeConePair, CertifiedDepthsAgainstTheOracle) {
  int certified = 0, base = 0, body = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 24 : 120, 915, 1, 0, 0.4)) {
    const double scale = std::max(shape_size(c.a), shape_size(c.b)), tol = 1e-10 * scale;
    const detail::PairFrame<double> f(c.pa, c.pb);
    ConvexContact<double> k;
    if (!detail::cone_cone_contact(c.a, c.b, f.R, f.t, tol, k)) continue;
    ++certified;
    const double oracle = double(depth_oracle(c.a, c.b, f.R, f.t, k.normal));
    EXPECT_GT(oracle, 0) << "certified a pair the oracle finds apart";
    EXPECT_LE(k.depth - k.depth_gap, oracle + 1e-12 * scale) << "lower bound above the depth";
    EXPECT_NEAR(k.depth, oracle, 1e-9 * scale);
    EXPECT_NEAR(double(overlap_ld(c.a, c.b, f.R, f.t, k.normal.cast<LD>())), k.depth, 1e-12 * scale);
    const bool on_axis = std::abs(k.normal.z()) > 1 - 1e-12 || std::abs(k.normal.dot(f.R.col(2))) > 1 - 1e-12;
    ++(on_axis ? base : body);
  }
  // both kinds certified: a base against a point, and the side contacts (apex, rim, ruling)
  EXPECT_GT(body, IMPACT_TEST_SANITIZED ? 0 : 10);
  EXPECT_EQ(base + body, certified);
}

// cone_cone_contact on (x, y) and on (y, x): each certified depth's lower bound below the oracle's
// depth and the depth within 1e-9 of the size of it. Returns how many of the two were certified.
int check_certified_both_orders(const Cone<double>& x, const RigidTransform<double>& px, const Cone<double>& y,
                                const RigidTransform<double>& py) {
  const double scale = std::max(shape_size(x), shape_size(y)), tol = 1e-10 * scale;
  int certified = 0;
  for (const bool x_first : {true, false}) {
    const Cone<double>& a = x_first ? x : y;
    const Cone<double>& b = x_first ? y : x;
    const detail::PairFrame<double> f(x_first ? px : py, x_first ? py : px);
    ConvexContact<double> c;
    if (!detail::cone_cone_contact(a, b, f.R, f.t, tol, c)) continue;
    ++certified;
    const double oracle = double(depth_oracle(a, b, f.R, f.t, c.normal));
    EXPECT_LE(c.depth - c.depth_gap, oracle + 1e-12 * scale) << "lower bound above the depth";
    EXPECT_NEAR(c.depth, oracle, 1e-9 * scale);
  }
  return certified;
}

// A narrow cone's apex through the other's base, tilted by up to 0.3 rad, 0.02 .. 0.3 of the
// base's cone deep, both ways round: the base candidate (and the apex's) decide it, certified, and
// within the tolerance of the oracle. Checked to fail: b's base candidate with its ball's radius
// doubled.
TEST(ConeConePair, ApexThroughBase) {
  test::Rng rng(916);
  int certified = 0;
  for (int k = 0; k < (IMPACT_TEST_SANITIZED ? 6 : 24); ++k) {
    const Cone<double> wide(rng.uniform(0.6, 1.0), rng.uniform(0.3, 0.8)), narrow(rng.uniform(0.05, 0.15), rng.uniform(0.4, 0.8));
    const double tilt = rng.uniform(0, 0.3), depth = rng.uniform(0.02, 0.3);
    // narrow's apex at wide's base centre + depth along wide's axis, narrow pointing up (+z) tilted about x
    const Eigen::Matrix3d tilt_r = Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const Eigen::Vector3d apex(rng.uniform(-0.2, 0.2) * wide.radius, 0, -wide.half_length + depth);
    const RigidTransform<double> pw{Eigen::Matrix3d(rng.rotation()), rng.vec(-1, 1)};
    const RigidTransform<double> pn_local{tilt_r, Eigen::Vector3d(apex - tilt_r * Eigen::Vector3d(0, 0, narrow.half_length))};
    const RigidTransform<double> pn{Eigen::Matrix3d(pw.R * pn_local.R), Eigen::Vector3d(pw.apply(pn_local.t))};
    certified += check_certified_both_orders(wide, pw, narrow, pn);
  }
  EXPECT_GT(certified, IMPACT_TEST_SANITIZED ? 6 : 30);
}

// A small flat cone deep inside a larger one (centres within 0.25), both argument orders: poses
// whose rim-against-side candidates (either base rim's point deepest below the other's side) have
// balls of more than half the best upper bound. Every certified depth within the tolerance of the
// oracle. Checked to fail: the radius of the ball of b's rim point doubled (rim_of_b: 9 wrong
// certified depths of the 26 certificates), and that of a's rim point (rim_of_a: 9), which the
// random poses of CertifiedDepthsAgainstTheOracle did not catch.
TEST(ConeConePair, SmallConeDeepInsideRimAgainstSide) {
  test::Rng rng(919);
  int certified = 0;
  for (int k = 0; k < (IMPACT_TEST_SANITIZED ? 16 : 30); ++k) {
    const Cone<double> large(rng.uniform(0.5, 1.0), rng.uniform(0.5, 1.0)), small(rng.uniform(0.1, 0.6), rng.uniform(0.1, 0.2));
    const RigidTransform<double> pl{rng.rotation(), rng.vec(-1, 1)};
    const RigidTransform<double> ps{rng.rotation(), Eigen::Vector3d(pl.t + rng.vec(-0.25, 0.25))};
    certified += check_certified_both_orders(large, pl, small, ps);
  }
  EXPECT_GT(certified, IMPACT_TEST_SANITIZED ? 8 : 20);
}

// The terms of one branch of each cone are a lower bound of the overlap everywhere and equal to it
// along the direction they were built at. Checked to fail: b's linear term with the wrong sign.
TEST(ConeConePair, TermsBoundTheOverlap) {
  test::Rng rng(917);
  int built = 0;
  for (const Case& c : cases(60, 918)) {
    const detail::PairFrame<double> f(c.pa, c.pb);
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector3d n = rng.vec(-1, 1).normalized();
      detail::OverlapTerms<double> terms;
      if (!detail::cone_cone_terms(c.a, c.b, f.R, f.t, n, terms)) continue;
      ++built;
      const auto value = [&](const Eigen::Vector3d& w) { return overlap_terms_value(terms, w); };
      EXPECT_NEAR(value(n), double(overlap_ld(c.a, c.b, f.R, f.t, n.cast<LD>())), 1e-12);
      for (int j = 0; j < 10; ++j) {
        const Eigen::Vector3d m = rng.vec(-1, 1).normalized();
        EXPECT_LE(value(m), double(overlap_ld(c.a, c.b, f.R, f.t, m.cast<LD>())) + 1e-12);
      }
    }
  }
  EXPECT_GT(built, 400);
}

// The whole query, both argument orders, on every intersecting pose (candidates, EPA with the
// local certificate): depth within 1e-9 of the size of the oracle's, never a lower bound above it;
// at the unit size, at 1e-3 and 1e3 of it, and 1e3 from the origin.
TEST(ConeConePair, PenetrationAgainstTheOracle) {
  int hits = 0;
  const double scales[4] = {1, 1e-3, 1e3, 1}, offsets[4] = {0, 0, 0, 1e3};
  for (int s = 0; s < 4; ++s) {
    for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 4 : 10, 920 + static_cast<std::uint64_t>(s), scales[s], offsets[s], 0.4)) {
      const double scale = std::max(shape_size(c.a), shape_size(c.b));
      const detail::PairFrame<double> f(c.pa, c.pb);
      const auto p = convex_penetration(c.a, c.pa, c.b, c.pb);
      const auto q = convex_penetration(c.b, c.pb, c.a, c.pa);
      const double oracle = double(depth_oracle(c.a, c.b, f.R, f.t, p.intersecting ? Eigen::Vector3d(c.pa.R.transpose() * p.normal) : Eigen::Vector3d(Eigen::Vector3d::UnitZ())));
      if (std::abs(oracle) < 1e-6 * scale) continue;  // touching: either answer
      EXPECT_EQ(p.intersecting, oracle > 0);
      EXPECT_EQ(q.intersecting, oracle > 0);
      if (oracle < 0 || !p.intersecting || !q.intersecting) continue;
      ++hits;
      // the rounding of the pose 1e3 away is about 1e3 eps, i.e. 1e-13 * 1e3 of a unit size
      const double slack = (1e-12 + 1e-15 * offsets[s]) * scale;
      for (const auto& r : {p, q}) {
        EXPECT_LE(r.depth - r.depth_gap, oracle + slack) << "lower bound above the depth";
        EXPECT_NEAR(r.depth, oracle, 1e-9 * scale + slack);
        EXPECT_FALSE(r.limit_reached);
      }
    }
  }
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 2 : 20);
}

// The cone's-side certificate of the cone–cone query (convex/certified_pair.hpp, where a cone's side
// ruling touches the other's apex or rim, so cone_cone_terms has no exact branch): Newton along b's
// side normals (cone_side_newton with a cone's support), then the local certificate on a's active
// branch and the body inside b along that ruling (cone_cone_side_terms); both ways round, from EPA
// alone's normal on deep poses. The terms are never above the overlap; every certificate that
// holds (the overlap at its normal within the tolerance of its bound, as the query accepts it)
// bounds the overlap from below on its cap (random directions in it and on its rim), and where its
// minimum is EPA's (the global one) its lower bound is below the oracle's depth. Checked to fail:
// the body moved out by half its radius (terms above the overlap); the rim's curvature left out
// of Newton's second derivative (fewer certificates than the bound below).
TEST(ConeConePair, SideCertificateAgainstTheOracle) {
  test::Rng rng(919);
  int built = 0, held = 0, global = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 30 : 120, 921, 1, 0, 0.4)) {
    for (const bool x_first : {true, false}) {
      const Cone<double>& a = x_first ? c.a : c.b;
      const Cone<double>& b = x_first ? c.b : c.a;
      const RigidTransform<double>& pa = x_first ? c.pa : c.pb;
      const RigidTransform<double>& pb = x_first ? c.pb : c.pa;
      const double scale = std::max(shape_size(a), shape_size(b)), tol = 1e-10 * scale;
      const detail::PairFrame<double> f(pa, pb);
      const ConvexContact<double> g = detail::general_penetration(a, pa, b, pb, ConvexQueryOptions<double>());
      if (!g.intersecting) continue;
      Eigen::Vector3d m = pa.R.transpose() * g.normal;
      detail::OverlapTerms<double> terms;
      if (!detail::cone_side_newton(a, b, f.R, f.t, m)) continue;
      // the body from the base rim point of b's ruling to past the contact's point of it
      const double end = detail::side_body_end(detail::cone_side_contact(a, b, f.R, f.t, m));
      if (!detail::cone_cone_side_terms(a, b, f.R, f.t, m, terms, 0.0, end)) continue;
      ++built;
      for (int j = 0; j < 10; ++j) {
        const Eigen::Vector3d w = rng.vec(-1, 1).normalized();
        EXPECT_LE(overlap_terms_value(terms, w), double(overlap_ld(a, b, f.R, f.t, w.cast<LD>())) + 1e-12 * scale);
      }
      const detail::LocalCertificate<double> lc = detail::local_certificate(terms, m);
      const auto sa = [&](const Eigen::Vector3d& d) { return Eigen::Vector3d(support(a, d)); };
      const auto sb = [&](const Eigen::Vector3d& d) { return Eigen::Vector3d(f.support_b(b, d)); };
      if (!detail::certificate_holds(lc, sa, sb, tol)) continue;
      ++held;
      const Eigen::Vector3d e1 = detail::any_orthogonal(lc.normal), e2 = lc.normal.cross(e1);
      for (int j = 0; j < 40; ++j) {  // directions in the cap (the last ten on its rim)
        const double phi = rng.uniform(0, 2 * M_PI), ang = j < 30 ? lc.cap * rng.uniform() : lc.cap;
        const Eigen::Vector3d w = std::cos(ang) * lc.normal + std::sin(ang) * (std::cos(phi) * e1 + std::sin(phi) * e2);
        EXPECT_GE(double(overlap_ld(a, b, f.R, f.t, w.cast<LD>())), lc.lower - 1e-12 * scale) << "below the bound in its cap";
      }
      if (!(std::abs(lc.upper - g.depth) <= 2 * tol)) continue;  // a local minimum, not the global one
      ++global;
      const double oracle = double(depth_oracle(a, b, f.R, f.t, lc.normal));
      EXPECT_LE(lc.lower, oracle + 1e-12 * scale) << "lower bound above the depth";
      EXPECT_NEAR(lc.upper, oracle, 1e-9 * scale);
    }
  }
  std::printf("side certificates: %d built, %d held, %d at the global minimum\n", built, held, global);
  // 18 with the body over the lower half of the ruling whatever the contact's point
  EXPECT_GT(global, IMPACT_TEST_SANITIZED ? 2 : 25);
}

// Float: the same query on float shapes and poses against the double oracle of the float inputs,
// within float's tolerance (1e-4 of the size) and the certified bracket.
TEST(ConeConePair, FloatPenetrationAgainstTheOracle) {
  int hits = 0, certified = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 8 : 24, 930, 1, 0, 0.4)) {
    const Cone<float> af(float(c.a.radius), float(c.a.half_length)), bf(float(c.b.radius), float(c.b.half_length));
    const RigidTransform<float> pa{c.pa.R.cast<float>(), c.pa.t.cast<float>()}, pb{c.pb.R.cast<float>(), c.pb.t.cast<float>()};
    // the oracle on the float inputs as given (double shapes and poses holding the same values)
    const Cone<double> ad(af.radius, af.half_length), bd(bf.radius, bf.half_length);
    const RigidTransform<double> pad{pa.R.cast<double>(), pa.t.cast<double>()}, pbd{pb.R.cast<double>(), pb.t.cast<double>()};
    const detail::PairFrame<double> f(pad, pbd);
    const double scale = std::max(shape_size(ad), shape_size(bd));
    const auto p = convex_penetration(af, pa, bf, pb);
    const double oracle = double(depth_oracle(ad, bd, f.R, f.t, p.intersecting ? Eigen::Vector3d((pa.R.transpose() * p.normal).cast<double>()) : Eigen::Vector3d(Eigen::Vector3d::UnitZ())));
    if (std::abs(oracle) < 1e-4 * scale) continue;
    EXPECT_EQ(p.intersecting, oracle > 0);
    if (oracle < 0 || !p.intersecting) continue;
    ++hits;
    EXPECT_LE(double(p.depth - p.depth_gap), oracle + 1e-5 * scale) << "lower bound above the depth";
    EXPECT_NEAR(double(p.depth), oracle, 1e-4 * scale);
    const detail::PairFrame<float> ff(pa, pb);
    ConvexContact<float> k;
    certified += detail::cone_cone_contact(af, bf, ff.R, ff.t, 1e-5f * float(scale), k);
  }
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 2 : 10);
  EXPECT_GT(certified, IMPACT_TEST_SANITIZED ? -1 : 2);
}

// cone_side_minimum (convex/cylinder_pair.hpp) of a cone against a cylinder placed by R, t in the
// cone's frame: F(phi) = h_cyl(-m(phi)), m(phi) = (k cos phi, k sin phi, c) the cone's side normal
// at azimuth phi. The oracle: the cylinder's support function in closed form in long double
// (t . d + r |P d| + h |a . d|), scanned at 4096 azimuths and refined by golden sections.
LD cylinder_h(const Cylinder<double>& cyl, const V3L& axis, const V3L& t, const V3L& d) {
  const LD ad = axis.dot(d);
  return t.dot(d) + LD(cyl.radius) * std::sqrt(std::max(d.squaredNorm() - ad * ad, LD(0))) + LD(cyl.half_length) * std::abs(ad);
}
struct SideOracle {
  LD k = 0, c = 0;
  V3L axis, t;
  Cylinder<double> cyl{0.3, 0.4};
  SideOracle(const Cone<double>& cone, const Cylinder<double>& cy, const Eigen::Matrix3d& R, const Eigen::Vector3d& tr)
      : axis(R.col(2).cast<LD>()), t(tr.cast<LD>()), cyl(cy) {
    const LD len = std::sqrt(LD(4) * cone.half_length * cone.half_length + LD(cone.radius) * cone.radius);
    k = 2 * cone.half_length / len;
    c = cone.radius / len;
  }
  LD F(LD phi) const { return cylinder_h(cyl, axis, t, V3L(-k * std::cos(phi), -k * std::sin(phi), -c)); }
  LD F(const V3L& m) const { return cylinder_h(cyl, axis, t, V3L(-m)); }
  // the least F and its azimuth
  std::pair<LD, LD> least() const {
    const LD pi = std::acos(LD(-1));
    int best = 0;
    for (int i = 1; i < 4096; ++i)
      if (F(2 * pi * i / 4096) < F(2 * pi * best / 4096)) best = i;
    LD lo = 2 * pi * (best - 1) / 4096, hi = 2 * pi * (best + 1) / 4096;
    const LD g = (std::sqrt(LD(5)) - 1) / 2;
    for (int it = 0; it < 120; ++it) {
      const LD x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
      if (F(x1) < F(x2)) hi = x2; else lo = x1;
    }
    return {F((lo + hi) / 2), (lo + hi) / 2};
  }
};

// The cylinder's support in the cone's frame (R, t), counting the calls.
template <class S>
auto counted_cylinder_support(const Cylinder<S>& cyl, const Mat3<S>& R, const Vec3<S>& t, int& calls) {
  return [&cyl, R, t, &calls](const Vec3<S>& d) {
    ++calls;
    return Vec3<S>(R * support(cyl, Vec3<S>(R.transpose() * d)) + t);
  };
}

// A smooth minimum (the cylinder's support on one rim near it): found (false only when the 8
// samples give no bracket of F's slope about the best: 10 support calls), F there the oracle's
// least value, x the support along -m; float and double.
TEST(ConeSideMinimum, SmoothMinimumAgainstTheOracle) {
  test::Rng rng(941);
  int smooth = 0, found = 0, found_f = 0;
  for (int n = 0; n < (IMPACT_TEST_SANITIZED ? 8 : 40); ++n) {
    const Cone<double> cone(rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0));
    const Cylinder<double> cyl(rng.uniform(0.1, 0.6), rng.uniform(0.1, 0.6));
    const Eigen::Matrix3d R = rng.rotation();
    const Eigen::Vector3d t = rng.vec(-0.5, 0.5);
    const SideOracle o(cone, cyl, R, t);
    const auto [fmin, phi] = o.least();
    // smooth there: the cylinder's support on one rim, away from its caps' switch and its axis
    const V3L d(-o.k * std::cos(phi), -o.k * std::sin(phi), -o.c);
    const LD ad = o.axis.dot(d);
    if (std::abs(ad) < 0.05 || d.squaredNorm() - ad * ad < 0.05) continue;
    ++smooth;
    int calls = 0;
    Vec3<double> m, x;
    if (detail::cone_side_minimum(cone, counted_cylinder_support(cyl, R, t, calls), m, x)) {
      ++found;
      EXPECT_NEAR(m.norm(), 1.0, 1e-15);
      EXPECT_NEAR(double(o.F(m.cast<LD>())), double(fmin), 1e-13) << "not the least overlap along the side";
      EXPECT_NEAR(-m.dot(x), double(o.F(m.cast<LD>())), 1e-14) << "x not the support along -m";
    } else {
      EXPECT_EQ(calls, 10) << "false after the samples bracketed a smooth minimum";  // 8 samples, 2 ends
    }
    const Cone<float> cf(float(cone.radius), float(cone.half_length));
    const Cylinder<float> yf(float(cyl.radius), float(cyl.half_length));
    const Mat3<float> Rf = R.cast<float>();
    const Vec3<float> tf = t.cast<float>();
    Vec3<float> mf, xf;
    calls = 0;
    if (detail::cone_side_minimum(cf, counted_cylinder_support(yf, Rf, tf, calls), mf, xf)) {
      ++found_f;
      EXPECT_NEAR(double(o.F(mf.cast<LD>())), double(fmin), 1e-5);
    } else {
      EXPECT_EQ(calls, 10);
    }
  }
  EXPECT_GT(smooth, IMPACT_TEST_SANITIZED ? 2 : 15);
  EXPECT_GE(found, smooth * 9 / 10);
  EXPECT_GE(found_f, smooth * 9 / 10);
}

// A kink minimum: the cylinder's axis normal to the cone's side normal at azimuth phi0 and tilted
// by 45 degrees about it from the cone's ruling, its centre in the plane of that ruling and the
// axis, so F's slope jumps from - k h sin 45 to + k h sin 45 at phi0 (the support switches caps;
// the contact is ruling against ruling, offered by opposite_rulings). cone_side_minimum says so
// early: false within 24 support calls (8 samples, 2 ends, then 9 to 11 steps of the bracket).
// Checked to fail (run): without the kink test, 34 calls (all 24 steps; the bracket never closes).
TEST(ConeSideMinimum, KinkEndsEarly) {
  for (const double phi0 : {0.3, 2.0, -2.6}) {
    const Cone<double> cone(0.5, 0.6);
    const Cylinder<double> cyl(0.2, 0.5);
    const double len = std::sqrt(4 * 0.6 * 0.6 + 0.5 * 0.5), k = 1.2 / len, c = 0.5 / len;
    const Eigen::Vector3d ruling(c * std::cos(phi0), c * std::sin(phi0), -k), tangent(-std::sin(phi0), std::cos(phi0), 0);
    const Eigen::Vector3d axis = (ruling + tangent).normalized();
    Eigen::Matrix3d R;
    R.col(0) = tangent.cross(axis).cross(axis).normalized();
    R.col(1) = axis.cross(R.col(0));
    R.col(2) = axis;
    const Eigen::Vector3d t = 0.3 * Eigen::Vector3d(std::cos(phi0), std::sin(phi0), 0) + Eigen::Vector3d(0, 0, 0.1);
    const SideOracle o(cone, cyl, R, t);
    // the construction: F's least value at phi0, a kink
    const auto [fmin, phi] = o.least();
    EXPECT_NEAR(double(std::remainder(phi - phi0, 2 * std::acos(LD(-1)))), 0.0, 1e-6);
    EXPECT_LT(double(o.F(LD(phi0))), double(std::min(o.F(LD(phi0 - 1e-4)), o.F(LD(phi0 + 1e-4))) - 1e-6));
    int calls = 0;
    Vec3<double> m, x;
    EXPECT_FALSE(detail::cone_side_minimum(cone, counted_cylinder_support(cyl, R, t, calls), m, x));
    EXPECT_LE(calls, 24);
  }
}

}  // namespace cone_cone_pair_test
}  // namespace
