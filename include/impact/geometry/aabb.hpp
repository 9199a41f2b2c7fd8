// SPDX-License-Identifier: MIT
/// \file
/// Aabb: axis-aligned box [min, max]. A bounding volume beside the sphere, and the extent used by
/// the top-down builder to choose the split axis.
#pragma once

#include "impact/core/types.hpp"

namespace impact {

template <class S> struct Aabb {
  Vec3<S> min = Vec3<S>::Constant(std::numeric_limits<S>::infinity());
  Vec3<S> max = Vec3<S>::Constant(-std::numeric_limits<S>::infinity());

  Aabb() = default;
  Aabb(const Vec3<S>& lo, const Vec3<S>& hi) : min(lo), max(hi) {}

  bool empty() const { return (min.array() > max.array()).any(); }
  void extend(const Vec3<S>& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  Vec3<S> center() const { return (min + max) / S(2); }
  Vec3<S> extent() const { return max - min; }
  /// Half the diagonal: the radius of the sphere through the corners.
  S half_diagonal() const { return (max - min).norm() / S(2); }
  /// Index (0, 1, 2) of the longest side.
  int longest_axis() const {
    const Vec3<S> e = extent();
    return e[0] >= e[1] ? (e[0] >= e[2] ? 0 : 2) : (e[1] >= e[2] ? 1 : 2);
  }
  bool contains(const Vec3<S>& p) const { return (p.array() >= min.array()).all() && (p.array() <= max.array()).all(); }
  template <class T> Aabb<T> cast() const { return {min.template cast<T>(), max.template cast<T>()}; }
};

/// True when the two closed boxes share a point.
template <class S> inline bool overlap(const Aabb<S>& a, const Aabb<S>& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

template <class S> inline Aabb<S> merge(Aabb<S> a, const Aabb<S>& b) {
  a.extend(b);
  return a;
}

}  // namespace impact
