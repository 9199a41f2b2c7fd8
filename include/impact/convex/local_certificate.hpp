// SPDX-License-Identifier: MIT
/// \file
/// A local certificate of the penetration depth of two curved convex shapes whose overlap has a
/// closed form (cylinder against cylinder, cone or box), used by EPA (convex/epa.hpp) to stop long
/// before its polytope resolves the curved contact.
///
/// The overlap along w (not necessarily unit), f(w) = h_A(w) + h_B(-w), is the support function of
/// D = A - B; for these shapes it is a sum of terms
///   disc terms  c |P_a w|  (P_a = I - a a^T: a disc of radius c about axis a),
///   abs terms   c |a . w|  (a segment of half length c along a),
///   linear      l . w,
/// (a cylinder of radius r and half length h about a: r |P_a w| + h |a . w| + centre . w; a cone is
/// the larger of its apex's and its base rim's terms, of which the branch active at the contact is
/// kept, a lower bound everywhere). The depth is min f over unit w.
///
/// Newton's method on the sphere from a start direction n0 (EPA's best normal) finds a smooth
/// local minimiser n* (exact gradient and Hessian of the terms), U = f(n*). In the gnomonic chart
/// w(y) = n* + y1 e1 + y2 e2 (e1, e2 orthonormal, normal to n*), for |y| <= T:
///   disc terms: |z0 + M y| >= |z0| + u . M y + y^T M^T (I - u u^T) M y / (2 (|z0| + T))
///               (z0 = P n*, u = z0 / |z0|, M = P [e1 e2], |M| <= 1);
///   abs terms:  c |a . w| >= c s (a . w), s the sign of a . n* (exact while the sign holds);
/// so F(y) = f(w(y)) >= U + g . y + y^T Q y / 2, and with lambda the least eigenvalue of Q - U I
/// (> 0 required), F(y) >= rho (1 + |y|^2 / 2) >= rho |w(y)| for rho = U - |g|^2 / (2 lambda)
/// (minus a rounding allowance): f >= rho on the cap of directions within atan(T) of n*. The
/// largest T of a short halving sequence that keeps lambda > 0 is taken.
///
/// Outside the cap, EPA's polytope P (inside D) decides: if f(n) < rho then h_P(n) < rho, so the
/// ray along n leaves P through a face F (normal m_F, distance d_F) at a point x with |x| < rho,
/// and angle(n, m_F) <= acos(d_F / rho). So when every face of P with d_F < rho has
/// angle(m_F, n*) + acos(d_F / rho) <= atan(T), no unit n has f(n) < rho: depth in [rho, U]
/// (EpaLocal below, checked by epa_penetration_from_simplex at each step).
///
/// When Newton meets a kink (a ruling, a cap, the cone's apex against its rim) or an indefinite
/// Hessian, or no T gives lambda > 0, there is no certificate and EPA goes on to its own tolerance.
/// Bounded: at most kLocalNewtonSteps Newton steps (each within half the distance to a disc term's
/// axis, where its model holds) and 14 trial radii.
///
/// Numerical contract: APPROXIMATE; upper is f(n*) from the terms (up to rounding), lower = rho
/// includes an allowance of 64 ulps of the terms' magnitude for rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/azimuth_turn.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace impact::detail {

inline constexpr int kLocalNewtonSteps = 12;
/// The most terms an overlap has: a cylinder's two against a box's three (convex/cylinder_box_pair.hpp).
inline constexpr int kMaxOverlapTerms = 5;

/// The overlap f(w) of the file comment as terms (at most kMaxOverlapTerms disc or abs terms).
template <class S>
struct OverlapTerms {
  Vec3<S> axis[kMaxOverlapTerms];
  S coef[kMaxOverlapTerms];
  bool disc[kMaxOverlapTerms];
  int n = 0;
  Vec3<S> linear = Vec3<S>::Zero();
  S magnitude = S(0);  // sum of |coefficients| and |linear|: the scale of rounding
  void add(const Vec3<S>& a, S c, bool is_disc) {
    axis[n] = a;
    coef[n] = c;
    disc[n] = is_disc;
    ++n;
    magnitude += std::abs(c);
  }
};

