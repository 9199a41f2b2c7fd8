// SPDX-License-Identifier: MIT
// Oriented box fitting: every box contains every point it was fitted to, checked in long double by
// solving center + axes h = p for h (so the stored, rounded axes are taken as they are, not as if
// orthonormal); degenerate point sets give finite boxes; the area-weighted axes follow the
// surface, not the vertex density; the OBB traits' merge, transform and overlap are conservative.
#include "impact/fit/bv_traits.hpp"
#include "impact/fit/obb_fit.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

using namespace impact;
using namespace impact::test;

namespace {

using Mat3L = Eigen::Matrix<long double, 3, 3>;
using Vec3L = Eigen::Matrix<long double, 3, 1>;

/// Coordinates of p in the box's (possibly slightly skewed) frame, in long double.
template <class S> Vec3L local(const Obb<S>& b, const Vec3L& p) {
  const Mat3L A = b.axes.template cast<long double>();
  return A.fullPivLu().solve(Vec3L(p - b.center.template cast<long double>()));
}
template <class S> Vec3L local(const Obb<S>& b, const Vec3<S>& p) { return local(b, Vec3L(p.template cast<long double>())); }

template <class S> bool contains(const Obb<S>& b, const Vec3<S>& p) {
  const Vec3L h = local(b, p);
  for (int k = 0; k < 3; ++k)
    if (!(std::abs(h[k]) <= static_cast<long double>(b.half[k]))) return false;
  return true;
}

template <class S> void expect_holds(const Obb<S>& b, const std::vector<Vec3<S>>& pts) {
  ASSERT_TRUE(all_finite(b.center) && all_finite(b.axes) && all_finite(b.half));
  EXPECT_TRUE((b.half.array() >= S(0)).all());
  EXPECT_NEAR(double(b.axes.determinant()), 1.0, 1e-5);
  for (const auto& p : pts) ASSERT_TRUE(contains(b, p)) << p.transpose();
  // the ball (Obb::radius) holds every point too, measured in long double
  for (const auto& p : pts)
    ASSERT_LE((p.template cast<long double>() - b.center.template cast<long double>()).norm(), static_cast<long double>(b.radius))
        << p.transpose();
}

template <class S> std::vector<Vec3<S>> cloud(Rng& rng, int n, double scale, const Eigen::Vector3d& offset, const Eigen::Matrix3d& shape) {
  std::vector<Vec3<S>> pts;
  for (int i = 0; i < n; ++i) pts.push_back((offset + scale * (shape * rng.vec(-1, 1))).cast<S>());
  return pts;
}

}  // namespace

template <class S> class ObbFitTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ObbFitTest, Scalars);

TYPED_TEST(ObbFitTest, ContainsEveryPointAtEveryScale) {
  using S = TypeParam;
  Rng rng(5);
  int boxes = 0;
  for (double scale : {1e-30, 1e-6, 1.0, 1e5, 1e30}) {
    for (double off : {0.0, 1.0, 1e3, 1e7}) {
      for (int trial = 0; trial < 20; ++trial) {
        const Eigen::Matrix3d shape = rng.rotation() * Eigen::Vector3d(1.0, rng.uniform(0, 1), rng.uniform(0, 0.1)).asDiagonal();
        const auto pts = cloud<S>(rng, 3 * (1 + int(rng.index(40))), scale, rng.vec(-1, 1) * off * scale, shape);
        for (ObbFit m : {ObbFit::TriangleArea, ObbFit::Points}) {
          expect_holds(fit_obb(pts.data(), pts.size(), m), pts);
          ++boxes;
        }
      }
    }
  }
  EXPECT_EQ(boxes, 800);
}

