// SPDX-License-Identifier: MIT
/// \file
/// A certified shortcut for the penetration of an intersecting cylinder and cylinder or cone
/// (convex/certified_pair.hpp runs it before EPA). With f(n) = h_A(n) + h_B(-n), the overlap along a unit
/// direction n (translating b by f(n) n separates them; the depth is min_n f(n), as for EPA in
/// convex/epa.hpp), each candidate below gives an upper bound f(n) at its direction and a lower
/// bound from balls inside the shapes: for balls A' (centre c_a, radius rho_a) inside A and B'
/// (c_b, rho_b) inside B, f >= f_{A',B'} everywhere, so depth >= rho_a + rho_b - |c_a - c_b| (a
/// ball of radius 0 is a point), and a ball B' against the whole of A gives depth >= rho_b +
/// dist(c_b, boundary of A). A cylinder's support along n is a cap disc (n along the axis), a
/// ruling (n normal to the axis) or a rim point; a cone's its base disc, a side ruling, the apex or
/// a base rim point. The candidates are the contacts where at most one side is a corner (rim point,
/// apex):
///   a cap (or the cone's base) against the other shape's deepest point x across it: the ball
///       about x of radius dist(x, boundary) inside the capped shape;
///   ruling against ruling (n normal to both axes; for a cone, normal to the cylinder's axis and a
///       side normal of the cone): the closest points of the two rulings, each with the largest
///       ball inside its shape tangent there;
///   a cylinder's ruling against the other's rim point nearest its axis (the distance of a circle to
///       a line: 8 samples of the angle, then Newton) or the cone's apex, n the radial direction
///       through it; the cone's side against the cylinder's rim point deepest below it (the same
///       minimisation of 2h rho + R z over the rim).
/// When undecided: when the best candidate's point of the cone lies inside the cylinder but a
/// ball about it is cut by another face of the cylinder, the cone's points deepest across those
/// faces join it in the lower bound of convex/cylinder_pair_points.hpp (the depth of the cylinder
/// against their hull); the same with the roles swapped (the cylinder's point inside the cone,
/// its ball cut by the cone's base or side: cone_points_bound). Last, the cone's side against the
/// cylinder: the least overlap along the cone's side normals (cone_side_minimum: an upper bound at
/// the contact of the cylinder's rim or ruling with a cone ruling, where the rim point deepest
/// below the side is not the contact's), and, when the best direction is a side normal of the
/// cone, that whole ruling (apex and rim point) as the points of convex/cylinder_pair_points.hpp
/// against the cylinder. (The side minimum is the dearest stage by the clock, a chain of dependent
/// square roots: last, it runs only on the poses the points bounds leave.)
/// At the true contact of these kinds the two bounds meet (up to rounding and Newton's last step);
/// when the best upper and lower bounds are within the tolerance, the answer is certified as EPA's
/// is (depth = the upper bound, depth_gap = upper - lower); otherwise (a rim against a rim, deep
/// contacts whose balls are too small, nearly parallel axes) the caller runs EPA.
///
/// Numerical contract: APPROXIMATE, as EPA's: depth is f(normal) computed from the supports (an
/// upper bound up to rounding), depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/azimuth_turn.hpp"
#include "impact/convex/closed_form.hpp"
#include "impact/convex/cylinder_pair_points.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// The angle's cosine and sine of the point of the circle c + cos(phi) u + sin(phi) v (u, v
/// orthogonal, of the circle's radius) minimising q = alpha rho + beta z, rho the point's distance
/// to the z axis: alpha = 1, beta = 0 gives the point nearest the axis; alpha = 2h, beta = R the
/// point deepest below the side of a cone of base radius R and half length h about the axis. The
/// best of 8 samples with z in [-zmax, zmax] (of all 8 if none is), then Newton on q(phi) (the
/// certificate that uses the point checks it anyway), the angle turned by each step as in
/// convex/azimuth_turn.hpp.
template <class S>
inline void circle_minimise(const Vec3<S>& c, const Vec3<S>& u, const Vec3<S>& v, S alpha, S beta, S zmax, S& cos_phi,
                            S& sin_phi) {
  static constexpr S k = S(0.7071067811865476);
  static constexpr S cs[8][2] = {{S(1), S(0)}, {k, k}, {S(0), S(1)}, {-k, k}, {S(-1), S(0)}, {-k, -k}, {S(0), S(-1)}, {k, -k}};
  int best = 0;
  S qbest = std::numeric_limits<S>::infinity();
  bool inside = false;  // whether the best sample so far has |z| <= zmax
  for (int i = 0; i < 8; ++i) {
    const Vec3<S> w = c + cs[i][0] * u + cs[i][1] * v;
    const S g = w.x() * w.x() + w.y() * w.y();
    const S q = beta != S(0) ? alpha * std::sqrt(g) + beta * w.z() : g;
    const bool in = std::abs(w.z()) <= zmax;
    if ((in && !inside) || (in == inside && q < qbest)) {
      qbest = q;
      best = i;
      inside = in;
    }
  }
  S co = cs[best][0], si = cs[best][1];
  for (int it = 0; it < 16; ++it) {
    const Vec3<S> p = co * u + si * v, w = c + p, d = -si * u + co * v;  // offset from c, point, derivative (w'' = -p)
    const S g = w.x() * w.x() + w.y() * w.y();
    const S g1 = w.x() * d.x() + w.y() * d.y(),
            g2 = d.x() * d.x() + d.y() * d.y() - (w.x() * p.x() + w.y() * p.y());  // g'/2, g''/2
    S q1 = g1, q2 = g2;  // beta = 0: Newton on g (the same minimiser as rho)
    if (beta != S(0)) {
      if (!(g > S(0))) break;
      const S inv_rho = S(1) / std::sqrt(g), r1 = g1 * inv_rho, r2 = (g2 - r1 * r1) * inv_rho;  // rho', rho''
      q1 = alpha * r1 + beta * d.z();
      q2 = alpha * r2 - beta * p.z();
    }
    S step = q2 > S(0) ? -q1 / q2 : (q1 > S(0) ? S(-0.2) : S(0.2));
    step = std::clamp(step, S(-0.4), S(0.4));
    azimuth_turn(step, co, si);
    if (std::abs(step) <= S(1e-7)) break;  // Newton's next step would be below 1e-14
  }
  cos_phi = co;
  sin_phi = si;
}