/// The local certificate: on success the minimiser, its overlap (upper), the certified lower bound
/// on the cap of directions within `cap` radians of the normal (cos_cap its cosine).
template <class S>
struct LocalCertificate {
  bool ok = false;
  Vec3<S> normal = Vec3<S>::UnitZ();
  S upper = S(0), lower = S(0), cap = S(0), cos_cap = S(1);
  int newton_steps = 0;
};

/// Value, gradient and Hessian (in the basis e1, e2 normal to n) of f at unit n, or false at a
/// kink: a disc term with |P n| below `kink` or (`signs` given) an abs term whose sign differs.
template <class S>
bool overlap_model(const OverlapTerms<S>& f, const Vec3<S>& n, const Vec3<S>& e1, const Vec3<S>& e2, S& value, S g[2], S H[3],
                   S kink) {
  value = f.linear.dot(n);
  g[0] = f.linear.dot(e1);
  g[1] = f.linear.dot(e2);
  H[0] = H[1] = H[2] = S(0);
  for (int k = 0; k < f.n; ++k) {
    const Vec3<S>& a = f.axis[k];
    const S c = f.coef[k], an = a.dot(n), a1 = a.dot(e1), a2 = a.dot(e2);
    if (f.disc[k]) {
      const Vec3<S> z = n - an * a;
      const S len = z.norm();
      if (!(len > kink)) return false;
      const S u1 = z.dot(e1) / len, u2 = z.dot(e2) / len, k2 = c / len;
      value += c * len;
      g[0] += c * u1;
      g[1] += c * u2;
      H[0] += k2 * (S(1) - a1 * a1 - u1 * u1);
      H[1] += k2 * (-a1 * a2 - u1 * u2);
      H[2] += k2 * (S(1) - a2 * a2 - u2 * u2);
    } else {
      const S s = an >= S(0) ? S(1) : S(-1);
      value += c * s * an;
      g[0] += c * s * a1;
      g[1] += c * s * a2;
    }
  }
  return true;
}

/// Least eigenvalue of the symmetric 2x2 matrix [h0 h1; h1 h2].
template <class S>
inline S least_eigenvalue(S h0, S h1, S h2) {
  const S m = (h0 + h2) / S(2), d = (h0 - h2) / S(2);
  return m - std::sqrt(d * d + h1 * h1);
}

