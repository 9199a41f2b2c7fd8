// SPDX-License-Identifier: MIT
// The convex primitives: support functions against points sampled from each shape's definition
// (the support point belongs to the shape and no sampled point goes further along the direction),
// bounding boxes, and the validation of the parameters.
#include "impact/convex/shapes.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace {

using impact::Box;
using impact::Capsule;
using impact::Cone;
using impact::Cylinder;
using impact::InvalidInput;
using impact::Sphere;
using impact::test::Rng;
using V3 = Eigen::Vector3d;

// Points of each shape drawn from its definition (boundary-heavy: many on the surface).
std::vector<V3> sample(const Capsule<double>& c, Rng& rng, int n) {
  std::vector<V3> out;
  for (int i = 0; i < n; ++i) {
    V3 d = rng.vec(-1, 1);
    if (d.norm() < 1e-3) continue;
    d.normalize();
    const double z = rng.uniform(-c.half_length, c.half_length);
    out.push_back(V3(0, 0, z) + c.radius * d);
    out.push_back(V3(0, 0, d.z() >= 0 ? c.half_length : -c.half_length) + c.radius * d);
  }
  return out;
}
std::vector<V3> sample(const Cylinder<double>& c, Rng& rng, int n) {
  std::vector<V3> out;
  for (int i = 0; i < n; ++i) {
    const double a = rng.uniform(0, 2 * M_PI), rr = c.radius * std::sqrt(rng.uniform());
    out.push_back(V3(c.radius * std::cos(a), c.radius * std::sin(a), rng.uniform(-c.half_length, c.half_length)));
    out.push_back(V3(rr * std::cos(a), rr * std::sin(a), rng.uniform() < 0.5 ? -c.half_length : c.half_length));
  }
  return out;
}
std::vector<V3> sample(const Cone<double>& c, Rng& rng, int n) {
  std::vector<V3> out;
  out.push_back(V3(0, 0, c.half_length));
  for (int i = 0; i < n; ++i) {
    const double a = rng.uniform(0, 2 * M_PI), s = rng.uniform();  // s: 0 at the apex, 1 at the base
    const double z = c.half_length - 2 * c.half_length * s;
    out.push_back(V3(c.radius * s * std::cos(a), c.radius * s * std::sin(a), z));
    out.push_back(V3(c.radius * std::cos(a), c.radius * std::sin(a), -c.half_length));
  }
  return out;
}
std::vector<V3> sample(const Box<double>& b, Rng& rng, int n) {
  std::vector<V3> out;
  for (int i = 0; i < 8; ++i) out.push_back(V3((i & 1) ? b.half.x() : -b.half.x(), (i & 2) ? b.half.y() : -b.half.y(), (i & 4) ? b.half.z() : -b.half.z()));
  for (int i = 0; i < n; ++i) out.push_back(rng.in_box(-b.half, b.half));
  return out;
}
std::vector<V3> sample(const Sphere<double>& s, Rng& rng, int n) {
  std::vector<V3> out;
  for (int i = 0; i < n; ++i) {
    V3 d = rng.vec(-1, 1);
    if (d.norm() < 1e-3) continue;
    out.push_back(s.center + s.radius * d.normalized());
  }
  return out;
}

// Is x in the shape (within tol)? Written from the definitions, not from the support functions.
bool contains(const Capsule<double>& c, const V3& x, double tol) {
  const double z = std::clamp(x.z(), -c.half_length, c.half_length);
  return (x - V3(0, 0, z)).norm() <= c.radius + tol;
}
bool contains(const Cylinder<double>& c, const V3& x, double tol) {
  return std::hypot(x.x(), x.y()) <= c.radius + tol && std::abs(x.z()) <= c.half_length + tol;
}
bool contains(const Cone<double>& c, const V3& x, double tol) {
  if (std::abs(x.z()) > c.half_length + tol) return false;
  const double s = (c.half_length - x.z()) / (2 * c.half_length);  // radius fraction at this height
  return std::hypot(x.x(), x.y()) <= c.radius * std::clamp(s, 0.0, 1.0) + tol;
}
bool contains(const Box<double>& b, const V3& x, double tol) { return (x.cwiseAbs() - b.half).maxCoeff() <= tol; }
bool contains(const Sphere<double>& s, const V3& x, double tol) { return (x - s.center).norm() <= s.radius + tol; }

