// SPDX-License-Identifier: MIT
/// \file
/// The convex primitives of the convex layer (capsule, cylinder, cone, box; spheres are the
/// geometry layer's Sphere, convex hulls are in convex/convex_hull.hpp), each in its own frame
/// (a RigidTransform places it), with its support function, its size and its world bounding box.
///
/// Conventions (the same as FCL's, so that an impact shape and an FCL shape of the same numbers
/// are the same set; FCL takes full lengths where impact takes halves):
///   Sphere{c, r}          the closed ball of radius r about c
///   Capsule{r, h}         the points within r of the segment from (0,0,-h) to (0,0,h)
///   Cylinder{r, h}        the solid cylinder of radius r about the z axis for z in [-h, h]
///   Cone{r, h}            base disc of radius r at z = -h, apex at (0,0,h)
///   Box{half}             [-half.x, half.x] x [-half.y, half.y] x [-half.z, half.z]
///
/// Validity: the constructors throw impact::InvalidInput unless every radius and half extent is
/// finite, > 0 (a capsule's half length may be 0: a sphere) and at most CoordinateRange<S>::max.
/// Zero radii or heights are rejected rather than treated as segments or discs: a flat shape makes
/// the penetration depth of two flat shapes undefined and the expanding polytope of EPA degenerate.
/// For the same reason a cylinder, cone or box must not be numerically flat: its least extent (the
/// smaller of radius and half length, the least half extent) must be at least kMaxFlatness<S> =
/// 1024 machine epsilons of its largest (an aspect ratio of at most 4.4e12 in double, 8,192 in
/// float). Thinner ones are rejected: EPA's polytope of such a shape is flat to within rounding, and
/// its depths were off by up to the whole size (fuzzing found them; swept over random poses, every
/// bracket closes at 4.4e12 in double and 16,384 in float, and stays open on a quarter to all of
/// the poses from 1e14 in double). A capsule has no such bound: its queries work on its segment
/// and treat the radius as a margin. Convex hulls have their own flatness test (convex_hull()).
/// The members are public for reading; a shape whose members are changed after construction must
/// be re-validated with validate_shape().
///
/// Thread safety: shapes are plain values and every function here is const or free, so a shape
/// may be read from any number of threads at once; changing its members is not concurrent with
/// anything else on it.
#pragma once

#include "impact/core/validate.hpp"
#include "impact/geometry/aabb.hpp"
#include "impact/geometry/sphere.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace impact {

/// Points within `radius` of the segment (0,0,-half_length)–(0,0,half_length).
template <class S>
struct Capsule {
  S radius = S(1);
  S half_length = S(0);
  Capsule(S r, S h) : radius(r), half_length(h) { validate_shape(*this, "Capsule"); }
};

/// The solid cylinder of radius `radius` about the z axis, z in [-half_length, half_length].
template <class S>
struct Cylinder {
  S radius = S(1);
  S half_length = S(1);
  Cylinder(S r, S h) : radius(r), half_length(h) { validate_shape(*this, "Cylinder"); }
};

/// The solid cone with its base disc of radius `radius` at z = -half_length and its apex at
/// (0, 0, half_length).
template <class S>
struct Cone {
  S radius = S(1);
  S half_length = S(1);
  Cone(S r, S h) : radius(r), half_length(h) { validate_shape(*this, "Cone"); }
};

/// The box centred on the origin with half extents `half` along the frame's axes.
template <class S>
struct Box {
  Vec3<S> half = Vec3<S>::Ones();
  explicit Box(const Vec3<S>& h) : half(h) { validate_shape(*this, "Box"); }
};

/// Throws InvalidInput unless the sphere's centre is finite and in range and its radius finite,
/// > 0 and in range.
template <class S>
void validate_shape(const Sphere<S>& s, const char* where) {
  constexpr S range = CoordinateRange<S>::max;  // the common case first (comparisons are false for NaN)
  if (IMPACT_LIKELY(std::abs(s.center.x()) <= range && std::abs(s.center.y()) <= range && std::abs(s.center.z()) <= range &&
                    s.radius > S(0) && s.radius <= range))
    return;
  validate_coordinates(s.center, where, "sphere.center");
  validate_length(s.radius, where, "sphere.radius");
  validate_positive(s.radius, where, "sphere.radius");
}