/// The certificate of the file comment at unit n (any direction; it holds only near a local
/// minimiser): true and `out` set when some T of the halving sequence from 1 down to 1/8192 gives a
/// lower bound rho > 0. Kinks at n (|P n| or |a . n| within
/// 1e-9) enter as norms: a disc term's c |z0 + M y| >= c sigma |y| - c |z0| (sigma the least
/// singular value of M), an abs term's c |z0 + m . y| >= c |m . y| - c |z0|; with
/// psi(y) = g . y + y^T (Q - U I) y / 2 + the kinks' norms (g, Q of the smooth terms), the bound
/// is rho = U + min psi over |y| <= T - allowances, min psi bounded below by
///   no kink: -|g|^2 / (2 lambda), lambda > 0 the least eigenvalue of Q - U I;
///   one abs kink along m (basis e1 along m): psi minimised over y2 (needs q22 > 0) leaves
///       -g2^2 / (2 q22) + (g1 - q12 g2 / q22) y1 + |m| |y1| + s y1^2 / 2, s the Schur complement:
///       >= -g2^2 / (2 q22) when kappa = |m| - |g1 - q12 g2 / q22| > 0 and T <= 2 kappa / max(-s, 0);
///   a disc kink or two abs kinks: psi >= kappa |y| - mu |y|^2 / 2 >= 0 for T <= 2 kappa / mu,
///       kappa the least of the homogeneous part g . y + norms on the unit circle (> 0 needed),
///       mu = max(0, -lambda).
template <class S>
bool certify_at(const OverlapTerms<S>& f, const Vec3<S>& n, LocalCertificate<S>& out) {
  const S kink = S(1e-9);
  int abs_kink[kMaxOverlapTerms], nka = 0;
  S disc_kink = S(0);  // sum of c sigma over the disc kinks
  bool any_disc_kink = false;
  Vec3<S> e1 = Vec3<S>::Zero();
  for (int k = 0; k < f.n; ++k) {
    const Vec3<S>& a = f.axis[k];
    if (!f.disc[k] && std::abs(a.dot(n)) <= kink) {
      if (nka == 0) e1 = a - a.dot(n) * n;
      abs_kink[nka++] = k;
    }
  }
  if (nka > 2) return false;
  e1 = nka > 0 && e1.norm() > S(0) ? Vec3<S>(e1.normalized()) : any_orthogonal(n);
  const Vec3<S> e2 = n.cross(e1);
  S U = f.linear.dot(n), g[2] = {f.linear.dot(e1), f.linear.dot(e2)}, at_kinks = S(0);
  S m[2][2] = {{S(0), S(0)}, {S(0), S(0)}};
  S smooth_len[kMaxOverlapTerms], smooth_b[kMaxOverlapTerms][3];
  int nsd = 0;
  for (int k = 0, j = 0; k < f.n; ++k) {
    const Vec3<S>& a = f.axis[k];
    const S c = f.coef[k], an = a.dot(n), a1 = a.dot(e1), a2 = a.dot(e2);
    if (f.disc[k]) {
      const S len = (n - an * a).norm();
      U += c * len;
      if (len <= kink) {
        any_disc_kink = true;
        at_kinks += c * len;
        disc_kink += c * std::sqrt(std::max(S(1) - a1 * a1 - a2 * a2, S(0)));
      } else {
        const Vec3<S> z = n - an * a;
        const S u1 = z.dot(e1) / len, u2 = z.dot(e2) / len;
        g[0] += c * u1;
        g[1] += c * u2;
        // c M^T (I - u u^T) M, M = P [e1 e2], divided by len + T in the loop below
        smooth_len[nsd] = len;
        smooth_b[nsd][0] = c * (S(1) - a1 * a1 - u1 * u1);
        smooth_b[nsd][1] = c * (-a1 * a2 - u1 * u2);
        smooth_b[nsd][2] = c * (S(1) - a2 * a2 - u2 * u2);
        ++nsd;
      }
    } else if (j < nka && abs_kink[j] == k) {
      U += c * std::abs(an);
      at_kinks += c * std::abs(an);
      m[j][0] = c * a1;
      m[j][1] = c * a2;
      ++j;
    } else {
      const S sg = an >= S(0) ? S(1) : S(-1);  // c |a . w| >= c sg (a . w) for every w
      U += c * sg * an;
      g[0] += c * sg * a1;
      g[1] += c * sg * a2;
    }
  }
  const S rounding = S(64) * std::numeric_limits<S>::epsilon() * (f.magnitude + f.linear.norm()) + S(2) * at_kinks;
  const S gn = std::sqrt(g[0] * g[0] + g[1] * g[1]);
  // kappa of the homogeneous part (disc kinks or two abs kinks): the least on the unit circle
  S kappa = std::numeric_limits<S>::infinity();
  if (any_disc_kink) {
    kappa = disc_kink - gn;
  } else if (nka == 2) {
    const auto omega = [&](S y1, S y2) {
      return g[0] * y1 + g[1] * y2 + std::abs(m[0][0] * y1 + m[0][1] * y2) + std::abs(m[1][0] * y1 + m[1][1] * y2);
    };
    for (int j = 0; j < 2; ++j) {  // the breakpoints: y normal to m_j
      const S l = std::sqrt(m[j][0] * m[j][0] + m[j][1] * m[j][1]);
      if (!(l > S(0))) return false;
      kappa = std::min({kappa, omega(-m[j][1] / l, m[j][0] / l), omega(m[j][1] / l, -m[j][0] / l)});
    }
    for (const S s1 : {S(-1), S(1)})  // inside a sector the linear piece v . y is least at -v / |v|
      for (const S s2 : {S(-1), S(1)}) {
        const S v1 = g[0] + s1 * m[0][0] + s2 * m[1][0], v2 = g[1] + s1 * m[0][1] + s2 * m[1][1], vl = std::sqrt(v1 * v1 + v2 * v2);
        if (!(vl > S(0))) continue;
        const S y1 = -v1 / vl, y2 = -v2 / vl;
        if ((m[0][0] * y1 + m[0][1] * y2) * s1 >= S(0) && (m[1][0] * y1 + m[1][1] * y2) * s2 >= S(0)) kappa = std::min(kappa, omega(y1, y2));
      }
  }
  S T = S(1);
  // down to 1/8192: near a disc term's kink (|P n| of 1e-3 .. 1e-2) its curvature bound
  // c / (|P n| + T) needs T about |P n| to outweigh -U on deep poses
  for (int trial = 0; trial < 14; ++trial, T /= S(2)) {
    if (!(T > S(0))) return false;
    S q0 = -U, q1 = S(0), q2 = -U;  // Q - U I
    for (int k = 0; k < nsd; ++k) {
      const S w = S(1) / (smooth_len[k] + T);
      q0 += w * smooth_b[k][0];
      q1 += w * smooth_b[k][1];
      q2 += w * smooth_b[k][2];
    }
    const S lambda = least_eigenvalue(q0, q1, q2), mu = std::max(-lambda, S(0));
    S psi = S(0);
    bool good = false;
    if (any_disc_kink || nka == 2) {
      good = kappa > S(0) && (mu == S(0) || T <= S(2) * kappa / mu);
    } else if (nka == 1) {
      if (q2 > S(0)) {
        const S schur = q0 - q1 * q1 / q2, ml = std::abs(m[0][0]);
        const S k1 = ml - std::abs(g[0] - q1 * g[1] / q2);
        good = k1 > S(0) && (schur >= S(0) || T <= S(2) * k1 / -schur);
        psi = -g[1] * g[1] / (S(2) * q2);
      }
    } else if (lambda > S(0)) {
      good = true;
      psi = -gn * gn / (S(2) * lambda);
    }
    if (!good) continue;
    const S rho = U + psi - rounding;
    if (!(rho > S(0))) return false;
    out.ok = true;
    out.normal = n;
    out.upper = U;
    out.lower = rho;
    out.cap = std::atan(T);
    out.cos_cap = S(1) / std::sqrt(S(1) + T * T);
    return true;
  }
  return false;
}

