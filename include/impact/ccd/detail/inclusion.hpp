// SPDX-License-Identifier: MIT
/// \file
/// The search behind vertex_face_ccd and edge_edge_ccd: a best-first subdivision of the parameter
/// box (t, u, v) of the multivariate formulation F(t, u, v) = 0 with a conservative inclusion of
/// the range of F on each box.
///
/// F is the difference of the two moving points, linear in each of t, u and v separately:
///   vertex-face  F = p(t) - f0(t) - u (f1(t) - f0(t)) - v (f2(t) - f0(t)),  u, v >= 0, u + v <= 1
///   edge-edge    F = a0(t) + u (a1(t) - a0(t)) - b0(t) - v (b1(t) - b0(t)), u, v in [0, 1]
/// A function that is linear in each variable takes its extreme values on a box at the box's 8
/// corners, so the hull of the corner values is the exact range of each component of F (and of
/// n . F for any fixed direction n). The corner values are computed in double with a forward
/// error bound (see error_bound below) that holds for every box, so a box is excluded only when
/// the exact range proves the distance exceeds the minimum separation: no false negatives.
///
/// Boxes are processed in order of their earliest time (ties: deeper boxes first), so the first
/// box that cannot be excluded and is within tolerance gives a time of impact no later than the
/// true one: every earlier time has been covered by excluded boxes. Splits are adaptive: a
/// variable whose halving lets a half be excluded, else the one along which F changes most.
/// The idea follows the inclusion-based method of Wang et al., "A Large Scale Benchmark and an
/// Inclusion-Based Algorithm for Continuous Collision Detection" (ACM TOG 2021), with best-first
/// ordering in t, adaptive splits and extra exclusion directions (plane normal, separation
/// direction) for coplanar motion, parallel edges and minimum separations.
///
/// The error bounds assume IEEE-754 double arithmetic (any rounding mode; contraction into FMA is
/// fine since it only removes roundings). Value-changing optimisations such as -ffast-math
/// (reassociation) void the guarantee.
#pragma once

#include "impact/ccd/detail/contact_proof.hpp"
#include "impact/ccd/detail/double_double.hpp"
#include "impact/ccd/options.hpp"
#include "impact/core/config.hpp"
#include "impact/core/error.hpp"
#include "impact/core/next_float.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace impact::detail {

/// One box of the parameter domain, with its depth (number of splits from the root).
struct CcdBox {
  double t0, t1, u0, u1, v0, v1;
  std::int32_t depth;
};

/// Heap order: the box with the smallest t0 first; among equal t0 the deeper box first.
struct CcdBoxLater {
  bool operator()(const CcdBox& a, const CcdBox& b) const { return a.t0 > b.t0 || (a.t0 == b.t0 && a.depth < b.depth); }
};

/// Absolute floor of the error bounds, covering underflow: of products and double-double low
/// parts (each at most 2^-1074 off), and of the power-of-two scaling of coordinates 2^1022 times
/// smaller than the largest one (ccd_normalise; at most 2^-1075 off, which moves F by less than
/// 2^-1070). The scaled coordinates are below 2 in magnitude, so this is far below any gap the
/// search could resolve.
inline constexpr double kCcdTinyError = 1e-290;

/// The arithmetic the search runs in: double for the search itself, DoubleDouble for the re-check
/// of hits. `value_exponent`: the corner values of F are within 2^value_exponent m of exact (m the
/// magnitude bound); `direction_exponent`: the same for n . F, relative to sum |n_i| m_i.
/// With u the unit roundoff of one operation (2^-53 for double, 2^-103 for DoubleDouble, see
/// double_double.hpp) and m the bound on |x - r| (points relative to the reference point r, see
/// CcdQuery), the moving point (x0 - r) + t (x1 - x0) is within 6 u m of exact (x0 - r and
/// x1 - x0 rounded once each, |x1 - x0| <= 2 m), the differences and products of either
/// formulation add at most 45 u m more (all intermediates stay below 6 m), and a dot product with
/// n adds 3 u sum |n_i| m_i. The bounds used, 512 u m and 1024 u sum |n_i| m_i, leave a margin of
/// 10x, which also covers m being computed in double and the rounding of lo - err and of |n_i|.
/// The queries reach the search scaled by a power of two (ccd_normalise), so every coordinate is
/// below 2 in magnitude: nothing overflows, and what underflows is covered by kCcdTinyError.
template <class T> struct CcdArith;
template <> struct CcdArith<double> {
  static constexpr int value_exponent = -44;      // 512 * 2^-53
  static constexpr int direction_exponent = -43;  // 1024 * 2^-53
  static double difference(double a, double b) { return a - b; }
  static double approx(double x) { return x; }
  static double abs(double x) { return std::abs(x); }
};
template <> struct CcdArith<DoubleDouble> {
  static constexpr int value_exponent = -94;      // 512 * 2^-103
  static constexpr int direction_exponent = -93;  // 1024 * 2^-103
  static DoubleDouble difference(double a, double b) { return DoubleDouble::difference(a, b); }  // exact
  static double approx(const DoubleDouble& x) { return x.approx(); }
  static DoubleDouble abs(const DoubleDouble& x) { return detail::abs(x); }
};

