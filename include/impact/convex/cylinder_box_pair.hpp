// SPDX-License-Identifier: MIT
/// \file
/// Cylinder against box (the boolean of convex/query.hpp, the penetration of
/// convex/certified_pair.hpp), in the cylinder's frame (its axis z, its centre the origin; the box
/// placed by R, t there, half extents e):
///
/// Separating tests. The cylinder's extent along a unit u is h |u_z| + r |P_z u| about 0, the box's
/// sum_i e_i |R_i . u| about u . t; a plane normal to u separates them when the two intervals are
/// apart. cylinder_box_apart tries the box's three axes, the cylinder's axis and the three
/// directions normal to the axis and to a box axis (a box edge against the cylinder's side), each
/// in closed form with at most one square root.
///
/// Boolean test (cylinder_box_intersect): the line between the centres, the separating tests above,
/// a point of both (either centre, the cylinder's axis point nearest the box's centre, the box's
/// point nearest that), else GJK stopped as soon as it decides, as convex/cylinder_intersect.hpp does
/// for two cylinders.
///
/// Penetration candidates (cylinder_box_contact), built as those of convex/cone_box_pair.hpp: with
/// f(n) = h_A(n) + h_B(-n) = h |n_z| + r |P_z n| - n . t + sum_i e_i |R_i . n|, the overlap along a
/// unit n (the depth is min_n f), each candidate gives the upper bound f(n) at its direction and a
/// lower bound rho from a point x of one shape inside the other (the ball of radius rho about x,
/// x's distance to that shape's boundary, lies inside it, so every separating translation is at
/// least rho long):
///   a face of the box against the cylinder's deepest point across it (a rim point, or a ruling's
///       or cap's point), n the face's inward normal, the ball inside the box;
///   a cap of the cylinder against the box's deepest corner across it, n the cap's normal;
///   a corner of the box inside the cylinder pushed out through the nearest of its side and caps;
///   an edge of the box across the cylinder's side: n normal to the axis and to the edge, x the
///       edge's point at n's azimuth (where the edge crosses the ruling), the ball inside the
///       cylinder.
/// Where one of them is the contact the two bounds meet up to rounding; when the best upper and
/// lower bounds are within the tolerance the answer is certified as EPA's is (depth = the upper
/// bound, depth_gap = upper - lower); otherwise (a rim against an edge, a contact whose ball is cut
/// by another face) the caller runs EPA, which stops early by the local certificate of
/// convex/local_certificate.hpp on cylinder_box_terms (exact everywhere: the overlap has no
/// branches).
///
/// On the bench's 2000 cylinder–box poses (zoo shapes): the separating planes end 1,280 of the 1,306
/// separated poses; the candidates certify 241 of the 694 intersecting (run before GJK: their
/// positive lower bound proves the intersection). Of the 453 left to EPA, classed by the features
/// at its normal: a box face against a rim point 182 (the face candidate's upper bound is the depth
/// on 172, its ball cut by a neighbouring face), an edge against a rim 127 (no candidate), an edge
/// across the side 115 (the upper bound right on 114, the ball cut by a cap), a corner against a cap
/// 19 or the side 10. A lower bound from the box against the hull of 5 supports of the cylinder
/// about the candidate's normal (exact by the hull's separating axes) certified 124 of them but
/// cost more than EPA spent on them (10.8M -> 11.5M instructions over the 2000 poses): not kept.
///
/// Numerical contract: separating tests and the boolean's proving points EXACT up to rounding
/// (margins of a few ulps of the size: touching counts as intersecting); GJK as gjk_distance.
/// Candidates APPROXIMATE as EPA's: depth is f(normal) (an upper bound up to rounding),
/// depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// The overlap of cylinder a (its frame) and box b placed by R, t there at unit n (closed form).
template <class S>
S cylinder_box_overlap(const Cylinder<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n) {
  const Vec3<S> m = R.transpose() * n;
  return a.half_length * std::abs(n.z()) + a.radius * std::sqrt(std::max(n.x() * n.x() + n.y() * n.y(), S(0))) - n.dot(t) +
         b.half.x() * std::abs(m.x()) + b.half.y() * std::abs(m.y()) + b.half.z() * std::abs(m.z());
}

