// SPDX-License-Identifier: MIT
/// \file
/// A certified shortcut for the penetration of an intersecting cone and box (convex/certified_pair.hpp
/// runs it after the separating planes, before GJK and EPA), built as convex/cylinder_pair.hpp is: with f(n) = h_A(n) + h_B(-n), the
/// overlap along a unit direction n (the depth is min_n f(n)), each candidate gives an upper bound
/// f(n) at its direction and a lower bound rho from a point x of one shape inside the other, rho
/// its distance to that shape's boundary (the ball of radius rho about x lies inside it, so every
/// translation that separates them is at least rho long). The candidates:
///   a face of the box against the cone's deepest point across it (its apex or a base rim point),
///       n the face's inward normal;
///   a corner of the box inside the cone, n the outward normal of the nearest of the cone's side
///       (its tangent plane at the corner's azimuth) and base;
///   an edge of the box across the cone's side, n the side normal orthogonal to the edge, x the
///       edge's point at that normal's azimuth.
/// Where one of them is the contact (a rim point or the apex in a face, a corner through the side
/// or the base) the two bounds meet up to rounding; when the best upper and lower bounds are within
/// the tolerance, the answer is certified as EPA's is (depth = the upper bound, depth_gap = upper -
/// lower); otherwise (an edge of the box against the rim, a contact near an edge of either whose
/// nearest boundary is not the contact's) the caller runs EPA.
/// Over the bench's 175 intersecting cone–box poses the candidates certify 100 (measured with
/// impact-convex-bench's poses). The overlaps are computed in closed form (a face's from the cone's
/// support point in the box's frame, the others from h_B(-n) = -n . t + sum_i e_i |R_i . n|), not
/// from the box's support point: 3,549 -> 3,450 callgrind instructions per cone–box penetration on
/// the bench's 2000 poses.
/// cone_box_apart_along_box_axes, run before GJK, separates 92 of the 172 separated poses that the
/// line between the centres leaves (3,450 -> 3,386). Where the candidates fail (239 of the 362
/// intersecting poses go on to EPA), the commonest case is a box edge across the cone's side (90):
/// the edge candidate's upper bound is the depth on all 90, but its ball is cut, by the base on 56.
/// EPA then starts from that normal (its upper bound, and GJK's first direction) and stops by the
/// local certificate on a body inside the cone along the ruling the edge crosses
/// (cone_box_side_certificate, convex/cone_box_terms.hpp).
///
/// Numerical contract: APPROXIMATE, as EPA's: depth is f(normal) computed from the supports (an
/// upper bound up to rounding), depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/shapes.hpp"