/// The four moving points of a query, relative to a reference point r (the first point at t = 0):
/// x0 - r at t = 0 and dx = x1 - x0 (both rounded in double, exact in DoubleDouble), with the
/// per-axis magnitude bound and error bound. F is a difference of two moving points, so it is the
/// same function of the points relative to r; computing it from them makes the rounding errors,
/// and so the bounds, relative to the query's extent around r instead of to its distance from the
/// origin: a translated query is searched alike (identically when the translation is exact), and
/// a query whose coordinates differ by far less than their magnitude gets bounds it can beat.
template <class T> struct CcdQuery {
  T x0[4][3];
  T dx[4][3];
  double mag[3];  ///< max |x - r| over the 8 input points x, per axis (computed in double)
  double err[3];  ///< bound on |computed - exact| of any corner value of F, per axis
};

/// Forward error bound of one component of F at any (t, u, v) in [0,1]^3 computed as in
/// ccd_corners from coordinates bounded by m in magnitude (see CcdArith).
template <class T> inline double error_bound(double m) { return std::ldexp(m, CcdArith<T>::value_exponent) + kCcdTinyError; }

template <class T> inline CcdQuery<T> make_ccd_query(const double (&p0)[4][3], const double (&p1)[4][3]) {
  CcdQuery<T> q{};
  for (int i = 0; i < 3; ++i) {
    const double r = p0[0][i];
    q.mag[i] = 0.0;
    for (int k = 0; k < 4; ++k) {
      q.x0[k][i] = CcdArith<T>::difference(p0[k][i], r);
      q.dx[k][i] = CcdArith<T>::difference(p1[k][i], p0[k][i]);
      q.mag[i] = std::max(q.mag[i], std::max(std::abs(p0[k][i] - r), std::abs(p1[k][i] - r)));
    }
    q.err[i] = error_bound<T>(q.mag[i]);
  }
  return q;
}

/// Whether the parameters u, v >= 0 of a box corner satisfy u + v <= 1 exactly.
inline bool in_triangle(double u, double v) {
  double s, e;
  two_sum(u, v, s, e);
  return s < 1.0 || (s == 1.0 && e <= 0.0);
}

/// Number of extra exclusion directions per box (besides the three axes).
inline constexpr int kCcdDirections = 3;

