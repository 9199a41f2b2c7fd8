// SPDX-License-Identifier: MIT
// The local certificate of convex/local_certificate.hpp and EPA's early stop with it
// (epa_penetration_local, convex/epa.hpp), on cylinder–cylinder and cylinder–cone poses, deep and
// shallow:
//   - the overlap terms are the overlap of the supports (the cone's active branch a lower bound);
//     the body inside the cone along a ruling (cylinder_cone_side_terms, over random spans of the
//     ruling) is a lower bound too;
//   - where a certificate holds (from EPA's normal and from random directions), the overlap of the
//     supports is >= its lower bound on random directions of its cap (up to rounding), its bracket
//     agrees with plain EPA's at the global minimum, and the cap of a local minimum that is not
//     the global one leaves the global one out; every kind of contact is met (smooth, a cap, one
//     ruling, two rulings, the cone's side through its inner body), and the cone's side
//     certificate (cylinder_cone_side_certificate) holds at the global minimum of most side contacts;
//   - the queries with and without it agree within the tolerance, with fewer support calls;
//   - a certificate of a local minimum that is not the global one (the cap of two parallel
//     cylinders) does not stop EPA: the depth stays the global one; a flat circle of minima
//     (coincident cylinders) gives no certificate;
//   - the iteration bound still ends every query (reported), with the certificate on;
//   - cone against box (convex/cone_box_terms.hpp): the terms of the cone's active branch are the
//     overlap there and below it everywhere; the queries in either order agree with EPA alone
//     within the tolerance, in fewer support calls, and the bound still ends them.
#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace {

using namespace impact;
using impact::test::convex_poses;
using impact::test::overlap_along;
using impact::test::zoo;
using V3 = Eigen::Vector3d;

// The overlap along unit n (a's frame) of cylinder a and b placed by f there, from the supports.
template <class B>
double frame_overlap(const Cylinder<double>& a, const B& b, const detail::PairFrame<double>& f, const V3& n) {
  return n.dot(support(a, n)) - n.dot(f.support_b(b, V3(-n)));
}

template <class B>
detail::OverlapTerms<double> terms_at(const Cylinder<double>& a, const B& b, const detail::PairFrame<double>& f, const V3& n, bool& ok) {
  ok = true;
  if constexpr (std::is_same_v<B, Cone<double>>) {
    detail::OverlapTerms<double> t;
    ok = detail::cylinder_cone_terms(a, b, f.R, f.t, n, t);
    return t;
  } else {
    return detail::cylinder_pair_terms(a, b, f.R, f.t);
  }
}

double terms_value(const detail::OverlapTerms<double>& t, const V3& n) {
  const V3 e1 = detail::any_orthogonal(n), e2 = n.cross(e1);
  double v = 0, g[2], H[3];
  detail::overlap_model(t, n, e1, e2, v, g, H, -1.0);
  return v;
}

TEST(LocalCertificate, TermsAreTheOverlap) {
  const auto& z = zoo();
  test::Rng rng(11);
  for (int i = 0; i < 200; ++i) {
    const RigidTransform<double> pa{rng.rotation(), V3::Zero()}, pb{rng.rotation(), rng.vec(-0.8, 0.8)};
    const detail::PairFrame<double> f(pa, pb);
    V3 n = rng.vec(-1, 1);
    if (n.norm() < 0.1) continue;
    n.normalize();
    bool ok = true;
    const auto tc = terms_at(z.cylinder, z.cylinder, f, n, ok);
    EXPECT_NEAR(terms_value(tc, n), frame_overlap(z.cylinder, z.cylinder, f, n), 1e-14);
    detail::OverlapTerms<double> side;
    // the body from the base rim to a random fraction of the ruling (the default: half of it)
    const double s1 = i % 2 ? 0.5 : rng.uniform(0.05, 0.95);
    if (detail::cylinder_cone_side_terms(z.cylinder, z.cone, f.R, f.t, n, side, 0.0, s1)) {
      for (int k = 0; k < 20; ++k) {  // inside the cone: a lower bound everywhere
        V3 m = rng.vec(-1, 1);
        if (m.norm() < 0.1) continue;
        m.normalize();
        EXPECT_LE(terms_value(side, m), frame_overlap(z.cylinder, z.cone, f, m) + 1e-14);
      }
    }
    const auto tk = terms_at(z.cylinder, z.cone, f, n, ok);
    if (ok) {
      EXPECT_NEAR(terms_value(tk, n), frame_overlap(z.cylinder, z.cone, f, n), 1e-14);
      // the branch is a lower bound everywhere
      for (int k = 0; k < 20; ++k) {
        V3 m = rng.vec(-1, 1);
        if (m.norm() < 0.1) continue;
        m.normalize();
        EXPECT_LE(terms_value(tk, m), frame_overlap(z.cylinder, z.cone, f, m) + 1e-14);
      }
    }
  }
}