namespace impact::detail {

/// Whether a plane normal to one of the box's axes separates cone a (its frame) and box b (placed by
/// R, t there) by more than `margin`: the cone's extent along a unit u is [-h_A(-u), h_A(u)] with
/// h_A(u) = max(h u_z, r |u_xy| - h u_z) (one square root per axis for both signs), the box's
/// [u . t - e_i, u . t + e_i]. Exact up to rounding.
template <class S>
bool cone_box_apart_along_box_axes(const Cone<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, S margin) {
  const S r = a.radius, h = a.half_length;
  for (int i = 0; i < 3; ++i) {
    const Vec3<S> u = R.col(i);
    const S rim = r * std::sqrt(u.x() * u.x() + u.y() * u.y()), hz = h * u.z(), c = u.dot(t);
    const S up = std::max(hz, rim - hz), down = std::max(-hz, rim + hz);  // h_A(u), h_A(-u)
    if (up < c - b.half[i] - margin || down < -c - b.half[i] - margin) return true;
  }
  return false;
}

/// The certified contact of cone a and box b when one of the candidates of the file comment decides
/// it within `tolerance`, in a's frame (b placed by R, t there): true and `out` set (normal from a
/// towards b, depth, depth_gap, the deciding point (the caller moves it onto the plane midway
/// between the supporting planes), iterations counts the overlap evaluations); else false. A
/// separated pair is never certified (a lower bound needs a point of one inside the other).
template <class S>
bool cone_box_contact(const Cone<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, S tolerance, ConvexContact<S>& out) {
  // the box's axes scaled by its half extents (its corners are t +- hc[0] +- hc[1] +- hc[2]), and the
  // overlap along unit n with h_B(-n) = -n . t + sum_i e_i |R_i . n| (no support point of the box)
  const Vec3<S> hc[3] = {Vec3<S>(b.half.x() * R.col(0)), Vec3<S>(b.half.y() * R.col(1)), Vec3<S>(b.half.z() * R.col(2))};
  const auto overlap = [&](const Vec3<S>& n) {
    const Vec3<S> m = R.transpose() * n;
    return n.dot(support(a, n)) - n.dot(t) + b.half.x() * std::abs(m.x()) + b.half.y() * std::abs(m.y()) + b.half.z() * std::abs(m.z());
  };
  CandidateBounds<S> k;
  const S L = cone_slant(a);  // once for every inside_ball of the cone below
  // the box's faces: the cone's deepest point x across each, in the box's frame y (the overlap
  // along the face's inward normal s R_i is e_i + s y_i); x is support(a, n) with |n_xy| taken
  // once for both faces of an axis
  for (int i = 0; i < 3; ++i) {
    const S r_xy = std::sqrt(R(0, i) * R(0, i) + R(1, i) * R(1, i));
    for (const S s : {S(1), S(-1)}) {
      const Vec3<S> n = s * R.col(i);
      const Vec3<S> x = a.half_length * n.z() >= a.radius * r_xy - a.half_length * n.z() ? Vec3<S>(S(0), S(0), a.half_length)
                                                                                            : rim_support(a.radius, -a.half_length, n, r_xy);
      const Vec3<S> y = R.transpose() * (x - t);
      const InsideBall<S> ball = inside_ball(b, y);
      if (ball.rho > S(0)) k.offer(n, b.half[i] + s * y[i], x, ball.rho);
    }
  }
  if (k.upper - k.lower <= tolerance) return k.finish(tolerance, out);
  // the box's corners inside the cone, pushed out through its nearest side or base
  for (int v = 0; v < 8; ++v) {
    const Vec3<S> x = t + ((v & 1) ? hc[0] : Vec3<S>(-hc[0])) + ((v & 2) ? hc[1] : Vec3<S>(-hc[1])) + ((v & 4) ? hc[2] : Vec3<S>(-hc[2]));
    const InsideBall<S> ball = inside_ball(a, x, L);
    if (ball.rho > S(0)) {
      const Vec3<S> n = -ball.push;
      k.offer(n, overlap(n), x, ball.rho);
    }
  }
  if (k.upper - k.lower <= tolerance) return k.finish(tolerance, out);
  // an edge of the box across the cone's side: n the side normal orthogonal to the edge (2h u . e
  // = -r e_z, u the azimuth), the edge the box's deepest along -n, x its point at azimuth u
  // (box_edge_at_azimuth)
  const S r = a.radius, h = a.half_length, len = L;
  for (int i = 0; i < 3; ++i) {
    const Vec3<S> e = R.col(i);
    const S m2 = e.x() * e.x() + e.y() * e.y(), c = -r * e.z() / (S(2) * h);
    if (!(m2 > S(1e-12)) || c * c >= m2) continue;
    const S along = c / m2, across = std::sqrt(m2 - c * c) / m2;
    for (const S sign : {S(1), S(-1)}) {
      const S ux = along * e.x() - sign * across * e.y(), uy = along * e.y() + sign * across * e.x();
      const Vec3<S> n(S(2) * h * ux / len, S(2) * h * uy / len, r / len);
      Vec3<S> x;
      if (!box_edge_at_azimuth(R, t, hc, i, n, ux, uy, x)) continue;
      const InsideBall<S> ball = inside_ball(a, x, L);
      if (ball.rho > S(0)) k.offer(n, overlap(n), x, ball.rho);
    }
  }
  return k.finish(tolerance, out);
}

}  // namespace impact::detail