/// The least extent of a cylinder, cone or box, relative to its largest, below which it is
/// numerically flat (see the file comment): 1024 machine epsilons.
template <class S>
inline constexpr S kMaxFlatness = S(1024) * std::numeric_limits<S>::epsilon();

namespace detail {
/// Throws InvalidInput when `least` < kMaxFlatness<S> * `largest` (both finite and > 0).
template <class S>
void validate_not_flat(S least, S largest, const char* where, const char* shape) {
  if (IMPACT_LIKELY(least >= kMaxFlatness<S> * largest)) return;
  std::ostringstream s;
  s.precision(17);
  s << where << ": " << shape << " is numerically flat: its least extent " << least << " is below " << kMaxFlatness<S>
    << " (1024 machine epsilons) of its largest " << largest << " (an aspect ratio of at most " << S(1) / kMaxFlatness<S> << ")";
  throw InvalidInput(s.str());
}

/// The radius and half length of a capsule, cylinder or cone, named radius_name and length_name in
/// the messages: both finite and in range, the radius > 0, the half length > 0 too unless
/// `zero_length_ok`; unless `zero_length_ok` (a capsule), not numerically flat either.
template <class S>
void validate_radius_and_half_length(S radius, S half_length, bool zero_length_ok, const char* where, const char* radius_name,
                                     const char* length_name) {
  constexpr S range = CoordinateRange<S>::max;  // the common case first (comparisons are false for NaN)
  if (IMPACT_LIKELY(radius > S(0) && radius <= range && (zero_length_ok ? half_length >= S(0) : half_length > S(0)) && half_length <= range &&
                    (zero_length_ok || std::min(radius, half_length) >= kMaxFlatness<S> * std::max(radius, half_length))))
    return;
  validate_length(radius, where, radius_name);
  validate_positive(radius, where, radius_name);
  validate_length(half_length, where, length_name);
  if (!zero_length_ok) {
    validate_positive(half_length, where, length_name);
    validate_not_flat(std::min(radius, half_length), std::max(radius, half_length), where,
                      std::string(radius_name).substr(0, std::string(radius_name).find('.')).c_str());
  }
}
}  // namespace detail

template <class S>
void validate_shape(const Capsule<S>& s, const char* where) {
  detail::validate_radius_and_half_length(s.radius, s.half_length, true, where, "capsule.radius", "capsule.half_length");
}
template <class S>
void validate_shape(const Cylinder<S>& s, const char* where) {
  detail::validate_radius_and_half_length(s.radius, s.half_length, false, where, "cylinder.radius", "cylinder.half_length");
}
template <class S>
void validate_shape(const Cone<S>& s, const char* where) {
  detail::validate_radius_and_half_length(s.radius, s.half_length, false, where, "cone.radius", "cone.half_length");
}
template <class S>
void validate_shape(const Box<S>& s, const char* where) {
  constexpr S range = CoordinateRange<S>::max;  // the common case first (comparisons are false for NaN)
  const S x = s.half.x(), y = s.half.y(), z = s.half.z();
  if (IMPACT_LIKELY(x > S(0) && y > S(0) && z > S(0) && x <= range && y <= range && z <= range &&
                    std::min({x, y, z}) >= kMaxFlatness<S> * std::max({x, y, z})))
    return;
  validate_coordinates(s.half, where, "box.half");
  if (!(s.half.minCoeff() > S(0))) throw InvalidInput(std::string(where) + ": box.half must be > 0 on every axis");
  detail::validate_not_flat(s.half.minCoeff(), s.half.maxCoeff(), where, "box");
}

namespace detail {
/// The support point in direction d of the circle of radius `radius` about the z axis at height z:
/// radius d_xy / |d_xy| (`d_xy_norm` = |d_xy|), or (radius, 0) when d is parallel to the axis.
template <class S>
inline Vec3<S> rim_support(S radius, S z, const Vec3<S>& d, S d_xy_norm) {
  if (d_xy_norm > S(0)) return {d.x() * (radius / d_xy_norm), d.y() * (radius / d_xy_norm), z};
  return {radius, S(0), z};
}
}  // namespace detail