TYPED_TEST(ObbFitTest, DegeneratePointSets) {
  using S = TypeParam;
  Rng rng(6);
  const Vec3<S> p = Vec3<S>(S(0.3), S(-2), S(7));
  const Vec3<S> d = rng.vec(-1, 1).normalized().template cast<S>();
  const Vec3<S> e = d.cross(Vec3<S>(S(0.2), S(1), S(0.5))).normalized();
  std::vector<std::vector<Vec3<S>>> sets = {
      {p},                                                   // one point
      {p, p, p, p, p, p},                                    // coincident
      {p, Vec3<S>(p + d), Vec3<S>(p + S(2.5) * d), Vec3<S>(p - d), Vec3<S>(p + S(0.1) * d), p},  // collinear
  };
  std::vector<Vec3<S>> plane;  // coplanar, triangles of zero thickness
  for (int i = 0; i < 30; ++i) plane.push_back(Vec3<S>(p + S(rng.uniform(-1, 1)) * d + S(rng.uniform(-1, 1)) * e));
  sets.push_back(plane);
  for (const auto& pts : sets) {
    for (ObbFit m : {ObbFit::TriangleArea, ObbFit::Points}) {
      const Obb<S> b = fit_obb(pts.data(), pts.size(), m);
      expect_holds(b, pts);
      // a flat set gives a flat box: its smallest extent is within rounding of zero
      EXPECT_LE(double(b.half.minCoeff()), 1e-5 * (1 + double(p.norm())));
    }
  }
}

TYPED_TEST(ObbFitTest, AxesFollowALongThinSet) {
  using S = TypeParam;
  // a long thin box along a random direction: the box's main axis is that direction and the box is
  // far smaller than the axis-aligned one
  Rng rng(7);
  const Eigen::Matrix3d Q = rng.rotation();
  const auto pts = cloud<S>(rng, 300, 1.0, Eigen::Vector3d(4, 5, 6), Q * Eigen::Vector3d(10.0, 0.5, 0.1).asDiagonal());
  const Obb<S> b = fit_obb(pts.data(), pts.size(), ObbFit::Points);
  expect_holds(b, pts);
  EXPECT_GT(std::abs(double(b.axes.col(0).template cast<double>().dot(Q.col(0)))), 0.999);
  Aabb<S> box;
  for (const auto& q : pts) box.extend(q);
  EXPECT_LT(double(b.half.prod()) * 8, 0.2 * double(box.extent().prod()));
}

TYPED_TEST(ObbFitTest, KeepsTheCoordinateAxesWhenTheirBoxIsClearlySmaller) {
  using S = TypeParam;
  // The corners of a unit box, two opposite vertical edges (x = y) sampled densely: the covariance's
  // main axis is the diagonal (1, 1, 0), whose box is twice the axis-aligned box (2 against 1).
  // The fit keeps the coordinate axes: the box is the unit box, up to the rounding pad.
  std::vector<Vec3<S>> pts;
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2; ++y)
      for (int z = 0; z < 2; ++z) pts.emplace_back(S(x), S(y), S(z));
  for (int k = 0; k <= 20; ++k) {
    pts.emplace_back(S(0), S(0), S(k / 20.0));
    pts.emplace_back(S(1), S(1), S(k / 20.0));
  }
  const Obb<S> b = fit_obb(pts.data(), pts.size(), ObbFit::Points);
  expect_holds(b, pts);
  EXPECT_NEAR(double(b.half.prod()) * 8, 1.0, 1e-5);
  // moved off the origin and turned by a quarter turn about z (still axis-aligned): the same box
  for (auto& p : pts) p = Vec3<S>(S(1e3) - p.y(), S(-2e3) + p.x(), p.z());
  const Obb<S> moved = fit_obb(pts.data(), pts.size(), ObbFit::Points);
  expect_holds(moved, pts);
  EXPECT_NEAR(double(moved.half.prod()) * 8, 1.0, sizeof(S) == 4 ? 1e-2 : 1e-5);  // float: the pad for rounding at 2e3
}