/// Corner values of F on a box: f[c][axis] with corner c = 4 it + 2 iu + iv (it, iu, iv in {0, 1}
/// for the low/high ends of t, u, v), and two directions used as extra exclusion axes:
///  - the plane normal at the box's start time (cross product of the two edge vectors), which
///    separates coplanar motion and crossing edges;
///  - the part of F at the centre of the box's start face orthogonal to the longest edge, which
///    separates parallel edges and degenerate (collinear) triangles, where the normal vanishes;
///  - F at that centre itself: near the closest approach it is the direction of the separation, so
///    n . F > d |n| is a tight test against a minimum separation d > 0.
/// Any direction gives a valid exclusion; these are chosen to make it effective.
template <bool VertexFace, class T>
inline void ccd_corners(const CcdQuery<T>& q, const CcdBox& b, T (&f)[8][3], T (&dir)[kCcdDirections][3]) {
  using A = CcdArith<T>;
  const double ts[2] = {b.t0, b.t1};
  const double us[2] = {b.u0, b.u1};
  const double vs[2] = {b.v0, b.v1};
  T edge[3];
  double best = 0.0;
  for (int it = 0; it < 2; ++it) {
    T x[4][3];
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i) x[k][i] = q.x0[k][i] + ts[it] * q.dx[k][i];
    T e0[3], e1[3], e2[3];
    if constexpr (VertexFace) {
      for (int i = 0; i < 3; ++i) {
        e0[i] = x[0][i] - x[1][i];
        e1[i] = x[2][i] - x[1][i];
        e2[i] = x[3][i] - x[1][i];
      }
      for (int iu = 0; iu < 2; ++iu)
        for (int iv = 0; iv < 2; ++iv)
          for (int i = 0; i < 3; ++i) f[4 * it + 2 * iu + iv][i] = (e0[i] - us[iu] * e1[i]) - vs[iv] * e2[i];
    } else {
      for (int i = 0; i < 3; ++i) {
        e1[i] = x[1][i] - x[0][i];
        e2[i] = x[3][i] - x[2][i];
      }
      for (int iu = 0; iu < 2; ++iu)
        for (int iv = 0; iv < 2; ++iv)
          for (int i = 0; i < 3; ++i) f[4 * it + 2 * iu + iv][i] = (x[0][i] + us[iu] * e1[i]) - (x[2][i] + vs[iv] * e2[i]);
    }
    if (it == 0) {
      dir[0][0] = e1[1] * e2[2] - e1[2] * e2[1];
      dir[0][1] = e1[2] * e2[0] - e1[0] * e2[2];
      dir[0][2] = e1[0] * e2[1] - e1[1] * e2[0];
      // the longest edge, chosen in double (any choice is valid)
      auto len2 = [](const T (&e)[3]) {
        double l = 0.0;
        for (int i = 0; i < 3; ++i) l += A::approx(e[i]) * A::approx(e[i]);
        return l;
      };
      best = len2(e1);
      for (int i = 0; i < 3; ++i) edge[i] = e1[i];
      if (len2(e2) > best) {
        best = len2(e2);
        for (int i = 0; i < 3; ++i) edge[i] = e2[i];
      }
      if constexpr (VertexFace) {
        T e3[3];
        for (int i = 0; i < 3; ++i) e3[i] = e2[i] - e1[i];
        if (len2(e3) > best) {
          best = len2(e3);
          for (int i = 0; i < 3; ++i) edge[i] = e3[i];
        }
      }
    }
  }
  // F at the centre of the start face is the mean of its 4 corners (multilinearity).
  T fc[3];
  for (int i = 0; i < 3; ++i) fc[i] = 0.25 * ((f[0][i] + f[1][i]) + (f[2][i] + f[3][i]));
  double s = 0.0;
  if (best > 0.0) {
    for (int i = 0; i < 3; ++i) s += A::approx(fc[i]) * A::approx(edge[i]);
    s /= best;
  }
  for (int i = 0; i < 3; ++i) {
    dir[1][i] = fc[i] - s * edge[i];
    dir[2][i] = fc[i];
  }
}

