// SPDX-License-Identifier: MIT
/// \file
/// A cheap proof that a CCD hit is real, so that the double-double re-check of hits
/// (inclusion.hpp, ccd_query) only runs on the hits it can change.
///
/// Both tests solve F(t, u, v) = A(t) + u B(t) + v C(t) = 0 with A, B, C linear in t:
///   vertex-face  A = p - f0, B = f0 - f1, C = f0 - f2;   edge-edge  A = a0 - b0, B = a1 - a0, C = b0 - b1.
/// A transversal contact is a simple root of F inside the domain. Starting from the hit of the
/// search, a few Newton steps give an approximate root x, and the Krawczyk test proves a root in
/// a small box X around it: with Y an approximate inverse of the Jacobian at x,
///   K(X) = x - Y F(x) + (I - Y J(X)) (X - x)  contained in the interior of X
/// implies that F has exactly one zero in X (Krawczyk 1969; Moore, Kearfott and Cloud,
/// "Introduction to Interval Analysis", SIAM 2009, section 8.2). F(x) and J(X) are enclosed in
/// interval arithmetic with every bound rounded outward, starting from the input coordinates, so
/// the proof is rigorous. When X lies in the domain (t in [0, t_max], u, v >= 0 and u + v <= 1 or
/// u, v <= 1) the primitives touch: the hit is not a false positive. With a minimum separation
/// d > 0, a point of the domain where |F| <= d is proof enough: the closest points of the two
/// primitives at a few times from the hit on are tried first.
/// Contacts on the domain's boundary (a vertex exactly on an edge), tangential and coplanar
/// contacts have no such proof and go to the re-check, which then runs to its budget.
#pragma once

#include "impact/ccd/options.hpp"
#include "impact/core/next_float.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/triangle.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// A closed interval [lo, hi] of reals with outward-rounded arithmetic (each bound moved one ulp
/// outward after rounding to nearest, which is at most half an ulp off).
struct Interval {
  double lo = 0.0, hi = 0.0;

  static double down(double x) { return next_down(x); }
  static double up(double x) { return next_up(x); }
  static Interval point(double x) { return {x, x}; }

  friend Interval operator+(const Interval& a, const Interval& b) { return {down(a.lo + b.lo), up(a.hi + b.hi)}; }
  friend Interval operator-(const Interval& a, const Interval& b) { return {down(a.lo - b.hi), up(a.hi - b.lo)}; }
  friend Interval operator*(const Interval& a, const Interval& b) {
    const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
    return {down(std::min(std::min(p[0], p[1]), std::min(p[2], p[3]))), up(std::max(std::max(p[0], p[1]), std::max(p[2], p[3])))};
  }
  double mag() const { return std::max(std::abs(lo), std::abs(hi)); }
};

/// The coefficients of F = a0 + t a1 + u (b0 + t b1) + v (c0 + t c1), enclosed from the inputs.
struct CcdLinearForm {
  Interval a0[3], a1[3], b0[3], b1[3], c0[3], c1[3];
};

template <bool VertexFace>
inline CcdLinearForm ccd_linear_form(const double (&p0)[4][3], const double (&p1)[4][3]) {
  CcdLinearForm L;
  for (int i = 0; i < 3; ++i) {
    Interval x0[4], dx[4];
    for (int k = 0; k < 4; ++k) {
      x0[k] = Interval::point(p0[k][i]);
      dx[k] = Interval::point(p1[k][i]) - x0[k];
    }
    // (A, B, C) as differences of points: vertex-face (0-1, 1-2, 1-3), edge-edge (0-2, 1-0, 2-3)
    const int ia[2] = {0, VertexFace ? 1 : 2};
    const int ib[2] = {1, VertexFace ? 2 : 0};
    const int ic[2] = {VertexFace ? 1 : 2, 3};
    L.a0[i] = x0[ia[0]] - x0[ia[1]];
    L.a1[i] = dx[ia[0]] - dx[ia[1]];
    L.b0[i] = x0[ib[0]] - x0[ib[1]];
    L.b1[i] = dx[ib[0]] - dx[ib[1]];
    L.c0[i] = x0[ic[0]] - x0[ic[1]];
    L.c1[i] = dx[ic[0]] - dx[ic[1]];
  }
  return L;
}

/// Encloses F over the box (t, u, v) and the Jacobian columns (dF/dt, dF/du, dF/dv) over it. Each
/// variable appears once in each formula, so these are the exact ranges up to rounding.
inline void ccd_enclose(const CcdLinearForm& L, const Interval (&x)[3], Interval (&F)[3], Interval (&J)[3][3]) {
  for (int i = 0; i < 3; ++i) {
    const Interval B = L.b0[i] + x[0] * L.b1[i], C = L.c0[i] + x[0] * L.c1[i];
    F[i] = (L.a0[i] + x[0] * L.a1[i]) + x[1] * B + x[2] * C;
    J[i][0] = L.a1[i] + x[1] * L.b1[i] + x[2] * L.c1[i];
    J[i][1] = B;
    J[i][2] = C;
  }
}

