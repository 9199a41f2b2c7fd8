// SPDX-License-Identifier: MIT
/// \file
/// Plane n . x = d with unit normal n; the half-space "inside" is n . x < d.
#pragma once

#include "impact/core/types.hpp"

namespace impact {

template <class S> struct Plane {
  Vec3<S> normal = Vec3<S>::UnitZ();  ///< unit length
  S offset = S(0);                    ///< n . x on the plane

  Plane() = default;
  Plane(const Vec3<S>& unit_normal, S d) : normal(unit_normal), offset(d) {}
  static Plane through(const Vec3<S>& point, const Vec3<S>& n) {
    const Vec3<S> u = n.normalized();
    return {u, u.dot(point)};
  }
  /// Signed distance (positive on the side the normal points to).
  S signed_distance(const Vec3<S>& p) const { return normal.dot(p) - offset; }
  Vec3<S> project(const Vec3<S>& p) const { return p - signed_distance(p) * normal; }
};

}  // namespace impact