/// The search in arithmetic T (double, or DoubleDouble for the re-check). p0/p1: the 4 points at
/// t = 0 and t = 1 (vertex-face: p, f0, f1, f2; edge-edge: a0, a1, b0, b1). Preconditions: the
/// query normalised by ccd_normalise (coordinates below 2 in magnitude), 0 <= d <= 8,
/// 0 < t_max <= 1. Besides the tolerance, a corner
/// is accepted when rounding alone keeps it from being proved farther than d away (a single point
/// cannot be split further), which is what ends the re-check on real contacts.
template <bool VertexFace, class T = double>
inline CcdResult<double> inclusion_ccd(const double (&p0)[4][3], const double (&p1)[4][3], const CcdOptions& opt) {
  using A = CcdArith<T>;
  constexpr int kFunctions = 3 + kCcdDirections;
  const CcdQuery<T> q = make_ccd_query<T>(p0, p1);
  const double d = opt.min_separation;
  const double eps = std::numeric_limits<double>::epsilon();
  const double d2 = d * d * (1.0 + 32.0 * eps);
  const double acc = (d + opt.tolerance) * (d + opt.tolerance);
  CcdResult<double> r;
  r.toi = opt.t_max;

  std::vector<CcdBox> heap;
  heap.reserve(64);
  heap.push_back({0.0, opt.t_max, 0.0, 1.0, 0.0, 1.0, 0});
  const CcdBoxLater later;
  std::int64_t it = 0;
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), later);
    const CcdBox b = heap.back();
    heap.pop_back();
    if (VertexFace && b.u0 + b.v0 > 1.0) continue;  // outside the triangle (rounding is monotone)
    ++it;

    // hv[c][j]: corner c of exclusion function j (F_x, F_y, F_z, then dir_k . F).
    T f[8][3], dir[kCcdDirections][3], hv[8][kFunctions];
    ccd_corners<VertexFace>(q, b, f, dir);
    T lo[kFunctions], hi[kFunctions];
    double err[kFunctions], thr[kFunctions];
    // The directions, rounded to double (any direction is valid; this one is used exactly).
    double nd[kCcdDirections][3];
    for (int k = 0; k < kCcdDirections; ++k)
      for (int i = 0; i < 3; ++i) nd[k][i] = A::approx(dir[k][i]);
    for (int c = 0; c < 8; ++c) {
      for (int i = 0; i < 3; ++i) hv[c][i] = f[c][i];
      for (int k = 0; k < kCcdDirections; ++k) hv[c][3 + k] = f[c][0] * nd[k][0] + f[c][1] * nd[k][1] + f[c][2] * nd[k][2];
    }
    for (int j = 0; j < kFunctions; ++j) {
      lo[j] = hi[j] = hv[0][j];
      for (int c = 1; c < 8; ++c) {
        lo[j] = std::min(lo[j], hv[c][j]);
        hi[j] = std::max(hi[j], hv[c][j]);
      }
    }
    for (int i = 0; i < 3; ++i) {
      err[i] = q.err[i];
      thr[i] = d;
    }
    for (int k = 0; k < kCcdDirections; ++k) {
      const double* n = nd[k];
      // n . F is multilinear too (n is fixed on the box); error: |n|_1-weighted F error plus the
      // rounding of the dot product (see CcdArith).
      err[3 + k] = std::ldexp(std::abs(n[0]) * q.mag[0] + std::abs(n[1]) * q.mag[1] + std::abs(n[2]) * q.mag[2],
                              A::direction_exponent) +
                   kCcdTinyError;
      // |F| <= d implies |n . F| <= d |n|.
      thr[3 + k] = d > 0.0 ? d * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) * (1.0 + 16.0 * eps) : 0.0;
    }
    // Exclusion: some function stays beyond its threshold on the whole box, or (d > 0) the
    // per-axis lower bounds of |F_i| already exceed d together.
    bool excluded = false;
    double gap[3];
    for (int j = 0; j < kFunctions; ++j) {
      const T l = lo[j] - err[j], h = hi[j] + err[j];
      const T g = l > T(0.0) ? l : (h < T(0.0) ? -h : T(0.0));
      if (j < 3) gap[j] = A::approx(g);
      excluded = excluded || g > T(thr[j]);
    }
    if (!excluded && d > 0.0) excluded = gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2] > d2;
    if (excluded) continue;

    // Acceptance: a corner of the start face, inside the domain, where the primitives are within
    // d + tolerance (or not provably farther than d: see above). Every earlier time is excluded,
    // so toi = t0 is conservative.
    const double tm = 0.5 * (b.t0 + b.t1), um = 0.5 * (b.u0 + b.u1), vm = 0.5 * (b.v0 + b.v1);
    // Or the whole box is within the tolerance in every component: since it is not excluded,
    // every point of it is then within d + sqrt(3) tolerance (this is what ends the search when
    // d > 0, where the distance only grazes d at the first contact).
    int accept = -1;
    if (A::approx(hi[0] - lo[0]) <= opt.tolerance && A::approx(hi[1] - lo[1]) <= opt.tolerance &&
        A::approx(hi[2] - lo[2]) <= opt.tolerance)
      accept = 0;
    for (int c = 0; c < 4 && accept < 0; ++c) {
      const double cu = (c >> 1) ? b.u1 : b.u0, cv = (c & 1) ? b.v1 : b.v0;
      if (VertexFace && !in_triangle(cu, cv)) continue;
      double n2 = 0.0, m2 = 0.0;
      for (int i = 0; i < 3; ++i) {
        const double x = A::approx(f[c][i]);
        const double m = std::max(std::abs(x) - err[i], 0.0);
        n2 += x * x;
        m2 += m * m;
      }
      if (n2 <= acc || m2 <= d2) accept = c;
    }
    const bool can_t = tm > b.t0 && tm<b.t1, can_u = um> b.u0 && um<b.u1, can_v = vm> b.v0 && vm < b.v1;
    const bool budget = it >= opt.max_iterations;
    if (accept >= 0 || budget || !(can_t || can_u || can_v)) {
      r.hit = true;
      r.toi = b.t0;
      r.u = accept >= 0 ? ((accept >> 1) ? b.u1 : b.u0) : um;
      r.v = accept >= 0 ? ((accept & 1) ? b.v1 : b.v0) : vm;
      if (VertexFace && r.u + r.v > 1.0) {
        const double sum = r.u + r.v;
        r.u /= sum;
        r.v /= sum;
      }
      r.budget_exhausted = budget && accept < 0;
      r.iterations = it;
      return r;
    }
    // Split choice (heuristic, in double). F is multilinear, so the corner values of both halves
    // of a split are the parent's corners and the midpoints of its edges (averages). Prefer the
    // variable whose split lets a half be excluded right away (this is what makes sliding and
    // collinear contacts cheap); otherwise halve the variable along which F varies most.
    double hd[8][kFunctions];
    for (int c = 0; c < 8; ++c)
      for (int j = 0; j < kFunctions; ++j) hd[c][j] = A::approx(hv[c][j]);
    double wdim[3] = {0.0, 0.0, 0.0};
    int excl[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      const int bit = 4 >> k;  // t: 4, u: 2, v: 1
      for (int j = 0; j < kFunctions; ++j) {
        const double tj = thr[j] + err[j];
        double l0 = std::numeric_limits<double>::infinity(), h0 = -l0, l1 = l0, h1 = -l0, lm = l0, hm = -l0;
        for (int c = 0; c < 8; ++c) {
          if (c & bit) continue;
          const double x0 = hd[c][j], x1 = hd[c | bit][j], xm = 0.5 * (x0 + x1);
          l0 = std::min(l0, x0), h0 = std::max(h0, x0);
          l1 = std::min(l1, x1), h1 = std::max(h1, x1);
          lm = std::min(lm, xm), hm = std::max(hm, xm);
          // Widths that guide the split when no half can be excluded: the components of F for
          // d = 0; for d > 0 the radial direction (F at the centre), whose variation is small
          // in (u, v) near the closest approach and large in t, which favours time splits there.
          if (d > 0.0 ? j == 2 + kCcdDirections : j < 3) wdim[k] = std::max(wdim[k], std::abs(x1 - x0));
        }
        const bool ex0 = std::min(l0, lm) > tj || std::max(h0, hm) < -tj;
        const bool ex1 = std::min(l1, lm) > tj || std::max(h1, hm) < -tj;
        excl[k] = std::max(excl[k], int(ex0) + int(ex1));
      }
    }
    const bool can[3] = {can_t, can_u, can_v};
    int dim = -1;
    for (int k = 0; k < 3; ++k) {
      if (!can[k]) continue;
      if (dim < 0 || excl[k] > excl[dim] || (excl[k] == excl[dim] && wdim[k] > wdim[dim])) dim = k;
    }
    CcdBox lo_box = b, hi_box = b;
    lo_box.depth = hi_box.depth = b.depth + 1;
    if (dim == 0) {
      lo_box.t1 = hi_box.t0 = tm;
    } else if (dim == 1) {
      lo_box.u1 = hi_box.u0 = um;
    } else {
      lo_box.v1 = hi_box.v0 = vm;
    }
    heap.push_back(lo_box);
    std::push_heap(heap.begin(), heap.end(), later);
    heap.push_back(hi_box);
    std::push_heap(heap.begin(), heap.end(), later);
  }
  r.iterations = it;
  return r;
}

