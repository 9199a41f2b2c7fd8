// SPDX-License-Identifier: MIT
/// \file
/// A lower bound of the penetration depth of a cylinder (or a cone) A and a convex set B from a few
/// points of B inside A, for the candidates of convex/cylinder_pair.hpp whose ball is cut: a point x of B
/// deep across one face of A (its cap or its side) but near another face, so that no ball about x
/// inside A reaches the depth.
///
/// For points p of B, f(n) = h_A(n) + h_B(-n) >= g_p(n) = h_A(n) - n . p, so the depth
/// min_n f(n) >= L(P) = min_n max_{p in P} g_p(n) (the depth of A against the hull of P). A
/// minimiser n0 of max_p g_p lies in the cell of some p (where p is least along n: n . p <= n . q
/// for every q in P); in the cell's interior it is a local minimum of g_p, on its boundary it is
/// normal to p - q for some q. For p inside the cylinder (radius r, half length h about z) the
/// local minima of g_p on the sphere are its three faces' normals (in a meridian plane g_p is
/// a cos(t) + b sin(t) between the side and a cap, with no interior minimum): the cap normals
/// +-z with h -+ p_z, and the side's radial direction through p with r - |p_xy| (any horizontal
/// direction when p is on the axis). On the great circle normal to v = q - p, g_p is the distance
/// of p to the supporting lines of A's shadow along v (the same for every point of the line
/// through p and q; the bound takes the best of p, q and their midpoint): an ellipse with
/// semi-axes r |v_z| and r swept by the axis' shadow (half length h sqrt(1 - v_z^2)), so it is the
/// distance of p's shadow to that shadow's boundary, bounded below through the straight edges and
/// the distance to an ellipse (Newton on the nearest point's multiplier, from the side where the
/// distance it gives is an upper bound, then a step past the root, checked). So
///   L(P) >= min( the faces' values of each p whose normal lies in p's cell,
///                over pairs p, q: that shadow distance of p or of q, the larger ).
/// The points are x and, for each face of A whose value at x is below the depth sought, B's point
/// deepest across that face (its support along minus the face's normal: there g_y equals f).
///
/// The same bound with a cone as the container (cone_points_lower, cone_points_bound) is below.
///
/// Numerical contract: CONSERVATIVE up to rounding: the bound is lowered by an allowance of 1024
/// ulps of the pair's size. Thread safety: pure functions.
#pragma once

#include "impact/convex/shapes.hpp"
#include "impact/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// A lower bound of the distance from (u, v), u, v >= 0, inside the ellipse with semi-axes a along
/// the first axis and b >= a along the second, to its boundary curve. The nearest point is
/// (a^2 u / (t + a^2), b^2 v / (t + b^2)) at the root t* in (-a^2, 0] of the decreasing convex
/// F(t) = (a u / (t + a^2))^2 + (b v / (t + b^2))^2 - 1, and the distance there,
/// d(t) = -t sqrt((u / (t + a^2))^2 + (v / (t + b^2))^2), decreases with t: Newton from
/// -a^2 + a u (where F >= 0) stays left of t*, and any t >= t* (F(t) <= 0) gives d(t) <= the
/// distance. On an axis: v = 0 gives a - u; u = 0 gives a sqrt(1 - v^2 / (b^2 - a^2)) while
/// v <= b - a^2 / b, else b - v; near an axis the distance moves by at most the offset.
template <class S>
S ellipse_inner_distance(S u, S v, S a, S b) {
  const S w = b * b - a * a;
  const S on_major = w > S(0) && v * b <= w ? a * std::sqrt(std::max(S(1) - v * v / w, S(0))) : b - v;  // at (0, v)
  S best = std::max(on_major - u, a - u - v);                                                          // and (u, 0)
  if (!(u > S(1e-9) * b && v > S(1e-9) * b && a > S(1e-9) * b)) return best;
  const S a2 = a * a, b2 = b * b;
  const auto F = [&](S t) {
    const S x = a * u / (t + a2), y = b * v / (t + b2);
    return x * x + y * y - S(1);
  };
  // t* in [lo, hi]: F(lo) >= 0 (its first term alone is 1), F(hi) <= 0 (F(0) <= 0 inside, and at
  // -a^2 + sqrt(a^2 u^2 + b^2 v^2) the sum is at most 1)
  S lo = -a2 + a * u, hi = std::min(S(0), -a2 + std::sqrt(a2 * u * u + b2 * v * v));
  for (int it = 0; it < 64 && lo < hi; ++it) {
    const S da = lo + a2, db = lo + b2, x = a * u / da, y = b * v / db;
    const S f = x * x + y * y - S(1), df = -S(2) * (x * x / da + y * y / db);
    if (!(f > S(0) && df < S(0))) break;
    const S step = -f / df;
    const S t = lo + step < hi ? lo + step : (lo + hi) / S(2);
    if (F(t) > S(0)) {
      lo = t;
    } else {
      hi = t;
      break;
    }
    if (step <= S(1e-12) * a2) {  // converged from the left: a point just past the root
      const S past = std::min(lo + S(4) * step + S(1e-14) * a2, hi);
      if (F(past) <= S(0)) hi = past;
      break;
    }
  }
  if (!(F(hi) <= S(0))) return best;
  const S da = hi + a2, db = hi + b2;
  return std::max(best, -hi * std::sqrt(u * u / (da * da) + v * v / (db * db)));
}