/// Whether no point of the circle about c (radius r, its plane's unit normal n) lies strictly
/// inside the cylinder of radius `radius` and half length `half` about the z axis (by more than
/// `margin`): every point's distance to the axis is at least |c_xy| - r and its height within
/// r sqrt(1 - n_z^2) of c_z. Then a candidate at the circle's point has no ball inside that
/// cylinder (nor inside a cone it bounds) and is skipped without minimising over the circle.
template <class S>
inline bool circle_clear_of_cylinder(const Vec3<S>& c, S r, const Vec3<S>& n, S radius, S half, S margin) {
  const S cxy = std::sqrt(c.x() * c.x() + c.y() * c.y());
  if (cxy - r >= radius + margin) return true;
  const S zr = r * std::sqrt(std::max(S(1) - n.z() * n.z(), S(0)));
  return std::abs(c.z()) - zr >= half + margin;
}

/// The bounds the candidates give: the least overlap with its direction and point, the largest
/// certified lower bound.
template <class S>
struct CandidateBounds {
  S upper = std::numeric_limits<S>::infinity(), lower = S(0);
  Vec3<S> normal = Vec3<S>::UnitZ(), point = Vec3<S>::Zero();
  int calls = 0;
  void offer(const Vec3<S>& n, S f, const Vec3<S>& x, S lb) {
    ++calls;
    lower = std::max(lower, lb);
    if (f < upper) {
      upper = f;
      normal = n;
      point = x;
    }
  }
  /// A certified lower bound found apart from the candidates.
  void raise(S lb) { lower = std::max(lower, lb); }
  /// Certified within `tolerance`: `out` set as the contact functions below say.
  bool finish(S tolerance, ConvexContact<S>& out) const {
    out.iterations = calls;
    out.normal = normal;
    out.depth = upper;
    if (!(lower > S(0) && upper - lower <= tolerance)) return false;
    out.intersecting = true;
    out.depth = std::max(upper, S(0));
    out.depth_gap = std::max(upper - lower, S(0));
    out.point = point;
    return true;
  }
};

