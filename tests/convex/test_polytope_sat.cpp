// SPDX-License-Identifier: MIT
// Box–hull penetration by the separating-axis test (convex/polytope_sat.hpp) against an oracle
// written here: the exact polytope depth, the least overlap over every face normal of both shapes
// and every cross product of a box edge and a hull triangle edge, each overlap from the vertices
// by brute force (no support function, no Gauss map). Also against box–box's own separating axes
// (a hull of a box's corners), and degenerate poses: parallel edges and faces, touching faces,
// coincident centres, far from the origin, float against double. Hull–hull: the line between the
// centres that precedes GJK + EPA against brute force.
//
// Stated tolerances (relative to the larger shape's size): depth 1e-12 in double against the
// oracle (the test's skipped near-parallel edge pairs allow 1.5e-8; none of these poses comes that
// close), 1e-5 in float; booleans: no mismatch where the oracle's |depth| > 1e-9.
#include "impact/convex/polytope_sat.hpp"
#include "impact/convex/query.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace {

using namespace impact;
using SatV3 = Eigen::Vector3d;
using SatPose = RigidTransform<double>;

// The corners of box b at pose p, in the world.
std::vector<SatV3> sat_box_corners(const Box<double>& b, const SatPose& p) {
  std::vector<SatV3> out;
  for (int i = 0; i < 8; ++i)
    out.push_back(p.apply(SatV3((i & 1) ? b.half.x() : -b.half.x(), (i & 2) ? b.half.y() : -b.half.y(), (i & 4) ? b.half.z() : -b.half.z())));
  return out;
}
std::vector<SatV3> sat_hull_points(const ConvexHull<double>& h, const SatPose& p) {
  std::vector<SatV3> out;
  for (Eigen::Index i = 0; i < h.vertices.rows(); ++i) out.push_back(p.apply(SatV3(h.vertices.row(i).transpose())));
  return out;
}

// The exact penetration depth by brute force (negative: apart; its magnitude then is only a bound).
double sat_oracle_depth(const Box<double>& a, const SatPose& pa, const ConvexHull<double>& b, const SatPose& pb) {
  const std::vector<SatV3> va = sat_box_corners(a, pa), vb = sat_hull_points(b, pb);
  const auto overlap = [&](const SatV3& n) {
    double ta = -std::numeric_limits<double>::infinity(), lb = std::numeric_limits<double>::infinity();
    for (const SatV3& v : va) ta = std::max(ta, n.dot(v));
    for (const SatV3& v : vb) lb = std::min(lb, n.dot(v));
    return ta - lb;
  };
  std::vector<SatV3> axes, edges_b;
  for (int k = 0; k < 3; ++k) axes.push_back(pa.R.col(k));
  for (Eigen::Index t = 0; t < b.triangles.rows(); ++t) {
    const SatV3 x = pb.apply(SatV3(b.vertices.row(b.triangles(t, 0)).transpose())), y = pb.apply(SatV3(b.vertices.row(b.triangles(t, 1)).transpose())),
                z = pb.apply(SatV3(b.vertices.row(b.triangles(t, 2)).transpose()));
    axes.push_back((y - x).cross(z - x));
    edges_b.push_back(y - x);
    edges_b.push_back(z - y);
    edges_b.push_back(x - z);
  }
  for (int k = 0; k < 3; ++k)
    for (const SatV3& e : edges_b) axes.push_back(SatV3(pa.R.col(k)).cross(e));
  double best = std::numeric_limits<double>::infinity();
  for (const SatV3& n : axes) {
    if (n.norm() < 1e-12 * std::max(1.0, n.cwiseAbs().maxCoeff())) continue;
    const SatV3 u = n.normalized();
    best = std::min({best, overlap(u), overlap(SatV3(-u))});
  }
  return best;
}

