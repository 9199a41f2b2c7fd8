// SPDX-License-Identifier: MIT
// Exact integer oracles for the narrow-phase tests: determinants in __int128 and an exact
// separating-axis test for two closed (possibly degenerate) triangles with integer vertices.
#pragma once

#include <array>
#include <cstdint>

namespace impact::test {

__extension__ typedef __int128 I128;
using IPoint = std::array<std::int64_t, 3>;
using IVec = std::array<I128, 3>;

inline int sign128(I128 x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); }
inline IVec isub(const IVec& a, const IVec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline IVec icross(const IVec& a, const IVec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline I128 idot(const IVec& a, const IVec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline IVec to_ivec(const IPoint& p) { return {p[0], p[1], p[2]}; }

/// Exact sign of (d - a) . ((b - a) x (c - a)); coordinates up to about 2^40 in magnitude.
inline int orient3d_int(const IPoint& a, const IPoint& b, const IPoint& c, const IPoint& d) {
  const IVec A = to_ivec(a);
  return sign128(idot(isub(to_ivec(d), A), icross(isub(to_ivec(b), A), isub(to_ivec(c), A))));
}

/// Exact sign of (b - a) x (c - a); coordinates up to about 2^52 in magnitude.
inline int orient2d_int(std::int64_t ax, std::int64_t ay, std::int64_t bx, std::int64_t by, std::int64_t cx, std::int64_t cy) {
  return sign128(I128(bx - ax) * I128(cy - ay) - I128(by - ay) * I128(cx - ax));
}

/// Exact: the closed hulls of P and Q (three points each, possibly degenerate) intersect. Separating
/// axis test over a superset of the directions between closest features: face normals, edge x edge,
/// vertex differences d, and e x (d x e) for every edge e (vertex–edge and parallel edge–edge
/// closest pairs). Coordinates up to about 2^20 in magnitude.
inline bool triangles_intersect_int(const std::array<IPoint, 3>& P, const std::array<IPoint, 3>& Q) {
  IVec p[3], q[3];
  for (int k = 0; k < 3; ++k) p[k] = to_ivec(P[k]), q[k] = to_ivec(Q[k]);
  IVec edges[6];
  for (int k = 0; k < 3; ++k) edges[k] = isub(p[(k + 1) % 3], p[k]), edges[3 + k] = isub(q[(k + 1) % 3], q[k]);
  auto separates = [&](const IVec& axis) {
    if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0) return false;
    I128 pmin = idot(p[0], axis), pmax = pmin, qmin = idot(q[0], axis), qmax = qmin;
    for (int k = 1; k < 3; ++k) {
      const I128 x = idot(p[k], axis), y = idot(q[k], axis);
      if (x < pmin) pmin = x;
      if (x > pmax) pmax = x;
      if (y < qmin) qmin = y;
      if (y > qmax) qmax = y;
    }
    return pmax < qmin || qmax < pmin;
  };
  if (separates(icross(edges[0], isub(p[2], p[0])))) return false;
  if (separates(icross(edges[3], isub(q[2], q[0])))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 3; j < 6; ++j)
      if (separates(icross(edges[i], edges[j]))) return false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const IVec d = isub(q[j], p[i]);
      if (separates(d)) return false;
      for (const IVec& e : edges)
        if (separates(icross(e, icross(d, e)))) return false;
    }
  return true;
}

}  // namespace impact::test
