// SPDX-License-Identifier: MIT
// Cylinder against box (convex/cylinder_box_pair.hpp and the cylinder–box paths of
// convex/query.hpp): the certified candidates, the whole penetration (candidates, EPA with the
// local certificate on cylinder_box_terms) and the boolean test, against an oracle:
// the least overlap f(n) = h_cyl(n) + h_box(-n) over unit directions, both support functions in
// closed form in long double (h |n_z| + r |P_z n|; the box's centre and three abs terms),
// minimised by test::least_overlap (support/convex_oracle.hpp). Its minimum is an upper bound of
// the true depth and every certified lower bound lies below the true depth, so a certificate of a
// wrong (too large) depth shows as depth - depth_gap above the oracle; its sign decides the
// boolean away from touching.
#include "impact/convex/cylinder_box_pair.hpp"
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

// a named namespace: the convex tests build as one unity file (test_cone_box_pair.cpp's anonymous
// namespace has a Case and cases() too)
namespace cylinder_box_pair_test {

using namespace impact;
using LD = long double;
using V3L = Eigen::Matrix<LD, 3, 1>;

// The overlap along unit n of cylinder a (its frame) and box b placed by R, t there, in long double.
LD overlap_ld(const Cylinder<double>& a, const Box<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const V3L& n) {
  const LD cyl = LD(a.half_length) * std::abs(n.z()) + LD(a.radius) * std::sqrt(n.x() * n.x() + n.y() * n.y());
  LD box = -(LD(t.x()) * n.x() + LD(t.y()) * n.y() + LD(t.z()) * n.z());
  for (int i = 0; i < 3; ++i) box += LD(b.half[i]) * std::abs(LD(R(0, i)) * n.x() + LD(R(1, i)) * n.y() + LD(R(2, i)) * n.z());
  return cyl + box;
}

using Least = test::LeastOverlap;

// The least overlap by test::least_overlap: the kink circles normal to the box's axes (its edges)
// and to the cylinder's axis (its side), the box's six face normals, the cylinder's two cap
// normals and `extra` (the normal under test) as starts.
Least depth_oracle(const Cylinder<double>& a, const Box<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                   const Eigen::Vector3d& extra) {
  const auto f = [&](const V3L& n) { return overlap_ld(a, b, R, t, n); };
  std::vector<Eigen::Vector3d> starts;
  for (int i = 0; i < 3; ++i) {
    starts.push_back(R.col(i));
    starts.push_back(-R.col(i));
  }
  starts.push_back(Eigen::Vector3d::UnitZ());
  starts.push_back(-Eigen::Vector3d::UnitZ());
  starts.push_back(extra);
  const std::vector<test::KinkCircle> circles = {{R.col(0), 0}, {R.col(1), 0}, {R.col(2), 0}, {Eigen::Vector3d::UnitZ(), 0}};
  return test::least_overlap(f, starts, circles);
}

struct Case {
  Cylinder<double> cyl{0.5, 0.6};
  Box<double> box{Eigen::Vector3d(0.4, 0.3, 0.5)};
  RigidTransform<double> pa, pb;
};

// Cylinders and boxes of varied proportions (the zoo's first), b about a; every fifth box turned
// about a's axis only (a box axis parallel to the cylinder's: edges along the rulings, faces
// parallel to the caps), `scale` and `offset` scaling and moving the whole scene.
std::vector<Case> cases(int n, std::uint64_t seed, double scale = 1, double offset = 0) {
  test::Rng rng(seed);
  std::vector<Case> out;
  for (int k = 0; k < n; ++k) {
    Case c;
    if (k % 4 != 0) {
      c.cyl = Cylinder<double>(rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0));
      c.box = Box<double>(Eigen::Vector3d(rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0), rng.uniform(0.05, 1.0)));
    }
    const double reach = 0.6 * (shape_size(c.cyl) + shape_size(c.box));
    c.pa = {rng.rotation(), Eigen::Vector3d(rng.vec(-1, 1) + Eigen::Vector3d::Constant(offset))};
    Eigen::Matrix3d Rb = rng.rotation();
    if (k % 5 == 0) Rb = c.pa.R * Eigen::AngleAxisd(rng.uniform(0, 2 * M_PI), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    c.pb = {Rb, Eigen::Vector3d(c.pa.t + rng.vec(-reach, reach))};
    c.cyl = Cylinder<double>(c.cyl.radius * scale, c.cyl.half_length * scale);
    c.box = Box<double>(Eigen::Vector3d(c.box.half * scale));
    c.pa.t *= scale;
    c.pb.t *= scale;
    out.push_back(c);
  }
  return out;
}