/// Newton on the sphere from n (free: both tangent directions; with `constraint` a unit axis: on
/// the great circle normal to it, n projected onto it first); false at a kink of a disc term, an
/// indefinite Hessian or after kLocalNewtonSteps steps.
template <class S>
bool local_newton(const OverlapTerms<S>& f, Vec3<S>& n, const Vec3<S>* constraint, int& steps) {
  if (constraint) {
    n -= constraint->dot(n) * *constraint;
    if (!(n.norm() > S(1e-6))) return false;
    n.normalize();
  }
  for (int it = 0; it < kLocalNewtonSteps; ++it) {
    ++steps;
    const Vec3<S> e1 = constraint ? Vec3<S>(constraint->cross(n)) : any_orthogonal(n), e2 = n.cross(e1);
    S value, g[2], H[3];
    if (!overlap_model(f, n, e1, e2, value, g, H, S(1e-6))) return false;
    S y1, y2 = S(0);
    if (constraint) {
      const S h = H[0] - value;
      if (!(h > S(0))) return false;
      y1 = -g[0] / h;
    } else {
      const S h0 = H[0] - value, h1 = H[1], h2 = H[2] - value, det = h0 * h2 - h1 * h1;
      if (!(h0 > S(0) && det > S(0))) return false;
      y1 = -(h2 * g[0] - h1 * g[1]) / det;
      y2 = -(h0 * g[1] - h1 * g[0]) / det;
    }
    const S step = std::sqrt(y1 * y1 + y2 * y2);
    if (step <= S(1e-9)) return true;  // Newton's next step is below 1e-18
    // the model of a disc term c |P w| holds only within a fraction of |P n| (its kink, the axis,
    // is |P n| away; its Hessian c / |P n| changes by its own size over such a step): at most half
    // that far a step
    S reach = S(0.25);
    for (int k = 0; k < f.n; ++k)
      if (f.disc[k]) reach = std::min(reach, S(0.5) * (n - f.axis[k].dot(n) * f.axis[k]).norm());
    const S shrink = step > reach ? reach / step : S(1);
    n = (n + shrink * (y1 * e1 + y2 * e2)).normalized();
    if (constraint) {  // back onto the circle (rounding)
      n -= constraint->dot(n) * *constraint;
      n.normalize();
    }
  }
  return false;
}