// The contact kinds of a certified normal n (a's frame; b's axis bz).
enum Kind { kSmooth, kCap, kOneRuling, kTwoRulings, kConeSide };
Kind kind_of(const V3& n, const V3& bz) {
  const bool ra = std::abs(n.z()) < 1e-9, rb = std::abs(n.dot(bz)) < 1e-9;
  if (ra && rb) return kTwoRulings;
  if (ra || rb) return kOneRuling;
  if (std::abs(std::abs(n.z()) - 1) < 1e-12 || std::abs(std::abs(n.dot(bz)) - 1) < 1e-12) return kCap;
  return kSmooth;
}

template <class B>
void check_caps(const char* name, const B& b, double reach, std::uint64_t seed, int& certified, int kinds[5], int& side_at_minimum) {
  const auto& z = zoo();
  const Cylinder<double>& a = z.cylinder;
  const double scale = std::max(shape_size(a), shape_size(b)), tol = 1e-10 * scale;
  ConvexQueryOptions<double> plain;
  plain.local_certificate = false;
  test::Rng rng(seed + 1000);
  for (const auto& pose : convex_poses(IMPACT_TEST_SANITIZED ? 30 : 300, reach, seed)) {
    const RigidTransform<double>& pa = pose.first;
    const RigidTransform<double>& pb = pose.second;
    const auto c = convex_penetration(a, pa, b, pb, plain);
    if (!c.intersecting) continue;
    const detail::PairFrame<double> f(pa, pb);
    const V3 global = pa.R.transpose() * c.normal;  // EPA's normal: the global minimum's
    // from EPA's normal, then from random directions (which also find local minima that are not
    // the global one: their caps must leave the global one out)
    for (int start = 0; start < 4; ++start) {
      V3 n0 = global;
      if (start > 0) {
        n0 = rng.vec(-1, 1);
        if (n0.norm() < 0.1) continue;
        n0.normalize();
      }
      bool ok = true;
      auto terms = terms_at(a, b, f, n0, ok);
      auto cert = ok ? detail::local_certificate(terms, n0) : detail::LocalCertificate<double>();
      if constexpr (std::is_same_v<B, Cone<double>>) {
        // the cone's side: the body inside it along the ruling of the side minimiser, past the
        // contact's point of that ruling
        if (!cert.ok) {
          cert = detail::cylinder_cone_side_certificate(a, b, f.R, f.t, n0);
          if (cert.ok) ++kinds[kConeSide];
          // from EPA's normal, where that bound is the depth
          if (cert.ok && start == 0 && std::abs(frame_overlap(a, b, f, cert.normal) - cert.lower) <= tol) ++side_at_minimum;
        }
      }
      if (!cert.ok) continue;
      ++certified;
      ++kinds[kind_of(cert.normal, f.R.col(2))];
      EXPECT_LE(cert.lower, cert.upper) << name;
      EXPECT_LE(cert.upper - cert.lower, tol) << name;
      EXPECT_NEAR(cert.normal.norm(), 1.0, 1e-14) << name;
      EXPECT_GT(cert.cap, 0.0) << name;
      EXPECT_LT(cert.cap, 1.5708) << name;
      // the cone's branch or inner body: a lower bound, exact only where it touches the contact
      const double at_normal = frame_overlap(a, b, f, cert.normal);
      if constexpr (std::is_same_v<B, Cone<double>>) {
        EXPECT_GE(at_normal, cert.upper - 1e-14) << name;
      } else {
        EXPECT_NEAR(at_normal, cert.upper, 1e-14) << name;
      }
      if (start == 0 && at_normal - cert.lower <= tol && c.depth - c.depth_gap > cert.lower - tol) {
        // the global minimum: EPA's bracket [depth - gap, depth] and the certificate's agree
        EXPECT_LE(cert.lower, c.depth + 1e-15) << name;
        EXPECT_GE(cert.upper, c.depth - c.depth_gap - 1e-15) << name;
      }
      if (c.depth < cert.lower - 1e-15) {  // a local minimum only: the global one is off its cap
        EXPECT_GT(std::acos(std::clamp(global.dot(cert.normal), -1.0, 1.0)), cert.cap) << name;
      }
      // the bound on the cap: random directions within it, a third of them near its rim
      const V3 e1 = detail::any_orthogonal(cert.normal), e2 = cert.normal.cross(e1);
      for (int k = 0; k < 60; ++k) {
        const double phi = rng.uniform(0, 2 * M_PI), r = k % 3 == 0 ? rng.uniform(0.95, 1.0) : rng.uniform(0, 1);
        const double angle = r * cert.cap;
        const V3 m = std::cos(angle) * cert.normal + std::sin(angle) * (std::cos(phi) * e1 + std::sin(phi) * e2);
        const double fm = frame_overlap(a, b, f, m);
        EXPECT_GE(fm, cert.lower - 1e-14) << name << " angle " << angle << " of " << cert.cap;
      }
    }
  }
}