TYPED_TEST(ObbFitTest, TriangleAreaIgnoresVertexDensity) {
  using S = TypeParam;
  // A 4 x 1 rectangle tessellated finely at one end only: the vertex covariance's main axis is
  // pulled away from the long side by the dense end; the area-weighted one is the long side.
  std::vector<Vec3<S>> tris;
  auto quad = [&](double x0, double x1, double y0, double y1) {
    const Vec3<S> a(S(x0), S(y0), 0), b(S(x1), S(y0), 0), c(S(x1), S(y1), 0), d(S(x0), S(y1), 0);
    tris.insert(tris.end(), {a, b, c, a, c, d});
  };
  quad(0.5, 4.0, 0.0, 1.0);  // one big quad
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 40; ++j) quad(0.5 * i / 20, 0.5 * (i + 1) / 20, j / 40.0, (j + 1) / 40.0);
  // rotate the whole set so that no axis is special
  const Eigen::Matrix3d Q = Rng(8).rotation();
  for (auto& q : tris) q = (Q * q.template cast<double>()).template cast<S>();
  const Obb<S> area = fit_obb(tris.data(), tris.size(), ObbFit::TriangleArea);
  const Obb<S> points = fit_obb(tris.data(), tris.size(), ObbFit::Points);
  expect_holds(area, tris);
  expect_holds(points, tris);
  EXPECT_GT(std::abs(double(area.axes.col(0).template cast<double>().dot(Q.col(0)))), 0.99);
  // the area-weighted box is the rectangle itself: 4 x 1 x 0
  EXPECT_NEAR(double(area.half.prod()), 0.0, 1e-5);
  EXPECT_NEAR(2 * double(area.half[0]) * 2 * double(area.half[1]), 4.0, 1e-4);
  EXPECT_LT(std::abs(double(points.axes.col(0).template cast<double>().dot(Q.col(0)))), 0.99);
}

TYPED_TEST(ObbFitTest, MergeAndTransformContainTheirInputs) {
  using S = TypeParam;
  using T = BvTraits<Obb<S>>;
  Rng rng(9);
  for (int trial = 0; trial < 200; ++trial) {
    const double off = trial % 2 ? 1e4 : 1.0;
    const auto pa = cloud<S>(rng, 12, 1.0, rng.vec(-off, off), rng.rotation() * Eigen::Vector3d(1, 0.3, 0.01).asDiagonal());
    const auto pb = cloud<S>(rng, 12, 0.1, rng.vec(-off, off), rng.rotation());
    const Obb<S> a = T::fit(pa.data(), pa.size()), b = T::fit(pb.data(), pb.size());
    const Obb<S> m = T::merge(a, b);
    expect_holds(m, pa);
    expect_holds(m, pb);
    const RigidTransform<double> xf = random_pose(rng, Eigen::Vector3d::Constant(-off), Eigen::Vector3d::Constant(off));
    const RigidTransform<S> xs = xf.cast<S>();
    const Obb<S> moved = T::transformed(a, xs);
    // the transformed box holds the points moved exactly (long double) by the same transform
    for (const auto& q : pa) {
      const Vec3L h = local(moved, Vec3L(xs.R.template cast<long double>() * q.template cast<long double>() + xs.t.template cast<long double>()));
      for (int k = 0; k < 3; ++k) ASSERT_LE(std::abs(h[k]), static_cast<long double>(moved.half[k]));
      const Vec3L mq = xs.R.template cast<long double>() * q.template cast<long double>() + xs.t.template cast<long double>();
      ASSERT_LE((mq - moved.center.template cast<long double>()).norm(), static_cast<long double>(moved.radius));
    }
  }
}