ConvexHull<double> sat_ellipsoid_hull(int n, std::uint64_t seed) {
  test::Rng rng(seed);
  Vertices<double> p(n, 3);
  for (int i = 0; i < n; ++i) {
    SatV3 d = rng.vec(-1, 1);
    while (d.norm() < 0.1) d = rng.vec(-1, 1);
    d.normalize();
    p.row(i) = SatV3(0.5 * d.x(), 0.35 * d.y(), 0.45 * d.z()).transpose();
  }
  return convex_hull(p);
}

// A contact's own consistency: unit normal, depth = the overlap along it (brute force), the
// deepest points on their shapes' supporting planes.
void sat_check_contact(const ConvexContact<double>& c, const Box<double>& a, const SatPose& pa, const ConvexHull<double>& b, const SatPose& pb,
                       double tol, const char* what) {
  const std::vector<SatV3> va = sat_box_corners(a, pa), vb = sat_hull_points(b, pb);
  double ta = -std::numeric_limits<double>::infinity(), lb = std::numeric_limits<double>::infinity();
  for (const SatV3& v : va) ta = std::max(ta, c.normal.dot(v));
  for (const SatV3& v : vb) lb = std::min(lb, c.normal.dot(v));
  EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12) << what;
  EXPECT_NEAR(c.depth, ta - lb, tol) << what;
  EXPECT_NEAR(c.normal.dot(c.point_a()), ta, tol) << what;
  EXPECT_NEAR(c.normal.dot(c.point_b()), lb, tol) << what;
}

// Random poses (half near, half farther) of a box against hulls of 8 to 60 points (the sizes the
// test answers) and one of 100 (EPA answers): the boolean and the depth against the oracle, the
// contact's consistency, and the hull–box order giving the same depth and the opposite normal.
TEST(ConvexPolytopeSat, BoxHullAgainstBruteForceDepth) {
  const Box<double> box{SatV3(0.4, 0.3, 0.5)};
  const int n_poses = IMPACT_TEST_SANITIZED ? 12 : 100;
  int hits = 0, answered_by_sat = 0;
  for (int points : {8, 20, 40, 60, 100}) {
    const ConvexHull<double> hull = sat_ellipsoid_hull(points, 500 + static_cast<std::uint64_t>(points));
    answered_by_sat += detail::use_box_hull_sat(hull);
    test::Rng rng(900 + static_cast<std::uint64_t>(points));
    for (int i = 0; i < n_poses; ++i) {
      const double reach = i % 2 ? 0.5 : 1.2;
      const SatPose pa{rng.rotation(), rng.vec(-0.2, 0.2)};
      const SatPose pb{rng.rotation(), rng.vec(-reach, reach)};
      const double truth = sat_oracle_depth(box, pa, hull, pb);
      const auto c = convex_penetration(box, pa, hull, pb);
      const auto sat = detail::box_hull_sat(box, pa, hull, pb);
      if (std::abs(truth) > 1e-9) {
        EXPECT_EQ(c.intersecting, truth > 0) << points << " points, pose " << i;
        EXPECT_EQ(sat.intersecting, truth > 0) << points << " points, pose " << i;
      }
      if (!(truth > 1e-9 && c.intersecting && sat.intersecting)) continue;
      ++hits;
      EXPECT_NEAR(sat.depth, truth, 1e-12) << points << " points, pose " << i;
      EXPECT_NEAR(c.depth, truth, 1e-9) << points << " points, pose " << i;
      sat_check_contact(sat, box, pa, hull, pb, 1e-12, "box-hull");
      const auto r = convex_penetration(hull, pb, box, pa);
      ASSERT_TRUE(r.intersecting);
      EXPECT_NEAR(r.depth, c.depth, 1e-9);
      if (detail::use_box_hull_sat(hull)) {  // the same test with the roles swapped back
        EXPECT_NEAR((r.normal + c.normal).norm(), 0.0, 1e-12);
        EXPECT_NEAR((r.point - c.point).norm(), 0.0, 1e-12);
      }
    }
  }
  EXPECT_EQ(answered_by_sat, 4);  // the 100-point hull (196 faces) goes to EPA
  EXPECT_GT(hits, IMPACT_TEST_SANITIZED ? 5 : 150);
}