TEST(LocalCertificate, BoundHoldsOnItsCap) {
  const auto& z = zoo();
  int certified = 0, kinds[5] = {0, 0, 0, 0, 0}, side_at_minimum = 0;
  const double cyl = 2 * shape_size(z.cylinder), cone = shape_size(z.cylinder) + shape_size(z.cone);
  check_caps("cylinder-cylinder deep", z.cylinder, 0.3 * cyl, 31, certified, kinds, side_at_minimum);
  check_caps("cylinder-cylinder shallow", z.cylinder, 0.9 * cyl, 32, certified, kinds, side_at_minimum);
  check_caps("cylinder-cone deep", z.cone, 0.3 * cone, 33, certified, kinds, side_at_minimum);
  check_caps("cylinder-cone shallow", z.cone, 0.9 * cone, 34, certified, kinds, side_at_minimum);
  std::printf("cone side certificates at the global minimum: %d\n", side_at_minimum);
  EXPECT_GE(certified, IMPACT_TEST_SANITIZED ? 10 : 150);
  EXPECT_GT(kinds[kSmooth], 0);
  EXPECT_GT(kinds[kCap], 0);
  EXPECT_GT(kinds[kOneRuling], 0);
  EXPECT_GT(kinds[kTwoRulings], 0);
  EXPECT_GT(kinds[kConeSide], 0);
  // the body past the contact's point of the ruling, and from EPA's normal at a ruling of the
  // cylinder: 293 (155 with the body over the lower half of the ruling, 95 without the start at
  // a ruling)
  EXPECT_GE(side_at_minimum, IMPACT_TEST_SANITIZED ? 20 : 250);
}

template <class B>
void check_agreement(const char* name, const B& b, double reach, std::uint64_t seed, int& compared, int& fewer, long& calls_on,
                     long& calls_off) {
  const auto& z = zoo();
  const Cylinder<double>& a = z.cylinder;
  const double scale = std::max(shape_size(a), shape_size(b)), tol = 1e-10 * scale;
  ConvexQueryOptions<double> on, off;
  off.local_certificate = false;
  ASSERT_TRUE(on.local_certificate) << "on by default";
  for (const auto& pose : convex_poses(IMPACT_TEST_SANITIZED ? 30 : 300, reach, seed)) {
    const RigidTransform<double>& pa = pose.first;
    const RigidTransform<double>& pb = pose.second;
    const auto c1 = convex_penetration(a, pa, b, pb, on), c0 = convex_penetration(a, pa, b, pb, off);
    ASSERT_EQ(c1.intersecting, c0.intersecting) << name;
    if (!c0.intersecting) continue;
    ++compared;
    calls_on += c1.iterations;
    calls_off += c0.iterations;
    fewer += c1.iterations < c0.iterations;
    EXPECT_FALSE(c1.limit_reached) << name;
    EXPECT_LE(c1.depth_gap, tol) << name;
    // both brackets hold the true depth
    EXPECT_LE(c1.depth - c1.depth_gap, c0.depth + 1e-15) << name;
    EXPECT_LE(c0.depth - c0.depth_gap, c1.depth + 1e-15) << name;
    EXPECT_NEAR(overlap_along(a, pa, b, pb, c1.normal), c1.depth, 1e-12 * scale) << name;
    EXPECT_NEAR(c1.normal.norm(), 1.0, 1e-12) << name;
  }
}

TEST(LocalCertificate, QueriesAgreeWithEpaAloneInFewerCalls) {
  const auto& z = zoo();
  int compared = 0, fewer = 0;
  long on = 0, off = 0;
  const double cyl = 2 * shape_size(z.cylinder), cone = shape_size(z.cylinder) + shape_size(z.cone);
  check_agreement("cylinder-cylinder deep", z.cylinder, 0.3 * cyl, 41, compared, fewer, on, off);
  check_agreement("cylinder-cylinder shallow", z.cylinder, 0.9 * cyl, 42, compared, fewer, on, off);
  check_agreement("cylinder-cone deep", z.cone, 0.3 * cone, 43, compared, fewer, on, off);
  check_agreement("cylinder-cone shallow", z.cone, 0.9 * cone, 44, compared, fewer, on, off);
  EXPECT_GE(compared, IMPACT_TEST_SANITIZED ? 20 : 300);
  EXPECT_GE(fewer, compared / 10);
  EXPECT_LT(on, off);
}

