// SPDX-License-Identifier: MIT
/// \file
/// TriangleShape: a triangle as a convex shape of the convex layer (a flat, closed set: the convex
/// hull of its three vertices), with its support function, an interior point, its size and its
/// validation, so that every query of convex/query.hpp takes it like any other shape
/// (convex_intersect(TriangleShape, pose, Box, pose_b) ...) and the mesh queries of
/// convex/mesh_convex.hpp test one triangle of a mesh at a time. Degenerate triangles (collinear
/// or coincident vertices) are the segment or point they are: the support function needs no area.
///
/// A triangle has no inside: its "penetration" with a solid shape is the convex one (the least
/// translation of the solid that separates it from the flat set, see mesh_convex.hpp), and two
/// triangles, both flat, have no penetration depth worth the name (EPA is not meant for that pair).
///
/// Thread safety: a plain value; every function is pure.
#pragma once

#include "impact/convex/shapes.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <cmath>

namespace impact {

/// The closed triangle (a, b, c) in its own frame (a RigidTransform places it like any shape).
template <class S>
struct TriangleShape {
  Triangle<S> triangle;
  TriangleShape() = default;
  explicit TriangleShape(const Triangle<S>& t) : triangle(t) {}
  TriangleShape(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c) : triangle(a, b, c) {}
};

/// Throws InvalidInput unless the three vertices are finite and within CoordinateRange.
template <class S>
void validate_shape(const TriangleShape<S>& s, const char* where) {
  validate_coordinates(s.triangle.a, where, "triangle.a");
  validate_coordinates(s.triangle.b, where, "triangle.b");
  validate_coordinates(s.triangle.c, where, "triangle.c");
}

/// The vertex maximising the dot product with d (the first of equal ones, in the order a, b, c).
template <class S>
inline Vec3<S> support(const TriangleShape<S>& s, const Vec3<S>& d) {
  const S da = d.dot(s.triangle.a), db = d.dot(s.triangle.b), dc = d.dot(s.triangle.c);
  if (da >= db && da >= dc) return s.triangle.a;
  return db >= dc ? s.triangle.b : s.triangle.c;
}

/// The centroid: in the relative interior of the triangle (of the segment or at the point of a
/// degenerate one), which is what GJK and MPR need of a flat set (the Minkowski difference with
/// a solid shape is solid, and the centroid minus the solid's interior point is inside it).
template <class S>
inline Vec3<S> interior_point(const TriangleShape<S>& s) {
  return s.triangle.centroid();
}

/// The largest distance from the centroid to a vertex (0 for three coincident vertices: the
/// queries take the larger of the two shapes' sizes as their scale).
template <class S>
inline S shape_size(const TriangleShape<S>& s) {
  const Vec3<S> g = s.triangle.centroid();
  return std::sqrt(std::max({(s.triangle.a - g).squaredNorm(), (s.triangle.b - g).squaredNorm(), (s.triangle.c - g).squaredNorm()}));
}

}  // namespace impact