template <class S>
RigidTransform<S> pose_as(const RigidTransform<double>& p) {
  return {p.R.cast<S>(), p.t.cast<S>()};
}

// Each certified candidate: its lower bound below the oracle's depth (an upper bound of the true
// one), its depth within the tolerance of it and the overlap along its normal; every kind
// certified (a box face, a cylinder cap, the cylinder's side against a corner or an edge).
TEST(CylinderBoxPair, CertifiedDepthsAgainstTheOracle) {
  int certified = 0, face = 0, cap = 0, side = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 40 : 200, 615)) {
    const double size = std::max(shape_size(c.cyl), shape_size(c.box)), tol = 1e-10 * size;
    const detail::PairFrame<double> f(c.pa, c.pb);
    ConvexContact<double> k;
    if (!detail::cylinder_box_contact(c.cyl, c.box, f.R, f.t, tol, k)) continue;
    ++certified;
    const Least o = depth_oracle(c.cyl, c.box, f.R, f.t, k.normal);
    const double oracle = double(o.depth);
    EXPECT_GT(oracle, 0) << "certified a pair the oracle finds apart";
    EXPECT_LE(k.depth - k.depth_gap, oracle + 1e-12 * size) << "lower bound above the depth";
    EXPECT_NEAR(k.depth, oracle, 1e-9 * size);
    EXPECT_NEAR(double(overlap_ld(c.cyl, c.box, f.R, f.t, k.normal.cast<LD>())), k.depth, 1e-12 * size);
    if ((f.R.transpose() * k.normal).cwiseAbs().maxCoeff() > 1 - 1e-12) {
      ++face;
    } else if (std::abs(k.normal.z()) > 1 - 1e-12) {
      ++cap;
    } else {
      ++side;
    }
  }
  EXPECT_GT(face, IMPACT_TEST_SANITIZED ? 0 : 10);
  EXPECT_GT(cap, IMPACT_TEST_SANITIZED ? 0 : 1);
  EXPECT_GT(side, IMPACT_TEST_SANITIZED ? 0 : 5);
}

