// SPDX-License-Identifier: MIT
/// \file
/// Sphere: centre and radius. The primary bounding volume of the library. A sphere under a rigid
/// transform only has its centre moved, which makes the relative-pose pair traversal cheap.
#pragma once

#include "impact/core/types.hpp"

#include <algorithm>
#include <limits>

namespace impact {

template <class S> struct Sphere {
  Vec3<S> center = Vec3<S>::Zero();
  S radius = S(-1);  ///< negative means empty

  Sphere() = default;
  Sphere(const Vec3<S>& c, S r) : center(c), radius(r) {}

  bool empty() const { return radius < S(0); }
  bool contains(const Vec3<S>& p, S slack = S(0)) const { return (p - center).norm() <= radius + slack; }
  template <class T> Sphere<T> cast() const { return {center.template cast<T>(), T(radius)}; }
};

/// True when the two (closed) spheres share a point.
template <class S> inline bool overlap(const Sphere<S>& a, const Sphere<S>& b) {
  const S r = a.radius + b.radius;
  return (a.center - b.center).squaredNorm() <= r * r;
}

/// The smallest sphere containing both spheres, padded for rounding so that both stay inside:
/// the centre is rounded at the scale of its coordinates (which can be far above the radii), so
/// the radius is measured again from the rounded centre to each input sphere, and each comparison
/// and distance is taken with a relative margin for its own rounding (a difference of two floats
/// is rounded relative to itself, a norm of three components within a few ulps).
template <class S> inline Sphere<S> merge(const Sphere<S>& a, const Sphere<S>& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  constexpr S grow = S(1) + S(8) * std::numeric_limits<S>::epsilon();
  const Vec3<S> d = b.center - a.center;
  const S dist = d.norm();
  if (dist == S(0)) return a.radius >= b.radius ? a : b;  // same centre, exactly
  if ((dist + b.radius) * grow <= a.radius) return a;
  if ((dist + a.radius) * grow <= b.radius) return b;
  const S r = (dist + a.radius + b.radius) / S(2);
  // centre moves from a.center towards b.center by (r - a.radius)
  const Vec3<S> c = a.center + d * ((r - a.radius) / dist);
  const S ra = (c - a.center).norm() + a.radius, rb = (c - b.center).norm() + b.radius;
  return {c, std::max(ra, rb) * grow + std::numeric_limits<S>::denorm_min()};
}

}  // namespace impact