/// A lower bound of the distance from (q1, q2) to the boundary of the ellipse with semi-axes a
/// along the first axis and b >= a along the second swept along the first axis over [-hs, hs]
/// (its Minkowski sum with that segment); -infinity when the point is not shown inside (a finite
/// negative value would not bound the signed distance of a point outside). By symmetry the nearest boundary point of a point of the first quadrant lies on
/// the straight edge at b (distance >= b - q2) or on the end arc about (hs, 0): at least the
/// distance to that ellipse's whole curve when inside it, and left of its centre a bound from the
/// arc's parametrisation (below).
template <class S>
S swept_ellipse_inner_distance(S q1, S q2, S a, S b, S hs) {
  q1 = std::abs(q1);
  q2 = std::abs(q2);
  const S edge = b - q2, u = q1 - hs;
  if (!(edge >= S(0))) return -std::numeric_limits<S>::infinity();  // outside
  const bool in_end = a > S(1e-9) * b && (u / a) * (u / a) + (q2 / b) * (q2 / b) <= S(1);
  S arc;
  if (!(a > S(1e-9) * b)) {
    arc = u <= S(0) ? -u : -std::numeric_limits<S>::infinity();  // a rectangle: the end segment at hs
  } else if (u > S(0)) {
    arc = in_end ? ellipse_inner_distance(u, q2, a, b) : -std::numeric_limits<S>::infinity();
  } else {
    // left of the arc's centre by d = -u: to an arc point (hs + a cos t, b sin t), cos t >= 0, the
    // squared distance is Q(s) + 2 a d sqrt(1 - s^2) + d^2 (s = sin t, Q the squared distance from
    // (hs, q2)), and sqrt(1 - s^2) >= 1 - s^2 leaves a quadratic in s on [-1, 1]
    const S d = -u, A = b * b - a * a - S(2) * a * d, B = b * q2, C = a * a + q2 * q2 + S(2) * a * d;
    const S m = A > S(0) && B <= A ? C - B * B / A : A - S(2) * B + C;
    arc = std::sqrt(std::max(m, S(0)) + d * d);
    if (in_end) arc = std::max(arc, ellipse_inner_distance(d, q2, a, b));
  }
  return std::min(edge, arc);
}

/// The least over unit n normal to v (not zero) of h_A(n) - n . p for cylinder a and p inside it,
/// bounded from below by the shadow of a along v (file comment).
template <class S>
S cylinder_shadow_distance(const Cylinder<S>& a, const Vec3<S>& p, const Vec3<S>& v) {
  const Vec3<S> vn = v.normalized();
  const S c = vn.z(), s = std::sqrt(std::max(S(1) - c * c, S(0)));
  const S r = a.radius, ac = r * std::abs(c);
  if (!(s > S(1e-6))) {  // nearly along the axis: the disc of radius r |c| inside the shadow
    const Vec3<S> q = p - p.dot(vn) * vn;
    return ac - q.norm();
  }
  const Vec3<S> e1 = (Vec3<S>::UnitZ() - c * vn) / s, e2 = vn.cross(e1);
  return swept_ellipse_inner_distance(p.dot(e1), p.dot(e2), ac, r, a.half_length * s);
}