TYPED_TEST(ObbFitTest, OverlapNeverMissesTouchingBoxes) {
  using S = TypeParam;
  using T = BvTraits<Obb<S>>;
  // Box b is placed so that one of its corners is exactly a point of box a's surface (computed in
  // long double and rounded): the test must accept every such pair, at every offset from the
  // origin; pairs moved apart by 1 % of their size along a's face normal must be rejected.
  Rng rng(10);
  int rejected_apart = 0, trials = 0;
  for (double off : {0.0, 1.0, 1e3, 1e6}) {
    for (int trial = 0; trial < 300; ++trial, ++trials) {
      Obb<S> a;
      a.axes = rng.rotation().cast<S>();
      a.center = (rng.vec(-1, 1) * off).cast<S>();
      a.half = (rng.vec(0.1, 1)).cast<S>();
      Obb<S> b;
      b.axes = rng.rotation().cast<S>();
      b.half = (rng.vec(0.1, 1)).cast<S>();
      // a point on a's +x face and b's corner (-,-,-) on it
      const Vec3L on_face = a.center.template cast<long double>() +
                            a.axes.template cast<long double>() *
                                Vec3L(static_cast<long double>(a.half[0]), (long double)rng.uniform(-1, 1) * a.half[1], (long double)rng.uniform(-1, 1) * a.half[2]);
      // b's centre such that its corner lies on the face, b outside a: choose b's axes so that
      // the corner points into a (b's axes are random; take the corner most opposed to a's normal)
      const Vec3L n = a.axes.col(0).template cast<long double>();
      Vec3L h;
      for (int k = 0; k < 3; ++k) h[k] = (b.axes.col(k).template cast<long double>().dot(n) > 0 ? -1 : 1) * (long double)b.half[k];
      b.center = (on_face - b.axes.template cast<long double>() * h).template cast<S>();
      EXPECT_TRUE(T::overlap(a, b)) << "offset " << off;
      EXPECT_TRUE(T::overlap(b, a));
      // the same through a transform: move both by a random pose
      const RigidTransform<S> xf = random_pose(rng, Eigen::Vector3d::Constant(-off), Eigen::Vector3d::Constant(off)).cast<S>();
      EXPECT_TRUE(T::overlap(T::transformed(a, xf), b, xf)) << "offset " << off;
      Obb<S> far = b;
      far.center = (b.center.template cast<long double>() + n * (long double)(0.01 + 1e-4 * off * (sizeof(S) == 4 ? 100 : 0))).template cast<S>();
      rejected_apart += !T::overlap(a, far);
    }
  }
  // a corner just off a face is usually separated by a face axis or an edge axis
  EXPECT_GT(rejected_apart, trials / 2);
}

// The one-frame test (BvTraits<Obb>::overlap(a, b), the self-collision walk's) decides as the
// pair frame's test under the identity on every pair: boxes near each other at every offset from
// the origin, with and without balls, both answers occurring.
TYPED_TEST(ObbFitTest, OneFrameTestDecidesAsTheIdentityFrame) {
  using S = TypeParam;
  Rng rng(12);
  int accepted = 0, trials = 0;
  for (double off : {0.0, 1.0, 1e3, 1e6}) {
    for (int trial = 0; trial < 500; ++trial, ++trials) {
      Obb<S> a, b;
      a.axes = rng.rotation().cast<S>();
      b.axes = rng.rotation().cast<S>();
      a.center = (rng.vec(-1, 1) * off).cast<S>();
      b.center = (a.center.template cast<double>() + rng.vec(-1.2, 1.2)).template cast<S>();
      a.half = rng.vec(0.05, 1).cast<S>();
      b.half = rng.vec(0.05, 1).cast<S>();
      a.radius = trial % 3 == 0 ? std::numeric_limits<S>::infinity() : a.half.norm() * S(rng.uniform(0.6, 1.0));
      b.radius = trial % 5 == 0 ? std::numeric_limits<S>::infinity() : b.half.norm() * S(rng.uniform(0.6, 1.0));
      const bool one = ObbPairFrame<S>::overlaps_in_one_frame(a, b);
      ASSERT_EQ(one, ObbPairFrame<S>().overlaps(a, b)) << "offset " << off << " trial " << trial;
      ASSERT_EQ(one, BvTraits<Obb<S>>::overlap(a, b));
      accepted += one;
    }
  }
  EXPECT_GT(accepted, trials / 10);
  EXPECT_LT(accepted, trials - trials / 10);
}