/// The local certificate from a start direction n0 (EPA's best normal). The kinks near n0 (within
/// 0.1: a term's |P n0| or |a . n0|) are tried first as active constraints, cheapest first: a disc
/// kink gives n = +-a, two abs kinks n = +-(a1 x a2) / |a1 x a2|, one abs kink Newton on its great
/// circle; then Newton free of kinks. Each candidate is certified by certify_at; the first that
/// holds with n0 in its cap is returned, else the first that holds (a minimiser of another basin:
/// a cap's axis beside a minimiser on a ruling's circle 0.004 rad away).
template <class S>
LocalCertificate<S> local_certificate(const OverlapTerms<S>& f, const Vec3<S>& n0) {
  LocalCertificate<S> out, first;
  int steps = 0;
  // true when out holds n0 in its cap (then returned); else the first that held is kept
  const auto done = [&]() {
    if (out.normal.dot(n0) >= out.cos_cap) return true;
    if (!first.ok) first = out;
    out = LocalCertificate<S>();
    return false;
  };
  const S near = S(0.1);
  int abs_near[kMaxOverlapTerms], nan = 0;
  for (int k = 0; k < f.n; ++k) {
    const Vec3<S>& a = f.axis[k];
    if (f.disc[k]) {
      if ((n0 - a.dot(n0) * a).norm() < near) {
        const Vec3<S> c = a.dot(n0) >= S(0) ? a : Vec3<S>(-a);
        if (certify_at(f, c, out) && done()) return out;
      }
    } else if (std::abs(a.dot(n0)) < near) {
      abs_near[nan++] = k;
    }
  }
  for (int i = 0; i < nan; ++i)
    for (int j = i + 1; j < nan; ++j) {
      Vec3<S> c = f.axis[abs_near[i]].cross(f.axis[abs_near[j]]);
      if (!(c.norm() > S(1e-6))) continue;
      c.normalize();
      if (c.dot(n0) < S(0)) c = -c;
      if (certify_at(f, c, out) && done()) return out;
    }
  Vec3<S> n;
  for (int i = 0; i < nan; ++i) {
    n = n0;
    if (local_newton(f, n, &f.axis[abs_near[i]], steps) && certify_at(f, n, out) && done()) {
      out.newton_steps = steps;
      return out;
    }
  }
  n = n0;
  if (local_newton(f, n, static_cast<const Vec3<S>*>(nullptr), steps) && certify_at(f, n, out) && done()) {
    out.newton_steps = steps;
    return out;
  }
  if (first.ok) out = first;
  out.newton_steps = steps;
  return out;
}