// A box face against the cylinder's rim point x, x's ball cut by a neighbouring face by delta
// (1e-5 .. 6e-5 of the size), the depth delta / 2 below the face's overlap: in the cylinder's
// frame, the box's corner edge along y at O = (r - A, 0, h - B) inside the cylinder, the box
// turned by phi about y (axes e1 = (cos phi, 0, sin phi), e3 = (-sin phi, 0, cos phi), extending
// along +e1, +e3 from O). x = (r, 0, h) is the cylinder's deepest point across the face normal to
// e1 (overlap a = (x - O) . e1) and lies a - delta from the face normal to e3; with phi =
// delta / (2A) and B from that, the box's lowest edge is B = a - delta / 2 below the cap, so the
// depth is at most a - delta / 2 while every face of the box overlaps by at least a. The whole
// scene is then posed at random. No certificate may claim a face's overlap. Checked to fail: the
// face candidate's ball radius inflated by 1e-4 (it certifies a, delta / 2 above the oracle).
TEST(CylinderBoxPair, FaceBallCutByANeighbour) {
  test::Rng rng(625);
  int checked = 0;
  for (int k = 0; k < (IMPACT_TEST_SANITIZED ? 3 : 12); ++k) {
    const Cylinder<double> cyl(rng.uniform(0.3, 1.0), rng.uniform(0.3, 1.0));
    const double A = rng.uniform(0.02, 0.1) * cyl.radius, delta = rng.uniform(1e-5, 6e-5), phi = delta / (2 * A);
    const double c = std::cos(phi), s = std::sin(phi);
    const double B = (A * (c + s) - delta) / (c - s);  // x's distance to the e3 face is a - delta
    const Eigen::Vector3d e1(c, 0, s), e3(-s, 0, c), O(cyl.radius - A, 0, cyl.half_length - B);
    const Box<double> box(Eigen::Vector3d(0.4, 0.2, 0.4));
    Eigen::Matrix3d Rl;
    Rl << e1, Eigen::Vector3d::UnitY(), e3;
    const RigidTransform<double> pa{rng.rotation(), rng.vec(-1, 1)};
    const RigidTransform<double> pb{Eigen::Matrix3d(pa.R * Rl), pa.apply(Eigen::Vector3d(O + box.half.x() * e1 + box.half.z() * e3))};
    const double size = std::max(shape_size(cyl), shape_size(box));
    const detail::PairFrame<double> f(pa, pb);
    double least_face = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i)
      for (const double sign : {1.0, -1.0}) least_face = std::min(least_face, double(overlap_ld(cyl, box, f.R, f.t, (sign * f.R.col(i)).cast<LD>())));
    ConvexContact<double> got;
    const bool certified = detail::cylinder_box_contact(cyl, box, f.R, f.t, 1e-10 * size, got);
    const double oracle = double(depth_oracle(cyl, box, f.R, f.t, certified ? got.normal : Eigen::Vector3d(Eigen::Vector3d::UnitZ())).depth);
    EXPECT_LT(oracle, least_face - delta / 4) << "the construction: the depth below every face's overlap";
    ++checked;
    if (certified) {
      EXPECT_LE(got.depth - got.depth_gap, oracle + 1e-12 * size) << "lower bound above the depth";
      EXPECT_NEAR(got.depth, oracle, 1e-9 * size);
    }
    const auto p = convex_penetration(cyl, pa, box, pb);
    EXPECT_NEAR(p.depth, oracle, 1e-9 * size);
  }
  EXPECT_EQ(checked, IMPACT_TEST_SANITIZED ? 3 : 12);
}

// The terms of the local certificate are the overlap itself (no branch): equal to the long-double
// overlap on random directions.
TEST(CylinderBoxPair, TermsAreTheOverlap) {
  test::Rng rng(617);
  for (const Case& c : cases(20, 616)) {
    const detail::PairFrame<double> f(c.pa, c.pb);
    const detail::OverlapTerms<double> terms = detail::cylinder_box_terms(c.cyl, c.box, f.R, f.t);
    for (int j = 0; j < 10; ++j) {
      const Eigen::Vector3d n = rng.vec(-1, 1).normalized();
      const double v = test::overlap_terms_value(terms, n);
      const double want = double(overlap_ld(c.cyl, c.box, f.R, f.t, n.cast<LD>()));
      EXPECT_NEAR(v, want, 1e-13);
      EXPECT_NEAR(detail::cylinder_box_overlap(c.cyl, c.box, f.R, f.t, n), want, 1e-13);
    }
  }
}