/// The radius of the largest ball inside cylinder c tangent to its side on a ruling at height z
/// (its frame): min(radius, half_length - |z|), < 0 beyond the caps.
template <class S>
inline S cylinder_ball_at_ruling(const Cylinder<S>& c, S z) {
  return std::min(c.radius, c.half_length - std::abs(z));
}

/// The lower bound of two balls, each inside its shape (a's ball: centre ca, radius ra; b's: cb,
/// rb; all in a's frame): the balls' depth, and each ball against the whole other shape (its radius
/// plus its centre's distance to that shape's boundary); `in_b` maps a's frame to b's.
template <class S, class A, class B, class InB>
S two_balls_lower(const A& a, const B& b, const InB& in_b, const Vec3<S>& ca, S ra, const Vec3<S>& cb, S rb) {
  S lb = ra + rb - (ca - cb).norm();
  const InsideBall<S> whole_a = inside_ball(a, cb), whole_b = inside_ball(b, in_b(ca));
  if (whole_a.rho >= S(0)) lb = std::max(lb, rb + whole_a.rho);
  if (whole_b.rho >= S(0)) lb = std::max(lb, ra + whole_b.rho);
  return lb;
}

/// The side of a cylinder or cone about its z axis, for the ruling-against-ruling candidate: the
/// axial and radial components of its unit side normals (cylinder: 0 and 1; cone of base radius R
/// and half length h: R / L and 2h / L, L = sqrt(4h^2 + R^2)); its ruling at the radial unit
/// direction (co, si) as the segment p0 + s d, s in [0, 1]; the largest ball inside it tangent to
/// the side at its point p (outward normal o there): rho < 0 when p is off the side's extent.
template <class S>
inline void side_normal(const Cylinder<S>&, S& axial, S& radial) {
  axial = S(0);
  radial = S(1);
}
template <class S>
inline void side_normal(const Cone<S>& c, S& axial, S& radial) {
  const S len = std::sqrt(S(4) * c.half_length * c.half_length + c.radius * c.radius);
  axial = c.radius / len;
  radial = S(2) * c.half_length / len;
}
template <class S>
inline void side_ruling(const Cylinder<S>& c, S co, S si, Vec3<S>& p0, Vec3<S>& d) {
  p0 = Vec3<S>(c.radius * co, c.radius * si, -c.half_length);
  d = Vec3<S>(S(0), S(0), S(2) * c.half_length);
}
template <class S>
inline void side_ruling(const Cone<S>& c, S co, S si, Vec3<S>& p0, Vec3<S>& d) {
  p0 = Vec3<S>(S(0), S(0), c.half_length);
  d = Vec3<S>(c.radius * co, c.radius * si, S(-2) * c.half_length);
}
template <class S>
inline InsideBall<S> ball_at_side(const Cylinder<S>& c, const Vec3<S>& p, const Vec3<S>& o) {
  InsideBall<S> out;
  const S rho = cylinder_ball_at_ruling(c, p.z());
  if (!(rho >= S(0))) return out;
  out.rho = rho;
  out.push = p - rho * o;  // the centre
  return out;
}
/// For a cone: the centre p - rho o with rho as large as the base and the axis allow, then cut to
/// the centre's own distance to the boundary.
template <class S>
inline InsideBall<S> ball_at_side(const Cone<S>& c, const Vec3<S>& p, const Vec3<S>& o) {
  const S h = c.half_length, len = std::sqrt(S(4) * h * h + c.radius * c.radius);
  const S rxy = std::sqrt(p.x() * p.x() + p.y() * p.y());
  InsideBall<S> out;
  const S rho = std::min((p.z() + h) / (S(1) + c.radius / len), rxy * len / (S(2) * h));
  if (!(rho >= S(0))) return out;
  const Vec3<S> centre = p - rho * o;
  out.rho = std::min(rho, inside_ball(c, centre).rho);
  out.push = centre;
  return out;
}