// A hull of a box's eight corners (its coplanar triangles merged into six squares, its edges
// parallel in threes) against a box, at random rotations: the same depth as box–box's 15 axes, and
// aligned poses whose edges are all parallel (every edge pair skipped: the faces decide), touching
// faces (depth 0, intersecting), a hair apart, coincident centres, and 1e6 from the origin.
TEST(ConvexPolytopeSat, BoxShapedHullDegenerateFeatures) {
  const Box<double> box{SatV3(0.4, 0.3, 0.5)}, other{SatV3(0.2, 0.35, 0.25)};
  Vertices<double> corners(8, 3);
  for (int i = 0; i < 8; ++i)
    corners.row(i) = SatV3((i & 1) ? other.half.x() : -other.half.x(), (i & 2) ? other.half.y() : -other.half.y(), (i & 4) ? other.half.z() : -other.half.z())
                         .transpose();
  const ConvexHull<double> hull = convex_hull(corners);
  ASSERT_EQ(hull.faces.size(), 6u);
  ASSERT_EQ(hull.edges.size(), 12u);
  test::Rng rng(4242);
  for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 10 : 100); ++i) {
    const SatPose pa{rng.rotation(), rng.vec(-0.3, 0.3)};
    const SatPose pb{rng.rotation(), rng.vec(-0.6, 0.6)};
    const auto h = convex_penetration(box, pa, hull, pb);
    const auto bb = convex_penetration(box, pa, other, pb);
    ASSERT_EQ(h.intersecting, bb.intersecting) << "pose " << i;
    if (h.intersecting) {
      EXPECT_NEAR(h.depth, bb.depth, 1e-12) << "pose " << i;
      EXPECT_NEAR(h.depth, sat_oracle_depth(box, pa, hull, pb), 1e-12) << "pose " << i;
    }
  }
  for (double far : {0.0, 1e6}) {
    const SatV3 shift(far, -far, 0.5 * far);
    const SatPose pa{Eigen::Matrix3d::Identity(), shift};
    // Aligned, overlapping by 0.1 along x (the least axis): every edge pair parallel.
    const SatPose pb{Eigen::Matrix3d::Identity(), SatV3(shift + SatV3(0.5, 0.05, -0.1))};
    const auto c = convex_penetration(box, pa, hull, pb);
    ASSERT_TRUE(c.intersecting);
    EXPECT_NEAR(c.depth, 0.1, 1e-12 * std::max(1.0, far));
    EXPECT_NEAR((c.normal - SatV3::UnitX()).norm(), 0.0, 1e-12);
    // Face on face, touching: intersecting with depth 0; a hair apart: not intersecting.
    const SatPose touch{Eigen::Matrix3d::Identity(), SatV3(shift + SatV3(0, 0, 0.75))};
    const auto t = convex_penetration(box, pa, hull, touch);
    ASSERT_TRUE(t.intersecting);  // the offsets are exact here, so the touching face decides
    EXPECT_EQ(t.depth, 0.0);
    EXPECT_NEAR((t.normal - SatV3::UnitZ()).norm(), 0.0, 1e-12);
    const SatPose apart{Eigen::Matrix3d::Identity(), SatV3(shift + SatV3(0, 0, 0.75 + 1e-9 * std::max(1.0, far)))};
    EXPECT_FALSE(convex_penetration(box, pa, hull, apart).intersecting);
    // Coincident centres, rotated: the depth of the oracle (a deep overlap).
    const SatPose rotated{Eigen::AngleAxisd(0.4, SatV3(1, 2, 3).normalized()).toRotationMatrix(), shift};
    const auto deep = convex_penetration(box, pa, hull, rotated);
    ASSERT_TRUE(deep.intersecting);
    EXPECT_NEAR(deep.depth, sat_oracle_depth(box, pa, hull, rotated), 1e-12 * std::max(1.0, far));
    EXPECT_NEAR(deep.depth, convex_penetration(box, pa, other, rotated).depth, 1e-12 * std::max(1.0, far));
  }
}