// The edge axes obb_overlap tries (EdgeAxes: a_i x b_j for i, j < EdgeAxes) only leave out
// separations: with fewer, every pair the full test accepts is accepted (random pairs near each
// other, at every offset from the origin, with and without balls, and corner-on-face touching
// pairs through the pair frame the mesh walks use); each count tries axes the smaller one does
// not (some pairs rejected by 2 and accepted by 1, rejected by 3 and accepted by 2).
TYPED_TEST(ObbFitTest, FewerEdgeAxesOnlyAcceptMore) {
  using S = TypeParam;
  Rng rng(13);
  int cut_by_2_only = 0, cut_by_3_only = 0, accepted = 0, trials = 0;
  for (double off : {0.0, 1.0, 1e3, 1e6}) {
    for (int trial = 0; trial < 1500; ++trial, ++trials) {
      Obb<S> a, b;
      a.axes = rng.rotation().cast<S>();
      b.axes = rng.rotation().cast<S>();
      a.center = (rng.vec(-1, 1) * off).cast<S>();
      b.center = (a.center.template cast<double>() + rng.vec(-0.8, 0.8)).template cast<S>();
      // flat boxes, as a surface's patches are: the last axis the thinnest (fit_obb's order)
      a.half = Vec3<S>(S(rng.uniform(0.3, 1)), S(rng.uniform(0.1, 0.6)), S(rng.uniform(0.001, 0.1)));
      b.half = Vec3<S>(S(rng.uniform(0.3, 1)), S(rng.uniform(0.1, 0.6)), S(rng.uniform(0.001, 0.1)));
      a.radius = trial % 3 == 0 ? std::numeric_limits<S>::infinity() : a.half.norm() * S(rng.uniform(0.7, 1.0));
      b.radius = trial % 4 == 0 ? std::numeric_limits<S>::infinity() : b.half.norm() * S(rng.uniform(0.7, 1.0));
      const RigidTransform<S> xf = random_pose(rng, Eigen::Vector3d::Constant(-off), Eigen::Vector3d::Constant(off)).cast<S>();
      const Obb<S> b_moved = BvTraits<Obb<S>>::transformed(b, xf.inverse());  // xf b_moved holds b
      const ObbPairFrame<S> frame(xf);
      auto im3 = frame.image_centre(b_moved), im2 = im3, im1 = im3;
      const bool all3 = frame.template overlaps<3>(a, im3, b_moved);
      const bool two = frame.template overlaps<2>(a, im2, b_moved);
      const bool one = frame.template overlaps<1>(a, im1, b_moved);
      ASSERT_TRUE(!all3 || two) << "offset " << off << " trial " << trial;
      ASSERT_TRUE(!two || one) << "offset " << off << " trial " << trial;
      ASSERT_EQ(all3, frame.overlaps(a, b_moved));  // the default tries all nine
      // the same boxes in one frame, through obb_overlap itself
      const Mat3<S> R = a.axes.transpose() * b.axes;
      const Vec3<S> t = a.axes.transpose() * (b.center - a.center);
      const bool box3 = obb_overlap<S, 3>(a.half, R, t, b.half), box2 = obb_overlap<S, 2>(a.half, R, t, b.half);
      ASSERT_TRUE(!box3 || box2);
      cut_by_2_only += one && !two;
      cut_by_3_only += two && !all3;
      accepted += all3;
    }
  }
  EXPECT_GT(cut_by_2_only, 0);
  EXPECT_GT(cut_by_3_only, 0);
  EXPECT_GT(accepted, trials / 10);
  // touching: b's corner exactly on a's face (as OverlapNeverMissesTouchingBoxes), seen through
  // a random pose, is accepted with two edge axes per box, as with three
  for (double off : {0.0, 1.0, 1e3, 1e6}) {
    for (int trial = 0; trial < 300; ++trial) {
      Obb<S> a, b;
      a.axes = rng.rotation().cast<S>();
      a.center = (rng.vec(-1, 1) * off).cast<S>();
      a.half = rng.vec(0.1, 1).cast<S>();
      b.axes = rng.rotation().cast<S>();
      b.half = rng.vec(0.1, 1).cast<S>();
      const Vec3L on_face = a.center.template cast<long double>() +
                            a.axes.template cast<long double>() *
                                Vec3L(static_cast<long double>(a.half[0]), (long double)rng.uniform(-1, 1) * a.half[1], (long double)rng.uniform(-1, 1) * a.half[2]);
      const Vec3L n = a.axes.col(0).template cast<long double>();
      Vec3L h;
      for (int k = 0; k < 3; ++k) h[k] = (b.axes.col(k).template cast<long double>().dot(n) > 0 ? -1 : 1) * (long double)b.half[k];
      b.center = (on_face - b.axes.template cast<long double>() * h).template cast<S>();
      const RigidTransform<S> xf = random_pose(rng, Eigen::Vector3d::Constant(-off), Eigen::Vector3d::Constant(off)).cast<S>();
      const Obb<S> b_moved = BvTraits<Obb<S>>::transformed(b, xf.inverse());
      const ObbPairFrame<S> frame(xf);
      auto im = frame.image_centre(b_moved);
      ASSERT_TRUE(frame.template overlaps<2>(a, im, b_moved)) << "offset " << off << " trial " << trial;
    }
  }
}