/// Ruling against ruling, for a cylinder or cone a (its frame) and a cylinder or cone b placed by
/// R, t there (in_b maps a's frame to b's): the directions n that are a side normal of a and whose
/// opposite is a side normal of b (n = (k cos psi, k sin psi, c) with b's axis w: n . w = -c_b; up
/// to two, cos(psi - base) = tau / |w_xy| without trigonometric calls); for each whose rulings'
/// closest points are interior to both, offer(n, the points' midpoint, the lower bound of the two
/// balls tangent there (two_balls_lower)).
template <class S, class A, class B, class InB, class Offer>
void opposite_rulings(const A& a, const B& b, const Mat3<S>& R, const Vec3<S>& t, const InB& in_b, const Offer& offer) {
  const Vec3<S> bz = R.col(2);
  S ca, ka, cb_axial, kb;
  side_normal(a, ca, ka);
  side_normal(b, cb_axial, kb);
  const S rho = std::sqrt(bz.x() * bz.x() + bz.y() * bz.y());
  const S tau = (-cb_axial - ca * bz.z()) / ka;
  if (!(rho > S(1e-6) && std::abs(tau) < rho)) return;
  // psi = base +- spread with cos(base), sin(base) = bz_xy / rho and cos(spread) = tau / rho
  const S cbase = bz.x() / rho, sbase = bz.y() / rho, cs = tau / rho, ss = std::sqrt(std::max(S(1) - cs * cs, S(0)));
  for (const S sign : {S(1), S(-1)}) {
    const S cp = cbase * cs - sign * sbase * ss, sp = sbase * cs + sign * cbase * ss;
    const Vec3<S> n(ka * cp, ka * sp, ca);
    // b's ruling: its azimuth from its side normal m = -R^T n
    const Vec3<S> m = -(R.transpose() * n);
    const S mxy = std::sqrt(m.x() * m.x() + m.y() * m.y());
    if (!(mxy > S(0))) continue;
    Vec3<S> p0, d, q0, e;
    side_ruling(a, cp, sp, p0, d);
    side_ruling(b, m.x() / mxy, m.y() / mxy, q0, e);
    q0 = R * q0 + t;
    e = R * e;
    // the closest points of a's ruling p0 + s d and b's q0 + l e
    const Vec3<S> w = p0 - q0;
    const S dd = d.dot(d), de = d.dot(e), ee = e.dot(e), dw = d.dot(w), ew = e.dot(w), den = dd * ee - de * de;
    if (!(den > S(1e-12) * dd * ee)) continue;
    const S s = (de * ew - ee * dw) / den, l = (dd * ew - de * dw) / den;
    if (!(s >= S(0) && s <= S(1) && l >= S(0) && l <= S(1))) continue;
    const Vec3<S> pa = p0 + s * d, pb = q0 + l * e;
    const InsideBall<S> ball_a = ball_at_side(a, pa, n);
    const InsideBall<S> ball_b = ball_at_side(b, in_b(pb), m);
    if (!(ball_a.rho >= S(0) && ball_b.rho >= S(0))) continue;
    offer(n, Vec3<S>((pa + pb) / S(2)),
          two_balls_lower(a, b, in_b, ball_a.push, ball_a.rho, Vec3<S>(R * ball_b.push + t), ball_b.rho));
  }
}

