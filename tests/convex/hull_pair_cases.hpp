// SPDX-License-Identifier: MIT
// What the tests of a solid of revolution (cylinder, cone) against a convex hull share
// (test_cylinder_hull_pair.cpp, test_cone_hull_pair.cpp): their hulls, the hull's vertices placed
// in the solid's frame in long double, the overlap along a direction of the placed vertices
// against a cylinder or a cone in long double, a hull scaled, and the size of the hull's support
// feature along a direction.
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/shapes.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"

#include <algorithm>
#include <cmath>
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

}  // namespace hull_pair_cases
