// SPDX-License-Identifier: MIT
// What the tests of a solid of revolution (cylinder, cone) against a convex hull share
// (test_cylinder_hull_pair.cpp, test_cone_hull_pair.cpp): their hulls, the hull's vertices placed
// in the solid's frame in long double, the overlap along a direction of the placed vertices
// against a cylinder or a cone in long double, a hull scaled, the size of the hull's support
// feature along a direction, the poses of the cases, and the depth oracle.
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/shapes.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace hull_pair_cases {

using LD = long double;
using V3L = Eigen::Matrix<LD, 3, 1>;

// The hulls: the zoo's (40 points of an ellipsoid, climbed), 8 random points (fewer than
// kHullClimbMinVertices: scanned), a slab of 24 points (its big faces merged polygons).
inline const std::vector<impact::ConvexHull<double>>& hulls() {
  static const std::vector<impact::ConvexHull<double>> h = [] {
    std::vector<impact::ConvexHull<double>> out;
    out.push_back(impact::test::zoo().hull);
    impact::test::Rng rng(640);
    impact::Vertices<double> p(8, 3);
    for (int i = 0; i < 8; ++i) p.row(i) = Eigen::Vector3d(rng.vec(-0.5, 0.5)).transpose();
    out.push_back(impact::convex_hull(p));
    impact::Vertices<double> q(24, 3);
    for (int i = 0; i < 24; ++i) {
      const Eigen::Vector3d v(rng.uniform(-0.6, 0.6), rng.uniform(-0.4, 0.4), i % 2 ? 0.15 : -0.15);
      q.row(i) = v.transpose();
    }
    out.push_back(impact::convex_hull(q));
    return out;
  }();
  return h;
}

// The hull's vertices placed by R, t in a's frame, long double.
inline std::vector<V3L> placed(const impact::ConvexHull<double>& b, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  std::vector<V3L> out;
  for (Eigen::Index i = 0; i < b.vertices.rows(); ++i) {
    const Eigen::Vector3d v = b.vertices.row(i).transpose();
    out.push_back(R.cast<LD>() * v.cast<LD>() + t.cast<LD>());
  }
  return out;
}

// The hull's part of the overlap along n: max_v (-n . v) over the placed vertices.
inline LD hull_part(const std::vector<V3L>& v, const V3L& n) {
  LD hull = -std::numeric_limits<LD>::infinity();
  for (const V3L& x : v) hull = std::max(hull, -n.dot(x));
  return hull;
}

// The overlap along unit n of cylinder a (its frame) and the hull's placed vertices, long double.
inline LD overlap_ld(const impact::Cylinder<double>& a, const std::vector<V3L>& v, const V3L& n) {
  return LD(a.half_length) * std::abs(n.z()) + LD(a.radius) * std::sqrt(n.x() * n.x() + n.y() * n.y()) + hull_part(v, n);
}

// The overlap along unit n of cone a (its frame) and the hull's placed vertices, long double.
inline LD overlap_ld(const impact::Cone<double>& a, const std::vector<V3L>& v, const V3L& n) {
  const LD h = a.half_length, rim = LD(a.radius) * std::sqrt(n.x() * n.x() + n.y() * n.y()) - h * n.z();
  return std::max(h * n.z(), rim) + hull_part(v, n);
}

// A hull scaled by s (vertices and planes).
inline impact::ConvexHull<double> scaled(const impact::ConvexHull<double>& h, double s) {
  impact::Vertices<double> p = h.vertices * s;
  return impact::convex_hull(p);
}

// The number of the hull's placed vertices within 1e-9 of the size of its support plane along -n:
// 1 for a vertex, 2 for an edge.
inline int support_count(const std::vector<V3L>& v, const Eigen::Vector3d& n, double size) {
  const LD top = hull_part(v, n.cast<LD>());
  int count = 0;
  for (const V3L& x : v) count += -n.cast<LD>().dot(x) >= top - LD(1e-9 * size);
  return count;
}

// A solid of revolution (a cylinder or a cone, in its own frame at pa) against hulls()[hull] at pb.
template <class Solid>
struct SolidHullCase {
  Solid solid;
  int hull = 0;
  impact::RigidTransform<double> pa, pb;
};

// n cases: solids of varied proportions (every fourth `first`) against the hulls in turn, b about
// a, `scale` times the size and `offset` from the origin.
template <class Solid>
std::vector<SolidHullCase<Solid>> solid_hull_cases(const Solid& first, int n, std::uint64_t seed, double scale, double offset) {
  impact::test::Rng rng(seed);
  std::vector<SolidHullCase<Solid>> out;
  for (int k = 0; k < n; ++k) {
    SolidHullCase<Solid> c{first, 0, {}, {}};
    if (k % 4 != 0) c.solid = Solid(rng.uniform(0.1, 1.0), rng.uniform(0.1, 1.0));
    c.hull = k % 3;
    const double reach = 0.6 * (impact::shape_size(c.solid) + impact::shape_size(hulls()[static_cast<std::size_t>(c.hull)]));
    c.pa = {rng.rotation(), Eigen::Vector3d(rng.vec(-1, 1) + Eigen::Vector3d::Constant(offset / scale))};
    c.pb = {rng.rotation(), Eigen::Vector3d(c.pa.t + rng.vec(-reach, reach))};
    c.solid = Solid(c.solid.radius * scale, c.solid.half_length * scale);
    c.pa.t *= scale;
    c.pb.t *= scale;
    out.push_back(c);
  }
  return out;
}

// The least overlap of solid a (its frame) and hull b placed by R, t (long double), minimised by
// test::least_overlap from +z, -z and `extra` (the normal under test) with the kink circle of the
// solid's side normals (n_z = side_z), then again from that minimiser and `extra` with the circles
// of the hull's edges whose ends both lie within 0.02 of the size of the support plane along -n
// (an edge against the rim: a valley along its arc). Its minimum is an upper bound of the depth.
template <class Solid>
impact::test::LeastOverlap solid_hull_depth_oracle(const Solid& a, const impact::ConvexHull<double>& b, const Eigen::Matrix3d& R,
                                                   const Eigen::Vector3d& t, const Eigen::Vector3d& extra, double side_z) {
  const std::vector<V3L> v = placed(b, R, t);
  const auto f = [&](const V3L& n) { return overlap_ld(a, v, n); };
  const std::vector<Eigen::Vector3d> starts = {Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ(), extra};
  std::vector<impact::test::KinkCircle> circles = {{Eigen::Vector3d::UnitZ(), side_z}};
  impact::test::LeastOverlap best = impact::test::least_overlap(f, starts, circles, IMPACT_TEST_SANITIZED ? 200 : 400);
  const V3L d = -best.normal;
  const LD top = hull_part(v, best.normal);
  circles.clear();
  const LD near = LD(0.02) * LD(std::max(impact::shape_size(a), impact::shape_size(b)));
  for (const impact::HullEdge& e : b.edges) {
    const std::size_t i0 = static_cast<std::size_t>(e.v0), i1 = static_cast<std::size_t>(e.v1);
    if (d.dot(v[i0]) >= top - near && d.dot(v[i1]) >= top - near) circles.push_back({(v[i1] - v[i0]).cast<double>(), 0});
  }
  if (circles.empty()) return best;
  const std::vector<Eigen::Vector3d> again = {best.normal.cast<double>(), extra};
  const impact::test::LeastOverlap second = impact::test::least_overlap(f, again, circles, 50);
  return second.depth < best.depth ? second : best;
}

}  // namespace hull_pair_cases