/// A query scaled by 2^-e so that its largest coordinate magnitude is in [1, 2), with the options
/// in the scaled units: the minimum separation scaled (rounded up, capped at 8, farther than any
/// two points of the scaled query can be) and the tolerance made absolute, tolerance times the
/// query's extent (the largest side of the box around its 8 points). Scaling by a power of two is
/// exact (up to underflow, see kCcdTinyError), so queries that differ by a power-of-two scale
/// are searched identically: the same decisions, iterations and toi, at any magnitude.
struct CcdNormalised {
  double p0[4][3], p1[4][3];
  CcdOptions opt;
};

inline CcdNormalised ccd_normalise(const double (&p0)[4][3], const double (&p1)[4][3], const CcdOptions& opt) {
  CcdNormalised n;
  double m = 0.0;
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < 3; ++i) m = std::max(m, std::max(std::abs(p0[k][i]), std::abs(p1[k][i])));
  const int e = m > 0.0 ? std::ilogb(m) : 0;
  if (e > -1000 && e < 1000) {  // one exact product each (2^-e is a normal double)
    const double s = std::ldexp(1.0, -e);
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i) {
        n.p0[k][i] = p0[k][i] * s;
        n.p1[k][i] = p1[k][i] * s;
      }
  } else {
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < 3; ++i) {
        n.p0[k][i] = std::ldexp(p0[k][i], -e);
        n.p1[k][i] = std::ldexp(p1[k][i], -e);
      }
  }
  double extent = 0.0;
  for (int i = 0; i < 3; ++i) {
    double lo = n.p0[0][i], hi = lo;
    for (int k = 0; k < 4; ++k) {
      lo = std::min(lo, std::min(n.p0[k][i], n.p1[k][i]));
      hi = std::max(hi, std::max(n.p0[k][i], n.p1[k][i]));
    }
    extent = std::max(extent, hi - lo);
  }
  n.opt = opt;
  double d = std::ldexp(opt.min_separation, -e);
  if (std::ldexp(d, e) < opt.min_separation) d = next_up(d);
  n.opt.min_separation = std::min(d, 8.0);
  n.opt.tolerance = opt.tolerance * extent;
  return n;
}