/// The least overlap of cone c (its frame) and another convex shape along the directions where
/// c's support is a whole side ruling: n = -m(u), m(u) = (k u, c) c's outward side normal at the
/// radial unit u (k = 2h / L, c = R / L), where the overlap is F(u) = h_O(-m) + h R / L (O the
/// other shape, `support_other(d)` its support along d in c's frame). Its slope along the circle
/// is F' = -s_O(-m) . (k u', 0), u' = u turned by a right angle (the support's own motion does not
/// count): the best of 8 samples of u, then regula falsi (Illinois) on F' between that sample's
/// neighbours when F' changes sign there, on the chord between the bracket's ends (u from the
/// normalised chord point: no trigonometric calls). True with m the direction found and x the
/// other shape's support along -m (any direction gives an upper bound: the caller offers it with
/// x's ball); false when F' does not change sign about the best sample or 24 steps do not close
/// the bracket to 1e-9 (128 ulps in float).
template <class S, class SupportOther>
bool cone_side_minimum(const Cone<S>& c, const SupportOther& support_other, Vec3<S>& m, Vec3<S>& x) {
  const S len = std::sqrt(S(4) * c.half_length * c.half_length + c.radius * c.radius), k = S(2) * c.half_length / len, cz = c.radius / len;
  const auto normal = [&](S ux, S uy) { return Vec3<S>(k * ux, k * uy, cz); };
  const auto slope = [&](S ux, S uy, Vec3<S>& sx) {  // F' at u, with the support
    sx = support_other(Vec3<S>(-normal(ux, uy)));
    return k * (sx.x() * uy - sx.y() * ux);
  };
  static constexpr S r = S(0.7071067811865476);
  static constexpr S cs[8][2] = {{S(1), S(0)}, {r, r}, {S(0), S(1)}, {-r, r}, {S(-1), S(0)}, {-r, -r}, {S(0), S(-1)}, {r, -r}};
  int best = 0;
  S fbest = std::numeric_limits<S>::infinity();
  for (int i = 0; i < 8; ++i) {
    const Vec3<S> n = normal(cs[i][0], cs[i][1]);
    const S f = -n.dot(support_other(Vec3<S>(-n)));
    if (f < fbest) {
      fbest = f;
      best = i;
    }
  }
  S lx = cs[(best + 7) % 8][0], ly = cs[(best + 7) % 8][1], hx = cs[(best + 1) % 8][0], hy = cs[(best + 1) % 8][1];
  Vec3<S> sl, sh;
  S gl = slope(lx, ly, sl), gh = slope(hx, hy, sh);
  if (!(gl < S(0) && gh > S(0))) return false;
  const S close = std::max(S(1e-9), S(128) * std::numeric_limits<S>::epsilon());
  // a kink: F' jumps where the other shape's support jumps (a cylinder's from cap to cap, a cone's
  // from apex to rim); there the bracket's true end slopes stay apart from 0 as it closes, while
  // about a smooth minimum they shrink with it (|F'| <= F'' width, F'' <= k |s| + k^2 r / |P d|)
  const S kink = S(1e2) * k * (sl.norm() + sh.norm());
  S tl = gl, th = gh;  // the true slopes at the ends (Illinois halves gl, gh)
  int side = 0;
  for (int it = 0; it < 24; ++it) {
    const S lam = gl / (gl - gh);  // the chord point where F' interpolates to 0
    S ux = lx + lam * (hx - lx), uy = ly + lam * (hy - ly);
    const S inv_norm = S(1) / std::sqrt(ux * ux + uy * uy);
    ux *= inv_norm;
    uy *= inv_norm;
    Vec3<S> sx;
    const S g = slope(ux, uy, sx);
    if (g < S(0)) {
      lx = ux;
      ly = uy;
      gl = tl = g;
      if (side == -1) gh /= S(2);
      side = -1;
    } else {
      hx = ux;
      hy = uy;
      gh = th = g;
      if (side == 1) gl /= S(2);
      side = 1;
    }
    const S width = std::abs(hx - lx) + std::abs(hy - ly);
    if (th - tl > kink * width) return false;  // a kink: no smooth minimum to find
    if (g == S(0) || width <= close) {
      m = normal(ux, uy);
      x = sx;
      return true;
    }
  }
  return false;
}