template <class Shape>
void check_support(const Shape& shape, std::uint64_t seed) {
  Rng rng(seed);
  const auto pts = sample(shape, rng, 4000);
  for (int k = 0; k < 300; ++k) {
    V3 d = rng.vec(-1, 1);
    if (k == 0) d = V3(0, 0, 1);
    if (k == 1) d = V3(0, 0, -1);
    if (k == 2) d = V3(1, 0, 0);
    const V3 s = impact::support(shape, d);
    ASSERT_TRUE(contains(shape, s, 1e-12)) << "support point outside the shape for d = " << d.transpose();
    double best = -1e300;
    for (const V3& p : pts) best = std::max(best, p.dot(d));
    EXPECT_GE(s.dot(d), best - 1e-12) << "a sampled point goes further than the support point, d = " << d.transpose();
    // not much further either (the sampling is fine): within 2 % of the shape's size
    EXPECT_LE(s.dot(d) - best, 0.02 * d.norm() * impact::shape_size(shape) + 1e-12);
  }
  // zero direction: some point of the shape
  EXPECT_TRUE(contains(shape, impact::support(shape, V3::Zero().eval()), 1e-12));
  // the world bounding box holds every sampled point and is touched on each side
  const impact::RigidTransform<double> pose{rng.rotation(), rng.vec(-3, 3)};
  const auto box = impact::bounding_box(shape, pose);
  V3 lo = V3::Constant(1e300), hi = V3::Constant(-1e300);
  for (const V3& p : pts) {
    const V3 w = pose.apply(p);
    EXPECT_TRUE((w.array() >= box.min.array() - 1e-12).all() && (w.array() <= box.max.array() + 1e-12).all());
    lo = lo.cwiseMin(w);
    hi = hi.cwiseMax(w);
  }
  EXPECT_LE((box.max - hi).maxCoeff(), 0.02 * impact::shape_size(shape));
  EXPECT_LE((lo - box.min).maxCoeff(), 0.02 * impact::shape_size(shape));
}

TEST(ConvexShapes, SupportAgainstSampledPoints) {
  check_support(Capsule<double>(0.3, 0.6), 1);
  check_support(Capsule<double>(0.5, 0.0), 2);
  check_support(Cylinder<double>(0.4, 0.5), 3);
  check_support(Cone<double>(0.5, 0.6), 4);
  check_support(Cone<double>(2.0, 0.1), 5);
  check_support(Box<double>(V3(0.4, 0.3, 0.5)), 6);
  check_support(Sphere<double>(V3(0.1, -0.2, 0.3), 0.7), 7);
}

TEST(ConvexShapes, ConeSupportPicksApexOrRim) {
  const Cone<double> c(1.0, 1.0);  // apex (0,0,1), rim at z = -1, radius 1; the side's slope is 2
  EXPECT_TRUE(impact::support(c, V3(0, 0, 1)).isApprox(V3(0, 0, 1)));
  EXPECT_TRUE(impact::support(c, V3(1, 0, 0)).isApprox(V3(1, 0, -1)));
  // d = (1, 0, 0.6): apex gives 0.6, rim gives 1 - 0.6 = 0.4 -> apex; d = (1, 0, 0.4): rim (0.6 > 0.4)
  EXPECT_TRUE(impact::support(c, V3(1, 0, 0.6)).isApprox(V3(0, 0, 1)));
  EXPECT_TRUE(impact::support(c, V3(1, 0, 0.4)).isApprox(V3(1, 0, -1)));
}

TEST(ConvexShapes, InvalidParametersThrow) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (double bad : {nan, inf, -inf, -1.0, 0.0}) {
    EXPECT_THROW(Capsule<double>(bad, 1.0), InvalidInput) << bad;
    EXPECT_THROW(Cylinder<double>(bad, 1.0), InvalidInput) << bad;
    EXPECT_THROW(Cylinder<double>(1.0, bad), InvalidInput) << bad;
    EXPECT_THROW(Cone<double>(bad, 1.0), InvalidInput) << bad;
    EXPECT_THROW(Cone<double>(1.0, bad), InvalidInput) << bad;
    for (int axis = 0; axis < 3; ++axis) {  // every axis: the validation's fast path must not pass a bad one
      V3 h(1, 1, 1);
      h[axis] = bad;
      EXPECT_THROW(Box<double>{h}, InvalidInput) << bad << " on axis " << axis;
    }
    EXPECT_THROW(impact::validate_shape(Sphere<double>(V3::Zero(), bad), "t"), InvalidInput) << bad;
  }
  for (double bad : {nan, inf, -1.0}) EXPECT_THROW(Capsule<double>(1.0, bad), InvalidInput) << bad;
  EXPECT_NO_THROW(Capsule<double>(1.0, 0.0));  // a capsule of zero length is a sphere
  EXPECT_THROW(Capsule<double>(1e300, 1.0), InvalidInput);  // beyond CoordinateRange
  EXPECT_THROW(Cylinder<float>(1e30f, 1.0f), InvalidInput);
  EXPECT_THROW(Box<double>(V3(1, 1e300, 1)), InvalidInput);  // beyond CoordinateRange
  EXPECT_THROW(Box<double>(V3(1, 1, 1e-14)), InvalidInput);  // numerically flat
  EXPECT_NO_THROW(Box<double>(V3(1, 1, 1e-12)));             // just above kMaxFlatness (2.3e-13)
  EXPECT_THROW(impact::validate_shape(Sphere<double>(V3(nan, 0, 0), 1.0), "t"), InvalidInput);
  try {
    Cone<double>(1.0, -2.0);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("cone.half_length"), std::string::npos) << e.what();
  }
}

TEST(ConvexShapes, FloatSupportMatchesDouble) {
  const Cylinder<float> cf(0.4f, 0.5f);
  const Cylinder<double> cd(0.4, 0.5);
  Rng rng(9);
  for (int k = 0; k < 100; ++k) {
    const V3 d = rng.vec(-1, 1);
    EXPECT_LE((impact::support(cf, Eigen::Vector3f(d.cast<float>())).cast<double>() - impact::support(cd, d)).norm(), 1e-6);
  }
}

}  // namespace