/// The overlap of cylinder a (its frame) and cylinder b placed by R, t there.
template <class S>
OverlapTerms<S> cylinder_pair_terms(const Cylinder<S>& a, const Cylinder<S>& b, const Mat3<S>& R, const Vec3<S>& t) {
  OverlapTerms<S> f;
  f.add(Vec3<S>::UnitZ(), a.radius, true);
  f.add(Vec3<S>::UnitZ(), a.half_length, false);
  f.add(R.col(2), b.radius, true);
  f.add(R.col(2), b.half_length, false);
  f.linear = -t;
  return f;
}

/// Adds to f cone b's term h_B(-w) (b placed by R, t in f's frame) with the branch active along n:
/// h_B(-w) = -t . w + max(-h bz . w, h bz . w + r |P w|), its apex or its base rim; false, f's linear
/// part unset, when the two tie within 1e-6 of the cone's size (n a side normal: a ruling).
template <class S>
bool add_cone_branch_terms(const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f) {
  const Vec3<S> bz = R.col(2);
  const S bn = bz.dot(n), apex = -b.half_length * bn, rim = b.half_length * bn + b.radius * std::sqrt(std::max(S(1) - bn * bn, S(0)));
  if (!(std::abs(apex - rim) > S(1e-6) * (b.half_length + b.radius))) return false;
  f.linear = -t;
  if (apex > rim) {
    f.linear -= b.half_length * bz;
  } else {
    f.linear += b.half_length * bz;
    f.add(bz, b.radius, true);
  }
  f.magnitude += b.half_length;
  return true;
}

/// The overlap of cylinder a (its frame) and cone b placed by R, t there, with the cone's branch
/// active along n (add_cone_branch_terms; false on a ruling).
template <class S>
bool cylinder_cone_terms(const Cylinder<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n,
                         OverlapTerms<S>& f) {
  f = OverlapTerms<S>();
  f.add(Vec3<S>::UnitZ(), a.radius, true);
  f.add(Vec3<S>::UnitZ(), a.half_length, false);
  return add_cone_branch_terms(b, R, t, n, f);
}

/// The body inside cone b (placed by R, t in the terms' frame) along the ruling whose side normal
/// is nearest -n, as cylinder_cone_side_terms builds it, added to f: a disc term, an abs term and
/// a linear one (its support along -w); false when -n is along b's axis. The body spans the
/// fractions s0 < s1 of that ruling (0 at the base rim, 1 at the apex; 0 <= s0, s1 < 1): the disc
/// of radius R (1 - s1), tangent to b's side on the ruling, swept from s0 to s1.
template <class S>
bool add_cone_side_body(const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f, S s0 = S(0),
                        S s1 = S(0.5)) {
  const Vec3<S> v = -(R.transpose() * n);
  const S m = std::sqrt(v.x() * v.x() + v.y() * v.y());
  if (!(m > S(1e-9))) return false;
  const S rc = b.radius, hc = b.half_length, rho = rc * (S(1) - s1);
  const Vec3<S> e(v.x() / m, v.y() / m, S(0)), apex(S(0), S(0), hc);
  const Vec3<S> p = rc * e - Vec3<S>(S(0), S(0), hc), d = apex - p;
  const Vec3<S> c0 = (rc - rho) * e - Vec3<S>(S(0), S(0), hc);  // the disc's centre at s = 0
  const Vec3<S> centre = c0 + ((s0 + s1) / S(2)) * d, half = ((s1 - s0) / S(2)) * d;
  const S len = half.norm();
  f.add(R.col(2), rho, true);
  f.add(Vec3<S>(R * half / len), len, false);
  f.linear -= R * centre + t;
  f.magnitude += rc + hc;
  return true;
}