/// The certified contact of cylinders a and b when one of the candidates of the file comment
/// decides it within `tolerance`, in a's frame (b placed by R, t there): true and `out` set
/// (normal from a towards b, depth, depth_gap, a point of the contact (the caller moves it onto the
/// plane midway between the supporting planes), iterations counts the overlap evaluations); else
/// false, with out.normal and out.depth the best candidate's direction and overlap (depth infinite
/// when no candidate applied). Meant for intersecting pairs (a separated pair is never certified).
template <class S>
bool cylinder_pair_contact(const Cylinder<S>& a, const Cylinder<S>& b, const Mat3<S>& R, const Vec3<S>& t, S tolerance,
                           ConvexContact<S>& out) {
  const Vec3<S> bz = R.col(2), az_in_b = R.row(2).transpose();
  const S margin = std::numeric_limits<S>::epsilon() * S(1024) * (a.radius + a.half_length + b.radius + b.half_length + t.norm());
  const auto sb = [&](const Vec3<S>& d) { return Vec3<S>(R * support(b, Vec3<S>(R.transpose() * d)) + t); };
  const auto overlap = [&](const Vec3<S>& n) { return n.dot(support(a, n)) - n.dot(sb(Vec3<S>(-n))); };
  const auto in_b = [&](const Vec3<S>& x) { return Vec3<S>(R.transpose() * (x - t)); };
  CandidateBounds<S> k;
  const auto offer = [&](const Vec3<S>& n, const Vec3<S>& x, S lb) { k.offer(n, overlap(n), x, lb); };
  // caps of a: b's deepest point across each
  for (const S s : {S(1), S(-1)}) {
    const Vec3<S> n(S(0), S(0), s);
    const Vec3<S> x = sb(Vec3<S>(-n));
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) offer(n, x, ball.rho);
  }
  // caps of b: a's deepest point across each
  for (const S s : {S(1), S(-1)}) {
    const Vec3<S> n = s * bz;
    const Vec3<S> x = support(a, n);
    const InsideBall<S> ball = inside_ball(b, in_b(x));
    if (ball.rho > S(0)) offer(n, x, ball.rho);
  }
  const auto rulings = [&] {  // ruling against ruling: n normal to both axes, towards b
    const S m = std::sqrt(bz.x() * bz.x() + bz.y() * bz.y());
    if (!(m > S(1e-6))) return;
    Vec3<S> n(-bz.y() / m, bz.x() / m, S(0));
    if (n.dot(t) < S(0)) n = -n;
    const Vec3<S> tp = t - n.dot(t) * n;
    const S cb = bz.z(), w = S(1) - cb * cb;
    const S s2 = (cb * tp.z() - bz.dot(tp)) / w, s1 = tp.z() + cb * s2;  // s1 e_z - s2 bz = tp
    const S rho_a = cylinder_ball_at_ruling(a, s1), rho_b = cylinder_ball_at_ruling(b, s2);
    if (!(rho_a >= S(0) && rho_b >= S(0))) return;
    const Vec3<S> pa = a.radius * n + Vec3<S>(S(0), S(0), s1), pb = t - b.radius * n + s2 * bz;
    const S lb = two_balls_lower(a, b, in_b, Vec3<S>(pa - rho_a * n), rho_a, Vec3<S>(pb + rho_b * n), rho_b);
    offer(n, Vec3<S>((pa + pb) / S(2)), lb);
  };
  // ruling of a against b's rims: the rim point nearest a's axis, pushed out radially
  const auto rims_of_b = [&] {
    for (const S s : {S(1), S(-1)}) {
      const Vec3<S> c = t + s * b.half_length * bz, u = b.radius * R.col(0), v = b.radius * R.col(1);
      if (circle_clear_of_cylinder(c, b.radius, bz, a.radius, a.half_length, margin)) continue;
      S co, si;
      circle_minimise(c, u, v, S(1), S(0), a.half_length, co, si);
      const Vec3<S> x = c + co * u + si * v;
      const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
      const InsideBall<S> ball = inside_ball(a, x);
      if (rxy > S(0) && ball.rho > S(0)) offer(Vec3<S>(x.x() / rxy, x.y() / rxy, S(0)), x, ball.rho);
    }
  };
  // ruling of b against a's rims, in b's frame
  const auto rims_of_a = [&] {
    for (const S s : {S(1), S(-1)}) {
      const Vec3<S> c = in_b(Vec3<S>(S(0), S(0), s * a.half_length));
      if (circle_clear_of_cylinder(c, a.radius, az_in_b, b.radius, b.half_length, margin)) continue;
      const Vec3<S> u = a.radius * R.row(0).transpose(), v = a.radius * R.row(1).transpose();
      S co, si;
      circle_minimise(c, u, v, S(1), S(0), b.half_length, co, si);
      const Vec3<S> xb = c + co * u + si * v;
      const S rxy = std::sqrt(xb.x() * xb.x() + xb.y() * xb.y());
      const InsideBall<S> ball = inside_ball(b, xb);
      if (rxy > S(0) && ball.rho > S(0)) {
        const Vec3<S> x(co * a.radius, si * a.radius, s * a.half_length);
        offer(Vec3<S>(-(R * Vec3<S>(xb.x() / rxy, xb.y() / rxy, S(0)))), x, ball.rho);
      }
    }
  };
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  if (!decided()) rulings();
  if (!decided()) rims_of_b();
  if (!decided()) rims_of_a();
  return k.finish(tolerance, out);
}

