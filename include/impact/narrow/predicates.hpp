// SPDX-License-Identifier: MIT
/// \file
/// Exact orientation predicates orient3d and orient2d.
///
/// Numerical contract: EXACT. Each predicate returns the sign (-1, 0, +1) of the determinant of
/// its floating-point inputs as if evaluated in exact real arithmetic. The evaluation is a
/// floating-point determinant with a dynamic error bound (the Shewchuk stage-A bound, computed from
/// the permanent of the same products); only when that filter cannot certify the sign is the
/// determinant recomputed exactly with floating-point expansions (two-sum, fma two-product,
/// expansion growth with zero elimination). Float inputs are converted to double exactly and take
/// the double path.
///
/// Assumptions (documented, not checked):
///  - inputs are finite, and no intermediate product overflows or underflows into the subnormal
///    range: coordinate differences should stay within about [1e-50, 1e50] in magnitude when
///    nonzero (double), which every float input satisfies;
///  - IEEE-754 double arithmetic with round-to-nearest, no -ffast-math / -funsafe-math-optimizations
///    (fused multiply-add contraction is harmless: it only lowers the error of the filter, and the
///    exact stage uses std::fma explicitly).
#pragma once

#include "impact/core/types.hpp"

#include <cmath>
#include <type_traits>

namespace impact {
namespace detail {
namespace expansion {

/// x + y = a + b exactly, |y| <= ulp(x) / 2.
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a;
  const double av = x - bv;
  y = (a - av) + (b - bv);
}

/// x + y = a * b exactly (no underflow assumed).
inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

/// A floating-point expansion: a sum of nonoverlapping doubles stored by increasing magnitude,
/// zero components removed. Capacity N is a compile-time bound on the number of components.
template <int N> struct Expansion {
  double c[N];
  int n = 0;

  Expansion() = default;
  /// The expansion of a - b (exact, at most two components).
  static Expansion difference(double a, double b) {
    Expansion e;
    double x, y;
    two_sum(a, -b, x, y);
    if (y != 0.0) e.c[e.n++] = y;
    if (x != 0.0) e.c[e.n++] = x;
    return e;
  }
  /// Adds the double b exactly (Shewchuk's grow-expansion with zero elimination).
  void grow(double b) {
    if (b == 0.0) return;
    double q = b;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      double x, y;
      two_sum(q, c[i], x, y);
      q = x;
      if (y != 0.0) c[m++] = y;
    }
    if (q != 0.0) c[m++] = q;
    n = m;
  }
  /// Sign of the represented value: that of the most significant component.
  int sign() const { return n == 0 ? 0 : (c[n - 1] > 0.0 ? 1 : -1); }
};

/// Exact product of two expansions, accumulated into a (exact for the capacities used below).
template <int N, int A, int B> inline void add_product(Expansion<N>& acc, const Expansion<A>& x, const Expansion<B>& y, bool negate) {
  for (int i = 0; i < x.n; ++i)
    for (int j = 0; j < y.n; ++j) {
      double p, e;
      two_product(x.c[i], y.c[j], p, e);
      if (negate) p = -p, e = -e;
      acc.grow(e);
      acc.grow(p);
    }
}

/// Exact sign of det[b - a, c - a] (2D), by expansions.
inline int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
  const auto ux = Expansion<2>::difference(bx, ax), uy = Expansion<2>::difference(by, ay);
  const auto vx = Expansion<2>::difference(cx, ax), vy = Expansion<2>::difference(cy, ay);
  Expansion<16> det;
  add_product(det, ux, vy, false);
  add_product(det, uy, vx, true);
  return det.sign();
}

/// Exact sign of det[b - a, c - a, d - a] (3D), by expansions.
inline int orient3d_exact(const double* a, const double* b, const double* c, const double* d) {
  Expansion<2> u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = Expansion<2>::difference(b[k], a[k]);
    v[k] = Expansion<2>::difference(c[k], a[k]);
    w[k] = Expansion<2>::difference(d[k], a[k]);
  }
  Expansion<192> det;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    Expansion<16> minor;  // (u x v)_k = u_k1 v_k2 - u_k2 v_k1
    add_product(minor, u[k1], v[k2], false);
    add_product(minor, u[k2], v[k1], true);
    add_product(det, w[k], minor, false);
  }
  return det.sign();
}

}  // namespace expansion

/// Shewchuk's stage-A relative error bounds, rounded up generously (epsilon = 2^-53).
inline constexpr double orient3d_bound = (8.0 + 64.0 * 0x1p-53) * 0x1p-53;
inline constexpr double orient2d_bound = (4.0 + 32.0 * 0x1p-53) * 0x1p-53;