TYPED_TEST(ObbFitTest, BallsNeverRejectTouchingSets) {
  using S = TypeParam;
  using T = BvTraits<Obb<S>>;
  // Two fitted boxes whose point sets share one point exactly must overlap, at every offset from
  // the origin, also through a transform; their balls (Obb::radius) must reject some pairs that
  // the boxes alone accept (pairs apart along a box diagonal), or the balls would test nothing.
  Rng rng(11);
  int ball_only = 0;
  for (double off : {0.0, 1.0, 1e3, 1e6}) {
    for (int trial = 0; trial < 200; ++trial) {
      const auto pa = cloud<S>(rng, 9, 1.0, rng.vec(-off, off), rng.rotation() * Eigen::Vector3d(1, 0.5, 0.2).asDiagonal());
      auto pb = cloud<S>(rng, 9, 0.5, Eigen::Vector3d::Zero(), rng.rotation());
      const Vec3<S> shift = pa[std::size_t(trial % 9)] - pb[0];
      for (auto& q : pb) q = (q + shift).eval();
      pb[0] = pa[std::size_t(trial % 9)];  // exactly shared
      const Obb<S> a = T::fit(pa.data(), pa.size()), b = T::fit(pb.data(), pb.size());
      ASSERT_TRUE(T::overlap(a, b)) << "offset " << off;
      ASSERT_TRUE(T::overlap(b, a)) << "offset " << off;
      const RigidTransform<S> xf = random_pose(rng, Eigen::Vector3d::Constant(-off), Eigen::Vector3d::Constant(off)).cast<S>();
      ASSERT_TRUE(T::overlap(T::transformed(a, xf), b, xf)) << "offset " << off;
      // b moved out along a's box diagonal until only the corners could meet
      Obb<S> far = b;
      far.center = (a.center + a.axes * a.half + b.axes * b.half.cwiseProduct(Vec3<S>(S(-0.9), S(-0.9), S(-0.9)))).eval();
      Obb<S> far_box = far, a_box = a;
      far_box.radius = a_box.radius = std::numeric_limits<S>::infinity();
      ball_only += T::overlap(a_box, far_box) && !T::overlap(a, far);
    }
  }
  EXPECT_GT(ball_only, 0);
}