/// The same for cylinder a and cone b (base of radius R at -h along its axis, apex at +h; side
/// normals (2h u + R axis) / L, L = sqrt(4h^2 + R^2), u radial): a's caps against b's deepest point,
/// b's base against a's, b's apex and base rim against a's rulings, a ruling of each (n normal to
/// a's axis and a side normal of b: up to two directions), and b's side against the point of a's
/// rims deepest below it; then, when undecided, the bound from b's points when the best
/// candidate's point of b lies in a (cylinder_points_bound; 1 to 4 more support calls of b) and
/// from a's points when a's lies in b (cone_points_bound), the least overlap along b's side normals
/// (cone_side_minimum), and b's whole ruling against a when the best direction is a side normal of
/// b (cylinder_points_lower on its two ends).
template <class S>
bool cylinder_cone_contact(const Cylinder<S>& a, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, S tolerance,
                           ConvexContact<S>& out) {
  const Vec3<S> bz = R.col(2), az_in_b = R.row(2).transpose();
  const S rc = b.radius, hc = b.half_length, len = std::sqrt(S(4) * hc * hc + rc * rc);
  const S margin = std::numeric_limits<S>::epsilon() * S(1024) * (a.radius + a.half_length + rc + hc + t.norm());
  const auto sb = [&](const Vec3<S>& d) { return Vec3<S>(R * support(b, Vec3<S>(R.transpose() * d)) + t); };
  const auto overlap = [&](const Vec3<S>& n) { return n.dot(support(a, n)) - n.dot(sb(Vec3<S>(-n))); };
  const auto in_b = [&](const Vec3<S>& x) { return Vec3<S>(R.transpose() * (x - t)); };
  CandidateBounds<S> k;
  const auto offer = [&](const Vec3<S>& n, const Vec3<S>& x, S lb) { k.offer(n, overlap(n), x, lb); };
  const auto radial_push = [&](const Vec3<S>& x) {  // a point of b inside a, pushed out through a's side
    const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
    const InsideBall<S> ball = inside_ball(a, x);
    if (rxy > S(0) && ball.rho > S(0)) offer(Vec3<S>(x.x() / rxy, x.y() / rxy, S(0)), x, ball.rho);
  };
  // caps of a: b's deepest point across each
  for (const S s : {S(1), S(-1)}) {
    const Vec3<S> n(S(0), S(0), s);
    const Vec3<S> x = sb(Vec3<S>(-n));
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) offer(n, x, ball.rho);
  }
  {  // b's base (outward normal -axis): a's deepest point across it
    const Vec3<S> x = support(a, bz);
    const InsideBall<S> ball = inside_ball(b, in_b(x));
    if (ball.rho > S(0)) offer(bz, x, ball.rho);
  }
  radial_push(Vec3<S>(t + hc * bz));  // b's apex against a's side
  const auto base_rim = [&] {  // b's base rim against a's ruling: the rim point nearest a's axis
    const Vec3<S> c = t - hc * bz, u = rc * R.col(0), v = rc * R.col(1);
    if (circle_clear_of_cylinder(c, rc, bz, a.radius, a.half_length, margin)) return;
    S co, si;
    circle_minimise(c, u, v, S(1), S(0), a.half_length, co, si);
    radial_push(Vec3<S>(c + co * u + si * v));
  };
  const auto rims_of_a = [&] {  // b's side against a's rims: the rim point deepest below it
    for (const S s : {S(1), S(-1)}) {
      const Vec3<S> c = in_b(Vec3<S>(S(0), S(0), s * a.half_length));
      if (circle_clear_of_cylinder(c, a.radius, az_in_b, rc, hc, margin)) continue;  // b's bounding cylinder
      const Vec3<S> u = a.radius * R.row(0).transpose(), v = a.radius * R.row(1).transpose();
      S co, si;
      circle_minimise(c, u, v, S(2) * hc, rc, hc, co, si);
      const Vec3<S> xb = c + co * u + si * v;
      const S rxy = std::sqrt(xb.x() * xb.x() + xb.y() * xb.y());
      const InsideBall<S> ball = inside_ball(b, xb);
      if (rxy > S(0) && ball.rho > S(0)) {
        const Vec3<S> m(S(2) * hc * xb.x() / (rxy * len), S(2) * hc * xb.y() / (rxy * len), rc / len);  // b's side normal there
        offer(Vec3<S>(-(R * m)), Vec3<S>(co * a.radius, si * a.radius, s * a.half_length), ball.rho);
      }
    }
  };
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  if (!decided()) opposite_rulings(a, b, R, t, in_b, offer);  // a ruling of each
  if (!decided()) base_rim();
  if (!decided()) rims_of_a();
  const auto sa_in_b = [&](const Vec3<S>& d) { return in_b(support(a, Vec3<S>(R * d))); };  // a's support in b's frame
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    // the best candidate's point of b, when inside a: with b's points deepest across a's faces
    // that are nearer to it than the depth (convex/cylinder_pair_points.hpp)
    const Vec3<S> x = sb(Vec3<S>(-k.normal));
    ++k.calls;
    if (inside_ball(a, x).rho >= S(0)) k.raise(cylinder_points_bound(a, x, k.upper, tolerance, sb, k.calls));
  }
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    // the best candidate's point of a, when inside b: with a's points deepest across b's faces
    // that are nearer to it than the depth (the cone as the container)
    const Vec3<S> x = sa_in_b(Vec3<S>(R.transpose() * k.normal));
    ++k.calls;
    if (inside_ball(b, x).rho >= S(0)) k.raise(cone_points_bound(b, x, k.upper, tolerance, sa_in_b, k.calls));
  }
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    // b's side against a: the least overlap along b's side normals
    Vec3<S> m, x;
    if (cone_side_minimum(b, sa_in_b, m, x)) offer(Vec3<S>(-(R * m)), Vec3<S>(R * x + t), std::max(inside_ball(b, x).rho, S(0)));
  }
  if (!decided() && k.upper < std::numeric_limits<S>::infinity()) {
    // the best direction a side normal of b: b's whole ruling there against a (its two ends as
    // the points of convex/cylinder_pair_points.hpp; a lower bound at any azimuth, tight at a
    // contact of that ruling)
    const Vec3<S> m = -(R.transpose() * k.normal);
    const S mxy = std::sqrt(m.x() * m.x() + m.y() * m.y());
    if (std::abs(m.z() - rc / len) <= S(1e-6) && mxy > S(0)) {
      const Vec3<S> P[2] = {Vec3<S>(t + hc * bz), Vec3<S>(R * Vec3<S>(rc * m.x() / mxy, rc * m.y() / mxy, -hc) + t)};
      k.raise(cylinder_points_lower(a, P, 2, k.upper - tolerance));
    }
  }
  return k.finish(tolerance, out);
}

}  // namespace impact::detail