// Two cylinders, b shifted by 0.1 along x and tilted by 0.05 rad about it: the overlap has its
// global minimum 0.7 at n = +x (the rulings) and a local one, about 1.02, at a's cap (n = +z).
TEST(LocalCertificate, LocalMinimumThatIsNotGlobalDoesNotStopEpa) {
  const Cylinder<double> a(0.4, 0.5), b(0.4, 0.5);
  const RigidTransform<double> pa{Eigen::Matrix3d::Identity(), V3::Zero()},
      pb{Eigen::AngleAxisd(0.05, V3::UnitX()).toRotationMatrix(), V3(0.1, 0, 0)};
  const detail::PairFrame<double> f(pa, pb);
  const auto terms = detail::cylinder_pair_terms(a, b, f.R, f.t);
  const auto at_cap = detail::local_certificate(terms, V3(0.02, 0.01, 1).normalized());
  ASSERT_TRUE(at_cap.ok) << "the cap is a strict local minimum";
  EXPECT_GT(at_cap.lower, 1.0);
  EXPECT_NEAR(at_cap.normal.z(), 1.0, 1e-14);
  const auto sa = [&](const V3& d) { return support(a, d); };
  const auto sb = [&](const V3& d) { return f.support_b(b, d); };
  detail::SimplexPoint<double> simplex[4];
  int its = 0;
  bool limit = false, failed = false;
  ASSERT_TRUE(detail::gjk_enclose(sa, sb, V3(-f.t), 1.0, 128, simplex, its, limit, failed));
  EpaSettings<double> st;
  st.tolerance = 1e-10;
  int calls = 0;
  const auto wrong = [&](const V3&) {
    ++calls;
    return at_cap;
  };
  const auto r = epa_penetration_local(sa, sb, simplex, its, st, wrong);
  EXPECT_TRUE(r.intersecting);
  EXPECT_FALSE(r.local_certificate);
  EXPECT_FALSE(r.failed);
  EXPECT_NEAR(r.depth, 0.7, 1e-9);
  EXPECT_NEAR(r.normal.x(), 1.0, 1e-6);
  EXPECT_EQ(r.depth, epa_penetration_from_simplex(sa, sb, simplex, its, st).depth) << "as EPA alone";
  EXPECT_LE(calls, 2) << "tried at most twice";
  // the query finds the global minimum, through its own certificate or EPA
  const auto c = convex_penetration(a, pa, b, pb);
  EXPECT_NEAR(c.depth, 0.7, 1e-9);
}

TEST(LocalCertificate, NoCertificateOnACircleOfMinima) {
  const Cylinder<double> a(0.4, 0.5);
  const detail::PairFrame<double> f(RigidTransform<double>{Eigen::Matrix3d::Identity(), V3::Zero()},
                                    RigidTransform<double>{Eigen::Matrix3d::Identity(), V3::Zero()});
  const auto terms = detail::cylinder_pair_terms(a, a, f.R, f.t);
  for (const V3& n0 : {V3(1, 0, 0.01), V3(0.3, 0.9, -0.05), V3(0.6, -0.8, 0.2)}) {
    const auto cert = detail::local_certificate(terms, V3(n0.normalized()));
    EXPECT_FALSE(cert.ok) << "f is constant along the equator";
    EXPECT_LE(cert.newton_steps, 2 * detail::kLocalNewtonSteps);
  }
}

TEST(LocalCertificate, IterationBoundStillEndsEveryQuery) {
  const auto& z = zoo();
  for (const int bound : {6, 10, 16}) {
    ConvexQueryOptions<double> o;
    o.max_iterations = bound;
    const double tol = 1e-10 * shape_size(z.cylinder);
    for (const auto& pose : convex_poses(IMPACT_TEST_SANITIZED ? 20 : 100, 0.6 * shape_size(z.cylinder), 51)) {
      const auto c = convex_penetration(z.cylinder, pose.first, z.cylinder, pose.second, o);
      if (c.intersecting) {
        EXPECT_TRUE(c.limit_reached || c.depth_gap <= tol) << "bound " << bound;
      }
      const auto k = convex_penetration(z.cylinder, pose.first, z.cone, pose.second, o);
      if (k.intersecting) {
        EXPECT_TRUE(k.limit_reached || k.depth_gap <= tol) << "bound " << bound;
      }
    }
  }
}