// Float against double on the same poses: the same booleans away from touching, depths within 1e-5.
TEST(ConvexPolytopeSat, FloatMatchesDouble) {
  const ConvexHull<double> hull = sat_ellipsoid_hull(30, 31);
  const ConvexHull<float> hull_f = convex_hull(Vertices<float>(hull.vertices.cast<float>()));
  const Box<double> box{SatV3(0.4, 0.3, 0.5)};
  const Box<float> box_f{Eigen::Vector3f(0.4f, 0.3f, 0.5f)};
  ASSERT_TRUE(detail::use_box_hull_sat(hull_f));
  test::Rng rng(3131);
  int compared = 0;
  for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 10 : 100); ++i) {
    const SatPose pa{rng.rotation(), rng.vec(-0.2, 0.2)};
    const SatPose pb{rng.rotation(), rng.vec(-0.7, 0.7)};
    const RigidTransform<float> pa_f{pa.R.cast<float>(), pa.t.cast<float>()}, pb_f{pb.R.cast<float>(), pb.t.cast<float>()};
    const auto d = convex_penetration(box, pa, hull, pb);
    const auto f = convex_penetration(box_f, pa_f, hull_f, pb_f);
    const double truth = sat_oracle_depth(box, pa, hull, pb);
    if (std::abs(truth) < 1e-4) continue;
    ASSERT_EQ(f.intersecting, d.intersecting) << "pose " << i;
    if (!d.intersecting) continue;
    ++compared;
    EXPECT_NEAR(double(f.depth), d.depth, 1e-5) << "pose " << i;
  }
  EXPECT_GT(compared, IMPACT_TEST_SANITIZED ? 1 : 20);
}

// Hull–hull penetration starts with the line between the centres: whenever it reports the hulls
// apart, the overlap along that line from every vertex (brute force) is negative, and the query
// agrees with GJK + EPA on every pose (boolean, depth).
TEST(ConvexPolytopeSat, HullPairCentreLine) {
  const ConvexHull<double> ha = sat_ellipsoid_hull(40, 41), hb = sat_ellipsoid_hull(24, 42);
  test::Rng rng(4343);
  int separated = 0;
  for (int i = 0; i < (IMPACT_TEST_SANITIZED ? 20 : 300); ++i) {
    const SatPose pa{rng.rotation(), rng.vec(-0.2, 0.2)};
    const SatPose pb{rng.rotation(), rng.vec(-1.0, 1.0)};
    const auto c = convex_penetration(ha, pa, hb, pb);
    const auto e = detail::general_penetration(ha, pa, hb, pb, ConvexQueryOptions<double>{});
    ASSERT_EQ(c.intersecting, e.intersecting) << "pose " << i;
    if (c.intersecting) { EXPECT_EQ(c.depth, e.depth) << "pose " << i; }
    if (!detail::centre_line_separates(ha, pa, hb, pb)) continue;
    ++separated;
    const SatV3 n = (pb.apply(hb.centroid) - pa.apply(ha.centroid)).normalized();
    double top_a = -std::numeric_limits<double>::infinity(), low_b = std::numeric_limits<double>::infinity();
    for (const SatV3& v : sat_hull_points(ha, pa)) top_a = std::max(top_a, n.dot(v));
    for (const SatV3& v : sat_hull_points(hb, pb)) low_b = std::min(low_b, n.dot(v));
    EXPECT_LT(top_a, low_b) << "pose " << i;
    EXPECT_FALSE(c.intersecting);
  }
  EXPECT_GT(separated, IMPACT_TEST_SANITIZED ? 2 : 100);
}

}  // namespace