/// The overlap of cylinder a (its frame) and, for cone b placed by R, t there, a body inside b
/// touching b's side along the ruling whose side normal is nearest -n (the azimuth of -n in b's
/// frame): a disc tangent to b's side on that ruling, swept along it over the fractions [s0, s1]
/// of its length from the base rim (by default the disc of radius R/2 tangent to the base rim,
/// swept for half the ruling; a slanted cylinder: at each height its disc touches b's
/// cross-section from inside), whose support is a disc term, an abs term (the ruling) and a linear
/// one. Its overlap is <= the true one everywhere and equal along the side normals of that ruling;
/// the certificate needs the contact's point of the ruling strictly inside the span (the abs
/// term's kink then holds the minimum on the side normals); false when -n is along b's axis.
template <class S>
bool cylinder_cone_side_terms(const Cylinder<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n,
                              OverlapTerms<S>& f, S s0 = S(0), S s1 = S(0.5)) {
  f = OverlapTerms<S>();
  f.add(Vec3<S>::UnitZ(), a.radius, true);
  f.add(Vec3<S>::UnitZ(), a.half_length, false);
  return add_cone_side_body(b, R, t, n, f, s0, s1);
}

/// Where a cylinder or cone a (its frame) touches the side of cone b (placed by R, t there) along
/// n, as a fraction of b's ruling whose side normal is nearest -n (0 at its base rim point, 1 at
/// the apex; not clamped): the projection onto that ruling of a's support along n (a rim point or
/// a cone's apex), or, for a cylinder with n within `flat` of normal to its axis (its support a
/// whole ruling), of the point of its ruling nearest the line of b's. NaN when -n is along b's
/// axis.
template <class S, class A>
S cone_side_contact(const A& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, S flat = S(0.1)) {
  const Vec3<S> v = -(R.transpose() * n);
  const S m = std::sqrt(v.x() * v.x() + v.y() * v.y());
  if (!(m > S(1e-9))) return std::numeric_limits<S>::quiet_NaN();
  const S rc = b.radius, hc = b.half_length;
  const Vec3<S> p = Vec3<S>(rc * v.x() / m, rc * v.y() / m, -hc), d = Vec3<S>(S(0), S(0), hc) - p;  // b's ruling from s = 0 to 1
  const S dd = d.dot(d);
  const Vec3<S> xa = support(a, n);
  if constexpr (std::is_same_v<A, Cylinder<S>>) {
    if (std::abs(n.z()) < flat) {
      // a's ruling q0 + sigma u, sigma in [-h_a, h_a] (u a's axis in b's frame): its point nearest
      // the line of b's ruling
      const Vec3<S> q0 = R.transpose() * (Vec3<S>(xa.x(), xa.y(), S(0)) - t), u = R.row(2).transpose(), w = q0 - p;
      const S du = d.dot(u), dw = d.dot(w), uw = u.dot(w), den = dd - du * du;  // |u| = 1
      S sigma = den > S(1e-12) * dd ? ((dw - uw * du) / den) * du - uw : S(0);
      sigma = std::clamp(sigma, -a.half_length, a.half_length);
      return (dw + sigma * du) / dd;
    }
  }
  return (R.transpose() * (xa - t) - p).dot(d) / dd;
}

/// The upper end of the body inside a cone along a ruling (add_cone_side_body, from the base rim
/// point) for a contact at the fraction s of that ruling (cone_side_contact): 0.1 of the ruling
/// past it, so the contact lies strictly inside the body's span, and its disc, tangent at that
/// end, as large as that allows; at most 0.95.
template <class S>
S side_body_end(S s) {
  return std::min(std::clamp(s, S(0), S(1)) + S(0.1), S(0.95));
}

/// Whether a cylinder's support along w (pw = |P w|, P the projection on its xy plane) is smooth
/// across the directions cone_side_newton turns through (not its cap or a ruling: a kink), and
/// then the radius of its active disc term (its own radius).
template <class S>
bool side_support_disc(const Cylinder<S>& a, const Vec3<S>& w, S pw, S& disc) {
  if (!(pw > S(1e-6) && std::abs(w.z()) > S(1e-6))) return false;
  disc = a.radius;
  return true;
}