/// Support point: a point of the shape (in its own frame) maximising the dot product with `d`.
/// `d` need not be unit; for d = 0 some point of the shape is returned.
template <class S>
inline Vec3<S> support(const Sphere<S>& s, const Vec3<S>& d) {
  const S n = d.norm();
  return n > S(0) ? Vec3<S>(s.center + d * (s.radius / n)) : Vec3<S>(s.center + Vec3<S>(S(0), S(0), s.radius));
}
template <class S>
inline Vec3<S> support(const Capsule<S>& s, const Vec3<S>& d) {
  const S n = d.norm();
  Vec3<S> p = n > S(0) ? Vec3<S>(d * (s.radius / n)) : Vec3<S>(S(0), S(0), s.radius);
  p.z() += d.z() >= S(0) ? s.half_length : -s.half_length;
  return p;
}
template <class S>
inline Vec3<S> support(const Cylinder<S>& s, const Vec3<S>& d) {
  const S r = std::sqrt(d.x() * d.x() + d.y() * d.y());
  return detail::rim_support(s.radius, d.z() >= S(0) ? s.half_length : -s.half_length, d, r);
}
template <class S>
inline Vec3<S> support(const Cone<S>& s, const Vec3<S>& d) {
  const S r = std::sqrt(d.x() * d.x() + d.y() * d.y());
  // The apex (0,0,h) against the best point of the base rim, (r d_xy/|d_xy|, -h).
  const S apex = s.half_length * d.z();
  const S rim = s.radius * r - s.half_length * d.z();
  if (apex >= rim) return {S(0), S(0), s.half_length};
  return detail::rim_support(s.radius, -s.half_length, d, r);
}
template <class S>
inline Vec3<S> support(const Box<S>& s, const Vec3<S>& d) {
  return {d.x() >= S(0) ? s.half.x() : -s.half.x(), d.y() >= S(0) ? s.half.y() : -s.half.y(),
          d.z() >= S(0) ? s.half.z() : -s.half.z()};
}

/// A point inside the shape (its own frame): the centre used to start GJK and MPR.
template <class S>
inline Vec3<S> interior_point(const Sphere<S>& s) {
  return s.center;
}
template <class S>
inline Vec3<S> interior_point(const Capsule<S>&) {
  return Vec3<S>::Zero();
}
template <class S>
inline Vec3<S> interior_point(const Cylinder<S>&) {
  return Vec3<S>::Zero();
}
template <class S>
inline Vec3<S> interior_point(const Cone<S>& s) {
  return Vec3<S>(S(0), S(0), -s.half_length / S(2));  // the centroid of the solid cone
}
template <class S>
inline Vec3<S> interior_point(const Box<S>&) {
  return Vec3<S>::Zero();
}

/// The radius of a ball about interior_point() holding the shape: the length scale of the shape
/// that relative tolerances are taken of.
template <class S>
inline S shape_size(const Sphere<S>& s) {
  return s.radius;
}
template <class S>
inline S shape_size(const Capsule<S>& s) {
  return s.radius + s.half_length;
}
template <class S>
inline S shape_size(const Cylinder<S>& s) {
  return std::sqrt(s.radius * s.radius + s.half_length * s.half_length);
}
template <class S>
inline S shape_size(const Cone<S>& s) {
  const S h = s.half_length * S(1.5);  // apex to the centroid
  return std::max(h, std::sqrt(s.radius * s.radius + s.half_length * s.half_length / S(4)));
}
template <class S>
inline S shape_size(const Box<S>& s) {
  return s.half.norm();
}

/// The world support point of `shape` placed by `pose`, for a world direction d.
template <class Shape, class S>
inline Vec3<S> support(const Shape& shape, const RigidTransform<S>& pose, const Vec3<S>& d) {
  return pose.apply(support(shape, Vec3<S>(pose.R.transpose() * d)));
}

/// The tight world axis-aligned bounding box of `shape` placed by `pose` (six support queries).
template <class Shape, class S>
inline Aabb<S> bounding_box(const Shape& shape, const RigidTransform<S>& pose) {
  Aabb<S> box;
  for (int i = 0; i < 3; ++i) {
    const Vec3<S> axis = pose.R.row(i).transpose();  // R^T e_i
    box.max[i] = pose.t[i] + axis.dot(support(shape, axis));
    box.min[i] = pose.t[i] + axis.dot(support(shape, Vec3<S>(-axis)));
  }
  return box;
}

}  // namespace impact