/// Whether the box lies in the domain of the parameters.
template <bool VertexFace> inline bool ccd_box_in_domain(const Interval (&x)[3], double t_max) {
  if (!(x[0].lo >= 0.0 && x[0].hi <= t_max && x[1].lo >= 0.0 && x[2].lo >= 0.0)) return false;
  if constexpr (VertexFace) return Interval::up(x[1].hi + x[2].hi) <= 1.0;
  return x[1].hi <= 1.0 && x[2].hi <= 1.0;
}

/// Tries to prove that the primitives come within opt.min_separation for some t in [0, t_max],
/// starting from the parameters (t, u, v) of a hit. True is a proof; false proves nothing.
template <bool VertexFace>
inline bool ccd_prove_contact(const double (&p0)[4][3], const double (&p1)[4][3], const CcdOptions& opt, double t, double u,
                              double v) {
  const CcdLinearForm L = ccd_linear_form<VertexFace>(p0, p1);
  double x[3] = {t, u, v};
  Interval F[3], J[3][3];
  const double d = opt.min_separation;
  auto close_enough = [&](const double (&y)[3]) {  // |F(y)| <= d, proven
    const Interval pt[3] = {Interval::point(y[0]), Interval::point(y[1]), Interval::point(y[2])};
    if (!ccd_box_in_domain<VertexFace>(pt, opt.t_max)) return false;
    ccd_enclose(L, pt, F, J);
    double s = 0.0;
    for (auto& f : F) s += f.mag() * f.mag();
    return std::sqrt(s) * (1.0 + 8.0 * std::numeric_limits<double>::epsilon()) <= d;
  };
  if (d > 0.0) {
    if (close_enough(x)) return true;
    for (int k = 0; k <= 8; ++k) {
      double y[3];
      y[0] = std::min(t + (opt.t_max - t) * (k / 8.0), opt.t_max);
      Vec3<double> X[4];
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 3; ++i) X[j][i] = p0[j][i] + y[0] * (p1[j][i] - p0[j][i]);
      if constexpr (VertexFace) {
        const auto c = closest_point_on_triangle(X[0], Triangle<double>(X[1], X[2], X[3]));
        y[1] = c.barycentric[1];
        y[2] = c.barycentric[2];
      } else {
        const auto c = closest_points_segment_segment(Segment<double>(X[0], X[1]), Segment<double>(X[2], X[3]));
        y[1] = c.s;
        y[2] = c.t;
      }
      if (close_enough(y)) return true;
    }
  }

  // Newton steps from the hit (plain double: only the final test needs to be rigorous).
  double Y[3][3];
  for (int it = 0; it < 6; ++it) {
    const Interval pt[3] = {Interval::point(x[0]), Interval::point(x[1]), Interval::point(x[2])};
    ccd_enclose(L, pt, F, J);
    double m[3][3], f[3];
    for (int i = 0; i < 3; ++i) {
      f[i] = 0.5 * (F[i].lo + F[i].hi);
      for (int j = 0; j < 3; ++j) m[i][j] = 0.5 * (J[i][j].lo + J[i][j].hi);
    }
    // Y = m^-1 by the adjugate
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) return false;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
        Y[i][j] = (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) / det;
      }
    double step = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double s = Y[i][0] * f[0] + Y[i][1] * f[1] + Y[i][2] * f[2];
      x[i] -= s;
      step = std::max(step, std::abs(s));
    }
    if (!std::isfinite(step) || step > 1.0) return false;
    if (step < 1e-15) break;
  }
  if (d > 0.0 && close_enough(x)) return true;

  // Krawczyk test on boxes of growing radius around x.
  for (double r : {1e-13, 1e-10, 1e-7}) {
    Interval X[3], D[3];
    for (int i = 0; i < 3; ++i) {
      X[i] = {Interval::down(x[i] - r), Interval::up(x[i] + r)};
      D[i] = X[i] - Interval::point(x[i]);
    }
    if (!ccd_box_in_domain<VertexFace>(X, opt.t_max)) continue;
    const Interval px[3] = {Interval::point(x[0]), Interval::point(x[1]), Interval::point(x[2])};
    Interval Fx[3], Jx[3][3], FX[3], JX[3][3];
    ccd_enclose(L, px, Fx, Jx);
    ccd_enclose(L, X, FX, JX);
    bool inside = true;
    for (int i = 0; i < 3 && inside; ++i) {
      Interval k = Interval::point(x[i]);
      for (int j = 0; j < 3; ++j) k = k - Interval::point(Y[i][j]) * Fx[j];
      for (int j = 0; j < 3; ++j) {
        Interval mij = Interval::point(i == j ? 1.0 : 0.0);
        for (int l = 0; l < 3; ++l) mij = mij - Interval::point(Y[i][l]) * JX[l][j];
        k = k + mij * D[j];
      }
      inside = k.lo > X[i].lo && k.hi < X[i].hi;
    }
    if (inside) return true;
  }
  return false;
}

}  // namespace impact::detail
