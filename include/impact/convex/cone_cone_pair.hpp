// SPDX-License-Identifier: MIT
/// \file
/// A certified shortcut for the penetration of two intersecting cones (convex/certified_pair.hpp runs it
/// after GJK has enclosed the origin, before EPA), built as convex/cylinder_pair.hpp and
/// convex/cone_box_pair.hpp are: with f(n) = h_A(n) + h_B(-n), the overlap along a unit direction
/// n (the depth is min_n f(n)), each candidate gives an upper bound f(n) at its direction and a
/// lower bound from balls inside the shapes (a point x of one cone inside the other at distance
/// rho from its boundary: every separating translation is at least rho long; two balls, one in
/// each: their own depth). A cone's support along n is its base disc, a side ruling, the apex or a
/// base rim point, so the candidates are the contacts where at most one side is a corner:
///   either base against the other cone's deepest point across it (n the base's outward normal);
///   either apex inside the other, pushed out through the nearest side or base;
///   either base rim against the other's side: the rim point deepest below that side (the
///       minimisation of 2h rho + R z over the circle of convex/cylinder_pair.hpp), n the side
///       normal at its azimuth;
///   ruling against ruling: n a side normal of a whose opposite is a side normal of b (up to two
///       directions), the closest points of the two rulings, each with the largest ball inside its
///       cone tangent there.
/// When undecided: when the best direction is a side normal of a cone, that cone's whole ruling
/// (apex and rim point) as points inside the other
/// (cone_points_lower of convex/cylinder_pair_points.hpp); and the best candidate's point of each
/// cone inside the other with the first's points deepest across the other's nearer faces
/// (cone_points_bound). (Not here: the least overlap along either cone's side normals,
/// cone_side_minimum of convex/cylinder_pair.hpp, which cylinder–cone runs last: on cone pairs it cost
/// more time on the poses it left to EPA than it saved; docs/convex-notes.md, note 15.)
/// At the true contact of these kinds the bounds meet (up to rounding and Newton's last step);
/// when the best upper and lower bounds are within the tolerance the answer is certified as EPA's
/// is (depth = the upper bound, depth_gap = upper - lower); otherwise (a rim against a rim, deep
/// contacts whose balls are cut by a nearer face) the caller runs EPA, seeded with the best
/// candidate's direction and stopped early by the local certificate on cone_cone_terms.
///
/// Numerical contract: APPROXIMATE, as EPA's: depth is f(normal) computed from the supports (an
/// upper bound up to rounding), depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// Adds cone c's support function h_c(w) (c placed by R, t in the terms' frame, its branch at n:
/// the apex, a linear term, or the base rim, a disc term about the axis plus a linear one) to f, or
/// h_c(-w) when `negate`. False when the branches tie within 1e-6 of the cone's size at n (n
/// normal to a side ruling): no term is exact there.
template <class S>
bool add_cone_terms(const Cone<S>& c, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, bool negate, OverlapTerms<S>& f) {
  const S sgn = negate ? S(-1) : S(1);
  const Vec3<S> z = R.col(2);
  const S vz = sgn * z.dot(n);  // the axis component of the direction the support is taken along
  const S apex = c.half_length * vz, rim = c.radius * std::sqrt(std::max(S(1) - vz * vz, S(0))) - c.half_length * vz;
  if (std::abs(apex - rim) <= S(1e-6) * (c.half_length + c.radius)) return false;
  // h_c(sgn w) = sgn t . w + (apex: h sgn z . w; rim: r |P_z w| - h sgn z . w)
  f.linear += sgn * t;
  if (apex > rim) {
    f.linear += (sgn * c.half_length) * z;
  } else {
    f.linear -= (sgn * c.half_length) * z;
    f.add(z, c.radius, true);
  }
  f.magnitude += c.half_length + t.norm();
  return true;
}