/// The points of a several-points bound (at most four), with each point within 1e-9 of `size` of
/// an earlier one dropped (the bound of fewer points is lower, so still valid), and in_cell(i, n):
/// whether point i is the deepest of them along the face normal n, so that n's face value at it
/// counts (generous: a face kept on a tie only lowers the bound).
template <class S>
struct DistinctPoints {
  Vec3<S> P[4];
  int m = 0;
  S size;
  DistinctPoints(const Vec3<S>* pts, int np, S size_) : size(size_) {
    for (int i = 0; i < np && i < 4; ++i) {
      bool dup = false;
      for (int j = 0; j < m; ++j) dup = dup || (pts[i] - P[j]).norm() <= S(1e-9) * size;
      if (!dup) P[m++] = pts[i];
    }
  }
  bool in_cell(int i, const Vec3<S>& n) const {
    for (int j = 0; j < m; ++j)
      if (j != i && n.dot(P[i]) > n.dot(P[j]) + S(1e-9) * size) return false;
    return true;
  }
};

/// L(P) of the file comment for the np points P of b (cylinder a's frame, np <= 4, inside a or
/// not; -infinity for a non-finite point, or as soon as the bound is seen to fall below `want`).
/// Points within 1e-9 of the size of an earlier one are dropped (the bound
/// of fewer points is lower, so still valid).
template <class S>
S cylinder_points_lower(const Cylinder<S>& a, const Vec3<S>* pts, int np, S want = -std::numeric_limits<S>::infinity()) {
  const S size = a.radius + a.half_length;
  const DistinctPoints<S> q(pts, np, size);
  S L = std::numeric_limits<S>::infinity();
  for (int i = 0; i < q.m; ++i) {
    const Vec3<S>& p = q.P[i];
    const S rxy = std::sqrt(p.x() * p.x() + p.y() * p.y());
    const S side = a.radius - rxy, top = a.half_length - p.z(), bottom = a.half_length + p.z();
    if (!(std::isfinite(side) && std::isfinite(p.z()))) return -std::numeric_limits<S>::infinity();
    if (q.in_cell(i, Vec3<S>::UnitZ())) L = std::min(L, top);
    if (q.in_cell(i, Vec3<S>(-Vec3<S>::UnitZ()))) L = std::min(L, bottom);
    const Vec3<S> u = rxy > S(1e-9) * size ? Vec3<S>(p.x() / rxy, p.y() / rxy, S(0)) : Vec3<S>(Vec3<S>::UnitX());
    if (!(rxy > S(1e-9) * size) || q.in_cell(i, u)) L = std::min(L, side);
    const S cap = std::min(top, bottom);
    if (side < S(0) && cap < S(0)) {  // beyond a rim: the direction from the rim to p, -dist(p, a)
      const Vec3<S> n = (-side * u + Vec3<S>(S(0), S(0), p.z() >= S(0) ? -cap : cap)).normalized();
      if (q.in_cell(i, n)) L = std::min(L, -std::sqrt(side * side + cap * cap));
    }
  }
  const S allowance = S(1024) * std::numeric_limits<S>::epsilon() * (size + (q.m > 0 ? q.P[0].norm() : S(0)));
  if (!(L - allowance >= want)) return -std::numeric_limits<S>::infinity();
  for (int i = 0; i < q.m; ++i)
    for (int j = i + 1; j < q.m; ++j) {  // on the great circle normal to v every point of the line through them ties
      const Vec3<S> v = q.P[j] - q.P[i], mid = (q.P[i] + q.P[j]) / S(2);
      S on_circle = cylinder_shadow_distance(a, q.P[i], v);  // the best of three, each only while it may lower L
      if (on_circle < L) on_circle = std::max(on_circle, cylinder_shadow_distance(a, mid, v));
      if (on_circle < L) on_circle = std::max(on_circle, cylinder_shadow_distance(a, q.P[j], v));
      L = std::min(L, on_circle);
      if (!(L - allowance >= want)) return -std::numeric_limits<S>::infinity();
    }
  return q.m > 0 ? L - allowance : -std::numeric_limits<S>::infinity();
}