/// The test: the query normalised (ccd_normalise), the search in double, then, for a hit that is
/// not proved real (contact_proof.hpp), the re-check in DoubleDouble without the tolerance
/// (CcdOptions::recheck_iterations), which turns the hit into a miss when it proves that no
/// contact happens; otherwise the double search's answer stands. toi, u, v are unitless, so the
/// result needs no scaling back.
template <bool VertexFace>
inline CcdResult<double> ccd_query(const double (&raw0)[4][3], const double (&raw1)[4][3], const CcdOptions& raw_opt) {
  const CcdNormalised n = ccd_normalise(raw0, raw1, raw_opt);
  const auto& p0 = n.p0;
  const auto& p1 = n.p1;
  const CcdOptions& opt = n.opt;
  CcdResult<double> r = inclusion_ccd<VertexFace>(p0, p1, opt);
  if (!r.hit || opt.recheck_iterations <= 0) return r;
  if (!r.budget_exhausted && ccd_prove_contact<VertexFace>(p0, p1, opt, r.toi, r.u, r.v)) return r;  // a real contact
  CcdOptions fine = opt;
  fine.tolerance = 0.0;
  fine.max_iterations = opt.recheck_iterations;
  CcdResult<double> c;
  if constexpr (VertexFace) {
    // The boxes cover u + v <= 1 only up to the hypotenuse, which boxes cannot resolve near a
    // near miss just outside it. Put the triangle vertex nearest to the hit at f0, so that the
    // edges next to the hit are the axes u = 0 and v = 0, which boxes resolve exactly.
    const double w[3] = {1.0 - r.u - r.v, r.u, r.v};
    const int k = w[1] > w[0] && w[1] >= w[2] ? 1 : (w[2] > w[0] && w[2] > w[1] ? 2 : 0);
    double q0[4][3], q1[4][3];
    for (int i = 0; i < 3; ++i) {
      q0[0][i] = p0[0][i];
      q1[0][i] = p1[0][i];
      for (int j = 0; j < 3; ++j) {
        q0[1 + j][i] = p0[1 + (k + j) % 3][i];
        q1[1 + j][i] = p1[1 + (k + j) % 3][i];
      }
    }
    c = inclusion_ccd<VertexFace, DoubleDouble>(q0, q1, fine);
  } else {
    c = inclusion_ccd<VertexFace, DoubleDouble>(p0, p1, fine);
  }
  r.recheck_iterations = c.iterations;
  if (!c.hit) {
    r.hit = false;
    r.toi = opt.t_max;
    r.u = r.v = 0.0;
    r.budget_exhausted = false;
  }
  return r;
}