/// Whether a plane normal to one of the seven directions of the file comment separates cylinder a
/// (its frame) and box b (placed by R, t there) by more than `margin`. Exact up to rounding.
template <class S>
bool cylinder_box_apart(const Cylinder<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, S margin) {
  const S r = a.radius, h = a.half_length;
  // the box's axes: the cylinder's half extent along R_i against e_i
  for (int i = 0; i < 3; ++i) {
    const Vec3<S> u = R.col(i);
    const S reach = h * std::abs(u.z()) + r * std::sqrt(std::max(S(1) - u.z() * u.z(), S(0)));
    if (std::abs(u.dot(t)) > reach + b.half[i] + margin) return true;
  }
  // the cylinder's axis: the box's half extent along z is sum_i e_i |R_zi|
  const S ez = b.half.x() * std::abs(R(2, 0)) + b.half.y() * std::abs(R(2, 1)) + b.half.z() * std::abs(R(2, 2));
  if (std::abs(t.z()) > h + ez + margin) return true;
  // normal to the axis and to box axis i: u = (R_i,y, -R_i,x, 0) / |.|, the cylinder's half extent r
  for (int i = 0; i < 3; ++i) {
    const S ux = R(1, i), uy = -R(0, i), m2 = ux * ux + uy * uy;
    if (!(m2 > S(1e-12))) continue;
    const S len = std::sqrt(m2);
    S reach = S(0);
    for (int j = 0; j < 3; ++j)
      if (j != i) reach += b.half[j] * std::abs(ux * R(0, j) + uy * R(1, j));
    if (std::abs(ux * t.x() + uy * t.y()) > (r + margin) * len + reach) return true;
  }
  return false;
}

/// Whether point y (in box b's frame) lies in b (boundary included).
template <class S>
inline bool point_in_box(const Box<S>& b, const Vec3<S>& y) {
  return std::abs(y.x()) <= b.half.x() && std::abs(y.y()) <= b.half.y() && std::abs(y.z()) <= b.half.z();
}

/// Whether cylinder a (its frame) and box b (placed by R, t there) touch or overlap, by the tests
/// of the file comment; `scale` the larger shape's size, `tolerance` GJK's (absolute),
/// limit_reached set when GJK's iteration bound decided.
template <class S>
bool cylinder_box_intersect(const Cylinder<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, S scale, S tolerance,
                            int max_iterations, bool& limit_reached) {
  limit_reached = false;
  const S margin = std::numeric_limits<S>::epsilon() * S(16) * scale;
  // the line between the centres
  const S len = t.norm();
  if (len > S(0) && cylinder_box_overlap(a, b, R, t, Vec3<S>(t / len)) < -margin) return false;
  const auto in_a = [&](const Vec3<S>& x) {
    return std::abs(x.z()) <= a.half_length && x.x() * x.x() + x.y() * x.y() <= a.radius * a.radius;
  };
  const auto in_b = [&](const Vec3<S>& x) { return point_in_box(b, Vec3<S>(R.transpose() * (x - t))); };
  // a centre inside the other, the axis point nearest the box's centre, the box's point nearest it
  const Vec3<S> p(S(0), S(0), std::clamp(t.z(), -a.half_length, a.half_length));
  if (in_a(t) || in_b(p)) return true;
  if (cylinder_box_apart(a, b, R, t, margin)) return false;
  {
    Vec3<S> y = R.transpose() * (p - t);
    for (int i = 0; i < 3; ++i) y[i] = std::clamp(y[i], -b.half[i], b.half[i]);
    if (in_a(Vec3<S>(R * y + t))) return true;
  }
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) {
    const Vec3<S> m = R.transpose() * d;
    Vec3<S> x = t;
    for (int i = 0; i < 3; ++i) x += (m[i] >= S(0) ? b.half[i] : -b.half[i]) * R.col(i);
    return x;
  };
  const ConvexDistance<S> d = gjk_distance<S>(sa, sb, Vec3<S>(-t), tolerance, max_iterations, tolerance);
  limit_reached = d.limit_reached;
  return d.intersecting;
}

/// The overlap of cylinder a (its frame) and box b placed by R, t there as the terms of
/// convex/local_certificate.hpp: a disc and an abs term about z, the box's three abs terms.
template <class S>
OverlapTerms<S> cylinder_box_terms(const Cylinder<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t) {
  OverlapTerms<S> f;
  f.add(Vec3<S>::UnitZ(), a.radius, true);
  f.add(Vec3<S>::UnitZ(), a.half_length, false);
  add_box_terms(b, R, t, f);
  return f;
}

