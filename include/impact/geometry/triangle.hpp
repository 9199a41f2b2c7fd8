// SPDX-License-Identifier: MIT
/// \file
/// Triangle: three vertices, with the derived quantities the narrow phase and builders need.
#pragma once

#include "impact/core/types.hpp"

namespace impact {

template <class S> struct Triangle {
  Vec3<S> a, b, c;

  Triangle() = default;
  Triangle(const Vec3<S>& a_, const Vec3<S>& b_, const Vec3<S>& c_) : a(a_), b(b_), c(c_) {}

  const Vec3<S>& operator[](int i) const { return i == 0 ? a : (i == 1 ? b : c); }
  Vec3<S>& operator[](int i) { return i == 0 ? a : (i == 1 ? b : c); }
  Vec3<S> centroid() const { return (a + b + c) / S(3); }
  /// (b - a) x (c - a): twice the area times the unit normal; zero for degenerate triangles.
  Vec3<S> scaled_normal() const { return (b - a).cross(c - a); }
  /// Unit normal, or zero for a degenerate (zero-area) triangle.
  Vec3<S> normal() const {
    const Vec3<S> n = scaled_normal();
    const S len = n.norm();
    return len > S(0) ? Vec3<S>(n / len) : Vec3<S>::Zero();
  }
  S area() const { return scaled_normal().norm() / S(2); }
  template <class T> Triangle<T> cast() const { return {a.template cast<T>(), b.template cast<T>(), c.template cast<T>()}; }
};

}  // namespace impact