// Cone a (its frame) against box b placed by f: the terms of the branch active at n are the
// overlap of the supports at n and below it on every other direction.
TEST(LocalCertificate, ConeBoxTermsAreTheOverlapOfTheActiveBranch) {
  const auto& z = zoo();
  test::Rng rng(61);
  int exact = 0, below = 0;
  for (const auto& pose : convex_poses(IMPACT_TEST_SANITIZED ? 20 : 200, 0.6 * (shape_size(z.cone) + shape_size(z.box)), 62)) {
    const detail::PairFrame<double> f(pose.first, pose.second);
    const auto overlap = [&](const V3& n) { return n.dot(support(z.cone, n)) - n.dot(f.support_b(z.box, V3(-n))); };
    for (int k = 0; k < 8; ++k) {
      const V3 n = rng.vec(-1, 1).normalized();
      detail::OverlapTerms<double> t;
      if (!detail::cone_box_terms(z.cone, z.box, f.R, f.t, n, t)) continue;
      EXPECT_NEAR(terms_value(t, n), overlap(n), 1e-12);
      ++exact;
      for (int j = 0; j < 8; ++j) {
        const V3 m = rng.vec(-1, 1).normalized();
        EXPECT_LE(terms_value(t, m), overlap(m) + 1e-12);
        ++below;
      }
    }
  }
  EXPECT_GE(exact, IMPACT_TEST_SANITIZED ? 100 : 1000);
  EXPECT_GE(below, 8 * exact);
}

// cone_box_penetration (either order) with and without the certificate: both brackets hold the
// true depth, the depth is the overlap along the normal, and the certificate saves support calls.
TEST(LocalCertificate, ConeBoxQueriesAgreeWithEpaAloneInFewerCalls) {
  const auto& z = zoo();
  const double scale = std::max(shape_size(z.cone), shape_size(z.box)), tol = 1e-10 * scale;
  ConvexQueryOptions<double> on, off;
  off.local_certificate = false;
  int compared = 0, fewer = 0;
  long calls_on = 0, calls_off = 0;
  for (const double reach : {0.3, 0.9}) {
    for (const auto& pose :
         convex_poses(IMPACT_TEST_SANITIZED ? 30 : 300, reach * (shape_size(z.cone) + shape_size(z.box)), reach < 0.5 ? 63 : 64)) {
      const RigidTransform<double>& pa = pose.first;
      const RigidTransform<double>& pb = pose.second;
      const auto c1 = convex_penetration(z.cone, pa, z.box, pb, on), c0 = convex_penetration(z.cone, pa, z.box, pb, off);
      const auto s1 = convex_penetration(z.box, pb, z.cone, pa, on);
      ASSERT_EQ(c1.intersecting, c0.intersecting);
      ASSERT_EQ(s1.intersecting, c0.intersecting);
      if (!c0.intersecting) continue;
      ++compared;
      calls_on += c1.iterations;
      calls_off += c0.iterations;
      fewer += c1.iterations < c0.iterations;
      for (const auto* c : {&c1, &s1}) {
        EXPECT_FALSE(c->limit_reached);
        EXPECT_LE(c->depth_gap, tol);
        EXPECT_LE(c->depth - c->depth_gap, c0.depth + 1e-15);
        EXPECT_LE(c0.depth - c0.depth_gap, c->depth + 1e-15);
        EXPECT_NEAR(c->normal.norm(), 1.0, 1e-12);
      }
      EXPECT_NEAR(overlap_along(z.cone, pa, z.box, pb, c1.normal), c1.depth, 1e-12 * scale);
      EXPECT_NEAR(overlap_along(z.box, pb, z.cone, pa, s1.normal), s1.depth, 1e-12 * scale);
    }
  }
  EXPECT_GE(compared, IMPACT_TEST_SANITIZED ? 10 : 150);
  EXPECT_GE(fewer, compared / 10);
  EXPECT_LT(calls_on, calls_off);
  for (const int bound : {6, 10}) {
    ConvexQueryOptions<double> o;
    o.max_iterations = bound;
    for (const auto& pose : convex_poses(IMPACT_TEST_SANITIZED ? 20 : 100, 0.5 * (shape_size(z.cone) + shape_size(z.box)), 65)) {
      const auto c = convex_penetration(z.cone, pose.first, z.box, pose.second, o);
      if (c.intersecting) {
        EXPECT_TRUE(c.limit_reached || c.depth_gap <= tol) << "bound " << bound;
      }
    }
  }
}

}  // namespace