/// The certified contact of cylinder a and box b when one of the candidates of the file comment
/// decides it within `tolerance`, in a's frame (b placed by R, t there): true and `out` set
/// (normal from a towards b, depth, depth_gap, the deciding point (the caller moves it onto the
/// plane midway between the supporting planes), iterations counts the overlap evaluations); else
/// false, with out.normal and out.depth the best candidate's (depth infinite when none applied).
/// A separated pair is never certified (a lower bound needs a point of one inside the other).
template <class S>
bool cylinder_box_contact(const Cylinder<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, S tolerance,
                          ConvexContact<S>& out) {
  const Vec3<S> hc[3] = {Vec3<S>(b.half.x() * R.col(0)), Vec3<S>(b.half.y() * R.col(1)), Vec3<S>(b.half.z() * R.col(2))};
  const auto overlap = [&](const Vec3<S>& n) { return cylinder_box_overlap(a, b, R, t, n); };
  CandidateBounds<S> k;
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  // the box's faces: the cylinder's deepest point x across each (support(a, s R_i), its rim
  // point's xy part shared by both signs: one square root per axis), in the box's frame y (the
  // overlap along the face's inward normal s R_i is e_i + s y_i; x's ball the least of the gaps)
  const S r = a.radius, h = a.half_length;
  for (int i = 0; i < 3; ++i) {
    const Vec3<S> c = R.col(i);
    const S cxy = std::sqrt(c.x() * c.x() + c.y() * c.y());
    const bool off_axis = cxy > S(0);
    const S q = off_axis ? r / cxy : S(0);
    for (const S s : {S(1), S(-1)}) {
      const Vec3<S> x(off_axis ? s * c.x() * q : r, off_axis ? s * c.y() * q : S(0), s * c.z() >= S(0) ? h : -h);
      const Vec3<S> y = R.transpose() * (x - t);
      const S rho = std::min(std::min(b.half.x() - std::abs(y.x()), b.half.y() - std::abs(y.y())), b.half.z() - std::abs(y.z()));
      if (rho > S(0)) k.offer(Vec3<S>(s * c), b.half[i] + s * y[i], x, rho);
    }
  }
  if (decided()) return k.finish(tolerance, out);
  // the cylinder's caps: the box's deepest corner across each (the overlap along s z is
  // h - s t_z + sum_i e_i |R_zi|)
  {
    const S ez = b.half.x() * std::abs(R(2, 0)) + b.half.y() * std::abs(R(2, 1)) + b.half.z() * std::abs(R(2, 2));
    for (const S s : {S(1), S(-1)}) {
      Vec3<S> x = t;
      for (int i = 0; i < 3; ++i) x += (s * R(2, i) > S(0)) ? Vec3<S>(-hc[i]) : hc[i];
      const InsideBall<S> ball = inside_ball(a, x);
      if (ball.rho > S(0)) k.offer(Vec3<S>(S(0), S(0), s), a.half_length - s * t.z() + ez, x, ball.rho);
    }
  }
  if (decided()) return k.finish(tolerance, out);
  // the box's corners inside the cylinder, pushed out through its nearest side or cap
  for (int v = 0; v < 8; ++v) {
    const Vec3<S> x = t + ((v & 1) ? hc[0] : Vec3<S>(-hc[0])) + ((v & 2) ? hc[1] : Vec3<S>(-hc[1])) + ((v & 4) ? hc[2] : Vec3<S>(-hc[2]));
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) {
      const Vec3<S> n = -ball.push;
      k.offer(n, overlap(n), x, ball.rho);
    }
  }
  if (decided()) return k.finish(tolerance, out);
  // an edge of the box across the cylinder's side: n normal to the axis and to the edge (both
  // signs), the edge the box's deepest along -n, x its point where its xy projection is along n
  // (box_edge_at_azimuth)
  for (int i = 0; i < 3; ++i) {
    const S ex = R(0, i), ey = R(1, i), m2 = ex * ex + ey * ey;
    if (!(m2 > S(1e-12))) continue;
    const S inv = S(1) / std::sqrt(m2);
    for (const S sign : {S(1), S(-1)}) {
      const Vec3<S> n(sign * ey * inv, -sign * ex * inv, S(0));
      Vec3<S> x;
      if (!box_edge_at_azimuth(R, t, hc, i, n, n.x(), n.y(), x)) continue;
      const InsideBall<S> ball = inside_ball(a, x);
      if (ball.rho > S(0)) {  // the overlap along n normal to the axis: r - n . t + the box's abs terms
        const Vec3<S> m = R.transpose() * n;
        k.offer(n, r - n.dot(t) + b.half.x() * std::abs(m.x()) + b.half.y() * std::abs(m.y()) + b.half.z() * std::abs(m.z()), x, ball.rho);
      }
    }
  }
  return k.finish(tolerance, out);
}

}  // namespace impact::detail
