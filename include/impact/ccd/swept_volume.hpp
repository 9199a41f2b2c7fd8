// SPDX-License-Identifier: MIT
/// \file
/// Swept bounding volumes of a linearly moving primitive (vertex, edge or triangle) over one time
/// step, inflated by a minimum separation: the broad-phase culling volumes of continuous collision
/// detection. Under linear motion every point of the primitive at any t in [0, 1] is a convex
/// combination of its vertices' start and end positions, so a volume around those 2n points
/// holds the whole swept primitive. Both functions round outwards, so they are conservative
/// (the box by one step to the neighbouring value, next_down / next_up on the bit pattern: a
/// tree's build fits every node from its triangles' boxes, where libm's nextafter was six calls
/// per box).
#pragma once

#include "impact/core/next_float.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/aabb.hpp"
#include "impact/geometry/sphere.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

namespace impact {

/// The axis-aligned box around the n points at t = 0 (`start`) and t = 1 (`end`), grown by
/// `inflate` >= 0 (the minimum separation) and rounded outwards. Any point of the swept primitive
/// within `inflate` of it lies inside. O(n).
template <class S>
Aabb<S> swept_aabb(const Vec3<S>* start, const Vec3<S>* end, std::size_t n, S inflate = S(0)) {
  Aabb<S> box;
  for (std::size_t k = 0; k < n; ++k) {
    box.extend(start[k]);
    box.extend(end[k]);
  }
  if (inflate > S(0)) {
    for (int i = 0; i < 3; ++i) {
      box.min[i] = next_down(box.min[i] - inflate);
      box.max[i] = next_up(box.max[i] + inflate);
    }
  }
  return box;
}

/// A sphere around the n points at t = 0 and t = 1, grown by `inflate` >= 0: centred at the middle
/// of their box, with the largest distance to a point as radius, padded for rounding. Not the
/// smallest sphere, but cheap and conservative. O(n).
template <class S>
Sphere<S> swept_sphere(const Vec3<S>* start, const Vec3<S>* end, std::size_t n, S inflate = S(0)) {
  const Aabb<S> box = swept_aabb(start, end, n, S(0));
  const Vec3<S> c = box.center();
  S r2 = S(0);
  for (std::size_t k = 0; k < n; ++k) {
    r2 = std::max(r2, (start[k] - c).squaredNorm());
    r2 = std::max(r2, (end[k] - c).squaredNorm());
  }
  // Relative padding covers the rounding of the squared distances and the square root.
  const S eps = std::numeric_limits<S>::epsilon();
  return {c, std::sqrt(r2) * (S(1) + S(16) * eps) + inflate * (S(1) + S(4) * eps) + std::numeric_limits<S>::denorm_min()};
}

/// Swept box of a moving vertex (p0 at t = 0, p1 at t = 1).
template <class S>
Aabb<S> swept_aabb(const Vec3<S>& p0, const Vec3<S>& p1, S inflate = S(0)) {
  return swept_aabb(&p0, &p1, 1, inflate);
}

/// Swept box of a moving edge or triangle given by its N vertices at t = 0 and t = 1.
template <class S, std::size_t N>
Aabb<S> swept_aabb(const Vec3<S> (&start)[N], const Vec3<S> (&end)[N], S inflate = S(0)) {
  return swept_aabb(start, end, N, inflate);
}

/// Swept sphere of a moving edge or triangle given by its N vertices at t = 0 and t = 1.
template <class S, std::size_t N>
Sphere<S> swept_sphere(const Vec3<S> (&start)[N], const Vec3<S> (&end)[N], S inflate = S(0)) {
  return swept_sphere(start, end, N, inflate);
}

}  // namespace impact