/// The overlap of cone a (its frame) and cone b placed by R, t there as the terms of
/// convex/local_certificate.hpp, each cone's branch the one active along n; false on a tie.
template <class S>
bool cone_cone_terms(const Cone<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f) {
  f = OverlapTerms<S>();
  return add_cone_terms(a, Mat3<S>(Mat3<S>::Identity()), Vec3<S>(Vec3<S>::Zero()), n, false, f) && add_cone_terms(b, R, t, n, true, f);
}

/// The overlap of cone a (its frame, its branch active along n) and the body inside cone b along
/// the ruling whose side normal is nearest -n (add_cone_side_body, over the fractions [s0, s1] of
/// that ruling): <= the true overlap everywhere, equal along that ruling's side normals while a's
/// branch is the active one; false at a tie of a's branches or with -n along b's axis.
template <class S>
bool cone_cone_side_terms(const Cone<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f,
                          S s0 = S(0), S s1 = S(0.5)) {
  f = OverlapTerms<S>();
  return add_cone_terms(a, Mat3<S>(Mat3<S>::Identity()), Vec3<S>(Vec3<S>::Zero()), n, false, f) && add_cone_side_body(b, R, t, n, f, s0, s1);
}

/// The outward side normal of cone c (its frame) at the azimuth of x (any azimuth on the axis).
template <class S>
Vec3<S> cone_side_normal_at(const Cone<S>& c, const Vec3<S>& x) {
  const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y()), len = std::sqrt(S(4) * c.half_length * c.half_length + c.radius * c.radius);
  const S ux = rxy > S(0) ? x.x() / rxy : S(1), uy = rxy > S(0) ? x.y() / rxy : S(0);
  return Vec3<S>(S(2) * c.half_length * ux / len, S(2) * c.half_length * uy / len, c.radius / len);
}