/// The same for a cone: not smooth where its base faces w or its apex and base rim tie (a side
/// ruling); the disc term is its base radius where the rim supports w, none (0) at its apex.
template <class S>
bool side_support_disc(const Cone<S>& a, const Vec3<S>& w, S pw, S& disc) {
  if (!(pw > S(1e-6))) return false;
  const S apex = a.half_length * w.z(), rim = a.radius * pw - a.half_length * w.z();
  if (!(std::abs(apex - rim) > S(1e-6) * (a.radius + a.half_length))) return false;
  disc = rim > apex ? a.radius : S(0);
  return true;
}

/// Cylinder or cone a (its frame) against cone b placed by R, t there, along b's side: the
/// directions w(phi) = -R m(phi), m(phi) b's outward side normal at azimuth phi, where the overlap
/// is h_A(w) - t . w + h r / L (b's support is its whole ruling there). Newton on phi from the
/// azimuth of -n (the derivatives from a's support: (s_A - t) . w' and w'^T H_A w' + (s_A - t) . w'',
/// H_A from a's active disc term, side_support_disc), the azimuth held as its cosine and sine and
/// turned by each step (convex/azimuth_turn.hpp); true with n the minimiser when it converges
/// (|step| <= 1e-10 within 16 steps) where a's support is smooth; false otherwise.
template <class A, class S>
bool cone_side_newton(const A& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, Vec3<S>& n) {
  const Vec3<S> v = -(R.transpose() * n);
  const S vxy = std::sqrt(v.x() * v.x() + v.y() * v.y());
  if (!(vxy > S(1e-9))) return false;
  S c = v.x() / vxy, s = v.y() / vxy;
  const S rc = b.radius, hc = b.half_length, L = std::sqrt(S(4) * hc * hc + rc * rc), k = S(2) * hc / L;
  for (int it = 0; it < 16; ++it) {
    const Vec3<S> w = -(R * Vec3<S>(k * c, k * s, rc / L)), w1 = -(R * Vec3<S>(-k * s, k * c, S(0))), w2 = -(R * Vec3<S>(-k * c, -k * s, S(0)));
    const S pw = std::sqrt(w.x() * w.x() + w.y() * w.y());
    S disc;
    if (!side_support_disc(a, w, pw, disc)) return false;
    const Vec3<S> arm = support(a, w) - t;
    const S perp = (w.x() * w1.y() - w.y() * w1.x()) / pw;  // w1's part normal to P w in a's xy plane
    const S g1 = arm.dot(w1), g2 = disc / pw * perp * perp + arm.dot(w2);
    if (!(g2 > S(0))) return false;
    const S step = std::clamp(-g1 / g2, S(-0.3), S(0.3));
    azimuth_turn(step, c, s);
    if (std::abs(step) <= S(1e-10)) {
      n = -(R * Vec3<S>(k * c, k * s, rc / L));
      return true;
    }
  }
  return false;
}

/// The local certificate of cylinder a (its frame) against the side of cone b placed by R, t
/// there, from a direction n near the contact (EPA's best normal): the minimiser along b's side
/// normals (cone_side_newton; where a's support is a ruling, n within 0.1 of normal to a's axis,
/// a kink Newton stops at: n itself), then local_certificate on the body inside b along that
/// ruling (cylinder_cone_side_terms) from its base rim point to side_body_end of the contact's
/// point of it (cone_side_contact). A lower
/// bound exact only where the body touches the contact: the caller checks the true overlap at its
/// normal (no certificate when none applies).
template <class S>
LocalCertificate<S> cylinder_cone_side_certificate(const Cylinder<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t,
                                                   const Vec3<S>& n) {
  Vec3<S> m = n;
  if (!cone_side_newton(a, b, R, t, m) && !(std::abs(n.z()) < S(0.1))) return LocalCertificate<S>();
  const S s = cone_side_contact(a, b, R, t, m);
  OverlapTerms<S> terms;
  if (!(s == s) || !cylinder_cone_side_terms(a, b, R, t, m, terms, S(0), side_body_end(s))) return LocalCertificate<S>();
  return local_certificate(terms, m);
}

}  // namespace impact::detail