// The whole penetration and the boolean test, both argument orders, in S, on every pose: the same
// answer as the oracle away from touching; depth within `close` of the size of the oracle's,
// never a lower bound above it.
template <class S>
void check_against_oracle(int count, double scale, double offset, std::uint64_t seed, double close) {
  int hits = 0, apart = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 12 : count, seed, scale, offset)) {
    const double size = std::max(shape_size(c.cyl), shape_size(c.box));
    const Cylinder<S> cyl(S(c.cyl.radius), S(c.cyl.half_length));
    const Box<S> box(c.box.half.cast<S>());
    const RigidTransform<S> pa = pose_as<S>(c.pa), pb = pose_as<S>(c.pb);
    // the oracle on the poses as S holds them
    const RigidTransform<double> qa{pa.R.template cast<double>(), pa.t.template cast<double>()},
        qb{pb.R.template cast<double>(), pb.t.template cast<double>()};
    const detail::PairFrame<double> f(qa, qb);
    const Cylinder<double> cd(double(cyl.radius), double(cyl.half_length));
    const Box<double> bd(box.half.template cast<double>());
    const auto p = convex_penetration(cyl, pa, box, pb);
    const auto q = convex_penetration(box, pb, cyl, pa);
    const Eigen::Vector3d extra = p.intersecting ? Eigen::Vector3d(qa.R.transpose() * p.normal.template cast<double>()) : Eigen::Vector3d::UnitZ();
    const double oracle = double(depth_oracle(cd, bd, f.R, f.t, extra).depth);
    if (std::abs(oracle) < std::max(1e-5, 10 * close) * size) continue;  // touching: either answer
    EXPECT_EQ(convex_intersect(cyl, pa, box, pb), oracle > 0);
    EXPECT_EQ(convex_intersect(box, pb, cyl, pa), oracle > 0);
    EXPECT_EQ(p.intersecting, oracle > 0);
    EXPECT_EQ(q.intersecting, oracle > 0);
    if (oracle < 0) ++apart;
    if (oracle < 0 || !p.intersecting || !q.intersecting) continue;
    ++hits;
    for (const auto& r : {p, q}) {
      EXPECT_LE(double(r.depth - r.depth_gap), oracle + close * size) << "lower bound above the depth";
      EXPECT_NEAR(double(r.depth), oracle, close * size);
      EXPECT_FALSE(r.limit_reached);
    }
    EXPECT_NEAR(double((p.normal + q.normal).norm()), 0, 1e-3);
  }
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 1 : count / 5);
  EXPECT_GT(apart, IMPACT_TEST_SANITIZED ? 0 : count / 20);
}

TEST(CylinderBoxPair, PenetrationAndBooleanAgainstTheOracle) {
  check_against_oracle<double>(80, 1, 0, 618, 1e-9);
  check_against_oracle<float>(40, 1, 0, 619, 2e-4);
}

TEST(CylinderBoxPair, ScaledAndTranslated) {
  check_against_oracle<double>(30, 1e-3, 0, 620, 1e-9);
  check_against_oracle<double>(30, 1e3, 0, 621, 1e-9);
  check_against_oracle<double>(30, 1, 1e3, 622, 1e-9);
  check_against_oracle<float>(30, 1e2, 0, 623, 2e-4);
}

// The boolean within 1e-7 of the size of touching: b moved along the oracle's normal by its depth
// plus or minus 1e-7 (beyond: apart; short of it: every overlap stays at least 1e-7 positive).
TEST(CylinderBoxPair, BooleanNearTouching) {
  int checked = 0;
  for (const Case& c : cases(IMPACT_TEST_SANITIZED ? 12 : 40, 624)) {
    const double size = std::max(shape_size(c.cyl), shape_size(c.box));
    const detail::PairFrame<double> f(c.pa, c.pb);
    const Least o = depth_oracle(c.cyl, c.box, f.R, f.t, Eigen::Vector3d::UnitZ());
    if (!(o.depth > 1e-3 * size)) continue;
    ++checked;
    const Eigen::Vector3d n = c.pa.R * o.normal.cast<double>().normalized();
    for (const double delta : {1e-7, -1e-7}) {
      const RigidTransform<double> moved{c.pb.R, Eigen::Vector3d(c.pb.t + (double(o.depth) + delta * size) * n)};
      EXPECT_EQ(convex_intersect(c.cyl, c.pa, c.box, moved), delta < 0) << delta;
      EXPECT_EQ(convex_intersect(c.box, moved, c.cyl, c.pa), delta < 0) << delta;
    }
  }
  EXPECT_GT(checked, IMPACT_TEST_SANITIZED ? 1 : 8);
}

}  // namespace cylinder_box_pair_test