/// The certified contact of cones a and b when one of the candidates of the file comment decides it
/// within `tolerance`, in a's frame (b placed by R, t there): true and `out` set (normal from a
/// towards b, depth, depth_gap, the deciding point, iterations counts the overlap evaluations); else
/// false, with out.normal and out.depth the best candidate's direction and overlap (depth infinite
/// when no candidate applied). Meant for intersecting pairs (a separated pair is never certified).
template <class S>
bool cone_cone_contact(const Cone<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, S tolerance, ConvexContact<S>& out) {
  const Vec3<S> bz = R.col(2), az_in_b = R.row(2).transpose();
  const S ra = a.radius, ha = a.half_length, rb = b.radius, hb = b.half_length;
  const S margin = std::numeric_limits<S>::epsilon() * S(1024) * (ra + ha + rb + hb + t.norm());
  const auto sb = [&](const Vec3<S>& d) { return Vec3<S>(R * support(b, Vec3<S>(R.transpose() * d)) + t); };
  const auto overlap = [&](const Vec3<S>& n) { return n.dot(support(a, n)) - n.dot(sb(Vec3<S>(-n))); };
  const auto in_b = [&](const Vec3<S>& x) { return Vec3<S>(R.transpose() * (x - t)); };
  CandidateBounds<S> k;
  const auto offer = [&](const Vec3<S>& n, const Vec3<S>& x, S lower) { k.offer(n, overlap(n), x, lower); };
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  {  // a's base (outward normal -z): b's deepest point across it
    const Vec3<S> n(S(0), S(0), S(-1));
    const Vec3<S> x = sb(Vec3<S>(-n));
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) offer(n, x, ball.rho);
  }
  {  // b's base (outward normal -bz): a's deepest point across it
    const Vec3<S> x = support(a, bz);
    const InsideBall<S> ball = inside_ball(b, in_b(x));
    if (ball.rho > S(0)) offer(bz, x, ball.rho);
  }
  {  // a's apex inside b, pushed out through b's nearest boundary (b moves along -its outward normal)
    const Vec3<S> x(S(0), S(0), ha);
    const InsideBall<S> ball = inside_ball(b, in_b(x));
    if (ball.rho > S(0)) offer(Vec3<S>(R * ball.push), x, ball.rho);
  }
  {  // b's apex inside a, pushed out through a's nearest boundary
    const Vec3<S> x = t + hb * bz;
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) offer(Vec3<S>(-ball.push), x, ball.rho);
  }
  const auto rim_of_b = [&] {  // b's base rim against a's side: the rim point deepest below it
    const Vec3<S> c = t - hb * bz, u = rb * R.col(0), v = rb * R.col(1);
    if (circle_clear_of_cylinder(c, rb, bz, ra, ha, margin)) return;  // a's bounding cylinder
    S co, si;
    circle_minimise(c, u, v, S(2) * ha, ra, ha, co, si);
    const Vec3<S> x = c + co * u + si * v;
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) offer(cone_side_normal_at(a, x), x, ball.rho);
  };
  const auto rim_of_a = [&] {  // a's base rim against b's side, in b's frame
    const Vec3<S> c = in_b(Vec3<S>(S(0), S(0), -ha));
    if (circle_clear_of_cylinder(c, ra, az_in_b, rb, hb, margin)) return;
    const Vec3<S> u = ra * R.row(0).transpose(), v = ra * R.row(1).transpose();
    S co, si;
    circle_minimise(c, u, v, S(2) * hb, rb, hb, co, si);
    const Vec3<S> xb = c + co * u + si * v;
    const InsideBall<S> ball = inside_ball(b, xb);
    if (ball.rho > S(0)) offer(Vec3<S>(-(R * cone_side_normal_at(b, xb))), Vec3<S>(co * ra, si * ra, -ha), ball.rho);
  };
  if (!decided()) opposite_rulings(a, b, R, t, in_b, offer);  // ruling against ruling
  if (!decided()) rim_of_b();
  if (!decided()) rim_of_a();
  const auto sa_in_b = [&](const Vec3<S>& d) { return in_b(support(a, Vec3<S>(R * d))); };
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    // the best direction a side normal of either cone: that cone's whole ruling there against the
    // other (its two ends as the points of cone_points_lower; a lower bound at any azimuth)
    const S ca = ra / std::sqrt(S(4) * ha * ha + ra * ra), cb = rb / std::sqrt(S(4) * hb * hb + rb * rb);
    const Vec3<S> mb = -(R.transpose() * k.normal), ma = k.normal;
    const S mbxy = std::sqrt(mb.x() * mb.x() + mb.y() * mb.y()), maxy = std::sqrt(ma.x() * ma.x() + ma.y() * ma.y());
    if (std::abs(mb.z() - cb) <= S(1e-6) && mbxy > S(0)) {
      const Vec3<S> P[2] = {Vec3<S>(t + hb * bz), Vec3<S>(R * Vec3<S>(rb * mb.x() / mbxy, rb * mb.y() / mbxy, -hb) + t)};
      k.raise(cone_points_lower(a, P, 2, k.upper - tolerance));
    }
    if (!decided() && std::abs(ma.z() - ca) <= S(1e-6) && maxy > S(0)) {
      const Vec3<S> P[2] = {in_b(Vec3<S>(S(0), S(0), ha)), in_b(Vec3<S>(ra * ma.x() / maxy, ra * ma.y() / maxy, -ha))};
      k.raise(cone_points_lower(b, P, 2, k.upper - tolerance));
    }
  }
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    // the best candidate's point of each cone, when inside the other: with the first's points
    // deepest across the other's faces nearer to it than the depth (convex/cylinder_pair_points.hpp)
    const Vec3<S> xb = sb(Vec3<S>(-k.normal));
    ++k.calls;
    if (inside_ball(a, xb).rho >= S(0)) k.raise(cone_points_bound(a, xb, k.upper, tolerance, sb, k.calls));
  }
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    const Vec3<S> xa = sa_in_b(Vec3<S>(R.transpose() * k.normal));
    ++k.calls;
    if (inside_ball(b, xa).rho >= S(0)) k.raise(cone_points_bound(b, xa, k.upper, tolerance, sa_in_b, k.calls));
  }
  return k.finish(tolerance, out);
}

}  // namespace impact::detail