/// The bound of the file comment for a candidate of depth `depth` whose point x of B (a's frame)
/// lies inside cylinder a: x and B's points deepest across each face of a whose value at x is
/// below depth - tolerance (`support_b(d)`: B's support along d in a's frame; calls counts them).
template <class S, class SupportB>
S cylinder_points_bound(const Cylinder<S>& a, const Vec3<S>& x, S depth, S tolerance, const SupportB& support_b, int& calls) {
  const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
  Vec3<S> pts[4] = {x, x, x, x};
  int np = 1;
  const S want = depth - tolerance;
  if (a.half_length - x.z() < want) pts[np++] = support_b(Vec3<S>(-Vec3<S>::UnitZ()));
  if (a.half_length + x.z() < want) pts[np++] = support_b(Vec3<S>(Vec3<S>::UnitZ()));
  if (a.radius - rxy < want && rxy > S(0)) pts[np++] = support_b(Vec3<S>(-x.x() / rxy, -x.y() / rxy, S(0)));
  calls += np - 1;
  if (np == 1) return -std::numeric_limits<S>::infinity();  // the ball about x was enough (or x outside)
  return cylinder_points_lower(a, pts, np, want);
}

/// The same bound with a cone c as the container (base disc of radius R at z = -h, apex (0, 0, h);
/// its outward side normal at azimuth u is m(u) = (2h u + R z^) / sqrt(4h^2 + R^2)): for p inside,
/// the local minima of g_p(n) = h_C(n) - n . p are the base normal -z (value h + p_z) and the side
/// normal at p's own azimuth (p's distance to that tangent plane; along the circle of side normals
/// g_p is least there, in the apex's and the rim's regions g_p has no interior minimum of a
/// non-negative value); for p outside also -dist(p, C) along the direction from C's nearest point.
/// On the great circle normal to v the value is the distance of p's shadow to the boundary of C's
/// shadow along v: the hull of the base disc's ellipse (semi-axes R |v_z| along the axis' shadow
/// and R across it) and the apex's point, bounded below through the two tangents from the apex to
/// the ellipse and the ellipse's arc (the whole ellipse curve when inside it, else the chord
/// between the tangent points, beyond which the arc does not reach).

/// The least over unit n normal to v (not zero) of h_C(n) - n . p for cone c and p, bounded from
/// below as the comment above says; -infinity when p's shadow is not shown inside c's.
template <class S>
S cone_shadow_distance(const Cone<S>& c, const Vec3<S>& p, const Vec3<S>& v) {
  const Vec3<S> vn = v.normalized();
  const S vz = vn.z(), s = std::sqrt(std::max(S(1) - vz * vz, S(0)));
  const S R = c.radius, h = c.half_length, a = R * std::abs(vz);
  const S none = -std::numeric_limits<S>::infinity();
  if (!(s > S(1e-6))) {  // nearly along the axis: the disc of radius R |v_z| about the base centre's shadow
    const Vec3<S> q = p + Vec3<S>(S(0), S(0), h);
    return a - (q - q.dot(vn) * vn).norm();
  }
  const Vec3<S> e1 = (Vec3<S>::UnitZ() - vz * vn) / s, e2 = vn.cross(e1);
  // from the ellipse's centre (the base centre's shadow): along the axis' shadow u, across it w
  const S u = p.dot(e1) + h * s, w = std::abs(p.dot(e2)), apex = S(2) * h * s;
  const bool in_ellipse = a > S(0) && (u / a) * (u / a) + (w / R) * (w / R) <= S(1);
  if (apex <= a) return in_ellipse ? ellipse_inner_distance(std::abs(u), w, a, R) : none;  // the shadow is the ellipse
  // the tangents from (apex, 0) touch the ellipse at (a^2 / apex, +-R sqrt(1 - a^2 / apex^2))
  const S xt = a * a / apex, yt = R * std::sqrt(std::max(S(1) - (a / apex) * (a / apex), S(0)));
  const S len = std::sqrt(yt * yt + (apex - xt) * (apex - xt));
  const S line = (yt * (xt - u) + (apex - xt) * (yt - w)) / len;  // below the upper tangent (outward normal (yt, apex - xt))
  if (!(line >= S(0))) return none;
  S arc = u > xt ? u - xt : none;
  if (in_ellipse) arc = std::max(arc, ellipse_inner_distance(std::abs(u), w, a, R));
  return std::min(line, arc);
}