/// Copies four Vec3-like points into a plain array of doubles.
template <class P>
inline void ccd_load(const P& a, const P& b, const P& c, const P& e, double (&out)[4][3]) {
  for (int i = 0; i < 3; ++i) {
    out[0][i] = static_cast<double>(a[i]);
    out[1][i] = static_cast<double>(b[i]);
    out[2][i] = static_cast<double>(c[i]);
    out[3][i] = static_cast<double>(e[i]);
  }
}

/// Converts a double result to scalar S, rounding the time of impact down so it stays conservative.
template <class S>
inline CcdResult<S> ccd_result_cast(const CcdResult<double>& r) {
  CcdResult<S> o;
  o.hit = r.hit;
  S t = static_cast<S>(r.toi);
  if (r.hit && static_cast<double>(t) > r.toi) t = next_down(t);
  o.toi = std::max(t, S(0));
  o.u = static_cast<S>(r.u);
  o.v = static_cast<S>(r.v);
  o.budget_exhausted = r.budget_exhausted;
  o.iterations = r.iterations;
  o.recheck_iterations = r.recheck_iterations;
  return o;
}

/// Largest iteration budget accepted, for the search and for the re-check. The search's heap
/// grows by at most one box (56 bytes) per iteration and a box costs about 0.1-2 us, so this
/// bounds one query to about 235 MB and a few seconds; a larger budget is an input error.
inline constexpr std::int64_t kCcdMaxIterations = std::int64_t(1) << 22;

/// Largest coordinate magnitude of the mesh CCD (mesh_ccd.hpp), whose swept boxes must stay
/// finite when grown by the minimum separation. The primitive tests take any finite coordinates.
inline constexpr double kCcdMaxCoordinate = 1e100;

/// A double for an error message (%g keeps tiny and huge values readable, NaN reads "nan").
inline std::string ccd_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

/// Throws InvalidInput unless the options are usable: min_separation finite and >= 0, t_max in
/// (0, 1], tolerance finite and >= 0, max_iterations in [1, kCcdMaxIterations],
/// recheck_iterations in [0, kCcdMaxIterations]. `where` names the entry point. A few compares.
inline void ccd_validate_options(const CcdOptions& opt, const char* where) {
  const std::string w = std::string(where) + ": CcdOptions::";
  if (!(opt.min_separation >= 0.0 && opt.min_separation <= std::numeric_limits<double>::max()))
    throw InvalidInput(w + "min_separation must be finite and >= 0, is " + ccd_number(opt.min_separation));
  if (!(opt.t_max > 0.0 && opt.t_max <= 1.0)) throw InvalidInput(w + "t_max must be in (0, 1], is " + ccd_number(opt.t_max));
  if (!(opt.tolerance >= 0.0 && opt.tolerance <= std::numeric_limits<double>::max()))
    throw InvalidInput(w + "tolerance must be finite and >= 0, is " + ccd_number(opt.tolerance));
  if (opt.max_iterations < 1 || opt.max_iterations > kCcdMaxIterations)
    throw InvalidInput(w + "max_iterations must be in [1, " + std::to_string(kCcdMaxIterations) + "], is " +
                       std::to_string(opt.max_iterations));
  if (opt.recheck_iterations < 0 || opt.recheck_iterations > kCcdMaxIterations)
    throw InvalidInput(w + "recheck_iterations must be in [0, " + std::to_string(kCcdMaxIterations) + "], is " +
                       std::to_string(opt.recheck_iterations));
}

/// Throws InvalidInput unless every coordinate of the 8 points is finite (any finite magnitude is
/// in range: the queries are normalised, see ccd_normalise). `where` names the entry point.
inline void ccd_validate_points(const double (&p0)[4][3], const double (&p1)[4][3], const char* where) {
  for (int k = 0; k < 8; ++k)
    for (int i = 0; i < 3; ++i) {
      const double x = k < 4 ? p0[k][i] : p1[k - 4][i];
      if (!std::isfinite(x))
        throw InvalidInput(std::string(where) + ": point " + std::to_string(k) + " (" + (k < 4 ? "t = 0" : "t = 1") +
                           ") has a non-finite coordinate " + ccd_number(x));
    }
}

/// Validates a query (options and points); throws InvalidInput. Cheap next to the test itself.
inline void ccd_check(const double (&p0)[4][3], const double (&p1)[4][3], const CcdOptions& opt, const char* where) {
  ccd_validate_options(opt, where);
  ccd_validate_points(p0, p1, where);
}

}  // namespace impact::detail