/// Filtered sign of (d - a) . n given the rounded normal n = fl((b - a) x (c - a)) and the permanent
/// components p_k = |u_k1 v_k2| + |u_k2 v_k1|. Returns 2 when the filter cannot decide.
inline int orient3d_filtered(const double* a, const double* n, const double* p, const double* d) {
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  const double det = wx * n[0] + wy * n[1] + wz * n[2];
  const double perm = std::fabs(wx) * p[0] + std::fabs(wy) * p[1] + std::fabs(wz) * p[2];
  const double bound = orient3d_bound * perm;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  if (perm == 0.0) return 0;  // every product is exactly zero
  return 2;
}

inline int orient3d_double(const double* a, const double* b, const double* c, const double* d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double n[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
  const double p[3] = {std::fabs(uy * vz) + std::fabs(uz * vy), std::fabs(uz * vx) + std::fabs(ux * vz),
                       std::fabs(ux * vy) + std::fabs(uy * vx)};
  const int s = orient3d_filtered(a, n, p, d);
  return s != 2 ? s : expansion::orient3d_exact(a, b, c, d);
}

inline int orient2d_double(double ax, double ay, double bx, double by, double cx, double cy) {
  const double l = (bx - ax) * (cy - ay), r = (by - ay) * (cx - ax);
  const double det = l - r;
  const double bound = orient2d_bound * (std::fabs(l) + std::fabs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  if (l == 0.0 && r == 0.0) return 0;
  return expansion::orient2d_exact(ax, ay, bx, by, cx, cy);
}

}  // namespace detail

/// Exact sign of det[b - a, c - a, d - a] = (d - a) . ((b - a) x (c - a)): +1 when d lies on the side
/// of the plane through a, b, c towards which the normal (b - a) x (c - a) points (a, b, c appear
/// counter-clockwise seen from d), -1 on the other side, 0 when the four points are coplanar
/// (exactly). Note the sign convention is the opposite of Shewchuk's orient3d.
template <class S> inline int orient3d(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c, const Vec3<S>& d) {
  static_assert(is_supported_scalar_v<S>, "orient3d: float or double");
  const double pa[3] = {double(a.x()), double(a.y()), double(a.z())}, pb[3] = {double(b.x()), double(b.y()), double(b.z())};
  const double pc[3] = {double(c.x()), double(c.y()), double(c.z())}, pd[3] = {double(d.x()), double(d.y()), double(d.z())};
  return detail::orient3d_double(pa, pb, pc, pd);
}

/// Exact sign of det[b - a, c - a] = (b - a) x (c - a): +1 when a, b, c turn counter-clockwise,
/// -1 clockwise, 0 when collinear (exactly).
template <class S> inline int orient2d(const Vec2<S>& a, const Vec2<S>& b, const Vec2<S>& c) {
  static_assert(is_supported_scalar_v<S>, "orient2d: float or double");
  return detail::orient2d_double(double(a.x()), double(a.y()), double(b.x()), double(b.y()), double(c.x()), double(c.y()));
}

/// A triangle's supporting plane prepared for many exact orient3d queries against the same a, b, c
/// (the normal and the filter's permanent terms are computed once). Same contract as orient3d.
struct OrientPlane {
  double a[3], b[3], c[3];
  double n[3];  ///< fl((b - a) x (c - a))
  double p[3];  ///< permanent terms of the normal for the error bound

  OrientPlane() = default;
  template <class S> OrientPlane(const Vec3<S>& pa, const Vec3<S>& pb, const Vec3<S>& pc) {
    for (int k = 0; k < 3; ++k) a[k] = double(pa[k]), b[k] = double(pb[k]), c[k] = double(pc[k]);
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    n[0] = uy * vz - uz * vy, n[1] = uz * vx - ux * vz, n[2] = ux * vy - uy * vx;
    p[0] = std::fabs(uy * vz) + std::fabs(uz * vy), p[1] = std::fabs(uz * vx) + std::fabs(ux * vz);
    p[2] = std::fabs(ux * vy) + std::fabs(uy * vx);
  }
  /// Exact orient3d(a, b, c, d).
  int orient(const double* d) const {
    const int s = detail::orient3d_filtered(a, n, p, d);
    return s != 2 ? s : detail::expansion::orient3d_exact(a, b, c, d);
  }
  template <class S> int orient(const Vec3<S>& d) const {
    const double pd[3] = {double(d.x()), double(d.y()), double(d.z())};
    return orient(pd);
  }
};

}  // namespace impact
