// SPDX-License-Identifier: MIT
// Exact oracle for triangle–triangle intersection (closed triangles, touching counts) on any finite
// float or double coordinates, independent of the library: the 18 coordinates of a pair are turned
// exactly into integers at a common power of two (arbitrary-precision cpp_int, Boost.Multiprecision,
// a test-only dependency), and a separating-axis test runs over a superset of the directions between
// closest features (face normals, edge x edge, vertex differences d, and e x (d x e) for every edge e:
// vertex–edge and parallel edge–edge closest pairs). Two disjoint compact convex sets are separated
// along the difference of their closest points, which is parallel to one of these, so the test is
// exact also for degenerate triangles (segments, points). Slow (microseconds a pair): for tests.
#pragma once

#include "impact/geometry/triangle.hpp"

#include "support/multiprecision.hpp"

#include <array>
#include <climits>
#include <cmath>
#include <cstdint>

namespace impact::test {

using BigInt = boost::multiprecision::cpp_int;
template <class N> using NVec = std::array<N, 3>;

template <class N> NVec<N> nsub(const NVec<N>& a, const NVec<N>& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
template <class N> NVec<N> ncross(const NVec<N>& a, const NVec<N>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
template <class N> N ndot(const NVec<N>& a, const NVec<N>& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// Exact: the closed hulls of p[0..3) and q[0..3) share a point (any exact integer type N).
template <class N> bool hulls_intersect_exact(const std::array<NVec<N>, 3>& p, const std::array<NVec<N>, 3>& q) {
  std::array<NVec<N>, 6> edges;
  for (int k = 0; k < 3; ++k) edges[k] = nsub(p[(k + 1) % 3], p[k]), edges[3 + k] = nsub(q[(k + 1) % 3], q[k]);
  auto separates = [&](const NVec<N>& axis) {
    if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0) return false;
    N pmin = ndot(p[0], axis), pmax = pmin, qmin = ndot(q[0], axis), qmax = qmin;
    for (int k = 1; k < 3; ++k) {
      const N x = ndot(p[k], axis), y = ndot(q[k], axis);
      if (x < pmin) pmin = x;
      if (x > pmax) pmax = x;
      if (y < qmin) qmin = y;
      if (y > qmax) qmax = y;
    }
    return pmax < qmin || qmax < pmin;
  };
  if (separates(ncross(edges[0], nsub(p[2], p[0])))) return false;
  if (separates(ncross(edges[3], nsub(q[2], q[0])))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 3; j < 6; ++j)
      if (separates(ncross(edges[i], edges[j]))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const NVec<N> d = nsub(q[j], p[i]);
      if (separates(d)) return false;
      for (const auto& e : edges)
        if (separates(ncross(e, ncross(d, e)))) return false;
    }
  return true;
}

/// Exact: the closed triangles ta and tb (float or double coordinates, finite) share a point.
template <class S> bool triangles_intersect_exact(const Triangle<S>& ta, const Triangle<S>& tb) {
  const Vec3<S>* v[6] = {&ta.a, &ta.b, &ta.c, &tb.a, &tb.b, &tb.c};
  // x = m 2^e with m an integer of at most 53 bits; all coordinates scaled by 2^-emin are integers.
  std::int64_t mant[18];
  int expo[18];
  int emin = INT_MAX;
  for (int k = 0; k < 18; ++k) {
    const double x = static_cast<double>((*v[k / 3])[k % 3]);
    int e = 0;
    const double f = std::frexp(x, &e);  // x = f 2^e, 0.5 <= |f| < 1
    mant[k] = static_cast<std::int64_t>(std::ldexp(f, 53));
    expo[k] = e - 53;
    if (mant[k] != 0 && expo[k] < emin) emin = expo[k];
  }
  std::array<NVec<BigInt>, 3> p, q;
  for (int k = 0; k < 18; ++k) {
    BigInt n = mant[k];
    if (mant[k] != 0) n *= BigInt(1) << static_cast<unsigned>(expo[k] - emin);
    (k < 9 ? p[k / 3] : q[k / 3 - 3])[k % 3] = n;
  }
  return hulls_intersect_exact(p, q);
}

}  // namespace impact::test