/// L(P) of the file comment for the np points P (cone c's frame, np <= 4, inside c or not;
/// -infinity for a non-finite point, or as soon as the bound is seen to fall below `want`).
template <class S>
S cone_points_lower(const Cone<S>& c, const Vec3<S>* pts, int np, S want = -std::numeric_limits<S>::infinity()) {
  const S R = c.radius, h = c.half_length, size = R + h, len = std::sqrt(S(4) * h * h + R * R);
  const DistinctPoints<S> q(pts, np, size);
  S L = std::numeric_limits<S>::infinity();
  for (int i = 0; i < q.m; ++i) {
    const Vec3<S>& p = q.P[i];
    const S rxy = std::sqrt(p.x() * p.x() + p.y() * p.y());
    const S base = h + p.z(), side = (R * (h - p.z()) - S(2) * h * rxy) / len;
    if (!(std::isfinite(side) && std::isfinite(base))) return -std::numeric_limits<S>::infinity();
    if (q.in_cell(i, Vec3<S>(-Vec3<S>::UnitZ()))) L = std::min(L, base);
    const bool on_axis = !(rxy > S(1e-9) * size);
    const S ux = on_axis ? S(1) : p.x() / rxy, uy = on_axis ? S(0) : p.y() / rxy;
    if (on_axis || q.in_cell(i, Vec3<S>(S(2) * h * ux / len, S(2) * h * uy / len, R / len))) L = std::min(L, side);
    if (side < S(0) || base < S(0)) {  // outside: -dist(p, C) along the direction from C's nearest point
      // in p's meridian half-plane (rho, z): the nearer of the base segment and the side segment
      const S qb = std::clamp(rxy, S(0), R);
      const S ts = std::clamp(((rxy - R) * -R + (p.z() + h) * (S(2) * h)) / (len * len), S(0), S(1));
      const S qs_rho = R - ts * R, qs_z = -h + S(2) * h * ts;
      const S db = std::hypot(rxy - qb, p.z() + h), ds = std::hypot(rxy - qs_rho, p.z() - qs_z);
      const S q_rho = db <= ds ? qb : qs_rho, q_z = db <= ds ? -h : qs_z, d = std::min(db, ds);
      const Vec3<S> n = Vec3<S>(p.x() - q_rho * ux, p.y() - q_rho * uy, p.z() - q_z) / d;
      if (!(d > S(0)) || q.in_cell(i, n)) L = std::min(L, -d);
    }
  }
  const S allowance = S(1024) * std::numeric_limits<S>::epsilon() * (size + (q.m > 0 ? q.P[0].norm() : S(0)));
  if (!(L - allowance >= want)) return -std::numeric_limits<S>::infinity();
  for (int i = 0; i < q.m; ++i)
    for (int j = i + 1; j < q.m; ++j) {  // on the great circle normal to v every point of the line through them ties
      L = std::min(L, cone_shadow_distance(c, Vec3<S>((q.P[i] + q.P[j]) / S(2)), Vec3<S>(q.P[j] - q.P[i])));
      if (!(L - allowance >= want)) return -std::numeric_limits<S>::infinity();
    }
  return q.m > 0 ? L - allowance : -std::numeric_limits<S>::infinity();
}

/// The bound for a candidate of depth `depth` whose point x of the other shape (c's frame) lies
/// inside cone c: x and the other shape's points deepest across each face of c whose value at x
/// is below depth - tolerance (`support_other(d)`: its support along d in c's frame; calls counts
/// them): across the base (its support along +z) and the side at x's azimuth (along minus that
/// side normal).
template <class S, class SupportOther>
S cone_points_bound(const Cone<S>& c, const Vec3<S>& x, S depth, S tolerance, const SupportOther& support_other, int& calls) {
  const S R = c.radius, h = c.half_length, len = std::sqrt(S(4) * h * h + R * R);
  const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
  Vec3<S> pts[3] = {x, x, x};
  int np = 1;
  const S want = depth - tolerance;
  if (h + x.z() < want) pts[np++] = support_other(Vec3<S>(Vec3<S>::UnitZ()));
  if ((R * (h - x.z()) - S(2) * h * rxy) / len < want && rxy > S(0))
    pts[np++] = support_other(Vec3<S>(-S(2) * h * x.x() / (rxy * len), -S(2) * h * x.y() / (rxy * len), -R / len));
  calls += np - 1;
  if (np == 1) return -std::numeric_limits<S>::infinity();  // the ball about x was enough (or x outside)
  return cone_points_lower(c, pts, np, want);
}

}  // namespace impact::detail
