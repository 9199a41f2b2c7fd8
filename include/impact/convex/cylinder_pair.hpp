// SPDX-License-Identifier: MIT
/// \file
/// A certified shortcut for the penetration of two intersecting cylinders (convex/query.hpp runs it
/// before EPA). With f(n) = h_A(n) + h_B(-n), the overlap along a unit direction n (translating b
/// by f(n) n separates them; the depth is min_n f(n), as for EPA in convex/epa.hpp), each candidate
/// below gives an upper bound f(n) at its direction and a lower bound from balls inside the shapes:
/// for balls A' (centre c_a, radius rho_a) inside A and B' (c_b, rho_b) inside B, f >= f_{A',B'}
/// everywhere, so depth >= rho_a + rho_b - |c_a - c_b| (a ball of radius 0 is a point). A
/// cylinder's support along n is a cap disc (n along the axis), a ruling (n normal to the axis) or
/// a rim point; the candidates are the contacts where at most one side is a rim point:
///   cap of a (n = +-a's axis) against b's deepest point across it, and the same with a, b swapped:
///       the point x, the ball about it of radius dist(x, boundary) inside the other shape;
///   ruling against ruling (n normal to both axes): the closest points of the two rulings, each
///       with the largest ball inside its cylinder tangent there;
///   ruling of a against a rim point of b: the point x of b's rims nearest a's axis (the distance
///       of a circle to a line: 8 samples of the angle, then Newton), n a's radial direction
///       through x, the ball about x inside a; and the same with a, b swapped.
/// At the true contact of these kinds the two bounds meet (up to rounding and Newton's last step);
/// when the best upper and lower bounds are within the tolerance, the answer is certified as EPA's
/// is (depth = the upper bound, depth_gap = upper - lower); otherwise (a rim against a rim, shallow
/// balls, nearly parallel axes) the caller runs EPA.
///
/// Numerical contract: APPROXIMATE, as EPA's: depth is f(normal) computed from the supports (an
/// upper bound up to rounding), depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// The angle's cosine and sine of the point of the circle c + cos(phi) u + sin(phi) v (u, v
/// orthogonal, of the circle's radius) nearest the z axis, i.e. minimising g = x^2 + y^2 of the
/// point: the best of 8 samples, then Newton on g(phi) (a trigonometric polynomial of degree 2: at
/// most two minima, 45 degrees of sampling apart at least in practice; the certificate checks the
/// answer anyway). Only the x, y components of c, u, v matter.
template <class S>
inline void circle_nearest_z_axis(const Vec3<S>& c, const Vec3<S>& u, const Vec3<S>& v, S& cos_phi, S& sin_phi) {
  const S qx = c.x(), qy = c.y(), ux = u.x(), uy = u.y(), vx = v.x(), vy = v.y();
  static constexpr S k = S(0.7071067811865476);
  static constexpr S cs[8][2] = {{S(1), S(0)}, {k, k}, {S(0), S(1)}, {-k, k}, {S(-1), S(0)}, {-k, -k}, {S(0), S(-1)}, {k, -k}};
  int best = 0;
  S gbest = std::numeric_limits<S>::infinity();
  for (int i = 0; i < 8; ++i) {
    const S wx = qx + cs[i][0] * ux + cs[i][1] * vx, wy = qy + cs[i][0] * uy + cs[i][1] * vy;
    const S g = wx * wx + wy * wy;
    if (g < gbest) {
      gbest = g;
      best = i;
    }
  }
  S co = cs[best][0], si = cs[best][1];
  for (int it = 0; it < 16; ++it) {
    const S px = co * ux + si * vx, py = co * uy + si * vy;                                // the circle's offset from c
    const S wx = qx + px, wy = qy + py, tx = -si * ux + co * vx, ty = -si * uy + co * vy;  // point, derivative
    const S g1 = wx * tx + wy * ty;                                                        // g' / 2
    const S g2 = tx * tx + ty * ty - (wx * px + wy * py);                                  // g'' / 2
    S step = g2 > S(0) ? -g1 / g2 : (g1 > S(0) ? S(-0.2) : S(0.2));
    step = std::clamp(step, S(-0.4), S(0.4));
    // rotate (co, si) by the step: Taylor series for small steps (error below 1e-16 under 1e-2)
    S cs_step, sn_step;
    if (std::abs(step) < S(1e-2)) {
      const S s2 = step * step;
      cs_step = S(1) - s2 / S(2) * (S(1) - s2 / S(12));
      sn_step = step * (S(1) - s2 / S(6) * (S(1) - s2 / S(20)));
    } else {
      cs_step = std::cos(step);
      sn_step = std::sin(step);
    }
    const S c2 = co * cs_step - si * sn_step, s2n = si * cs_step + co * sn_step;
    const S norm = S(1) / std::sqrt(c2 * c2 + s2n * s2n);
    co = c2 * norm;
    si = s2n * norm;
    if (std::abs(step) <= S(1e-7)) break;  // Newton's next step would be below 1e-14
  }
  cos_phi = co;
  sin_phi = si;
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
  const Vec3<S> bz = R.col(2);
  const auto sb = [&](const Vec3<S>& d) { return Vec3<S>(R * support(b, Vec3<S>(R.transpose() * d)) + t); };
  int calls = 0;
  const auto overlap = [&](const Vec3<S>& n) {
    ++calls;
    return n.dot(support(a, n)) - n.dot(sb(Vec3<S>(-n)));
  };
  S upper = std::numeric_limits<S>::infinity(), lower = S(0);
  Vec3<S> best_n = Vec3<S>::UnitZ(), best_x = Vec3<S>::Zero();
  const auto offer = [&](const Vec3<S>& n, const Vec3<S>& x, S lb) {
    lower = std::max(lower, lb);
    const S f = overlap(n);
    if (f < upper) {
      upper = f;
      best_n = n;
      best_x = x;
    }
  };
  const auto in_b = [&](const Vec3<S>& x) { return Vec3<S>(R.transpose() * (x - t)); };
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
  const auto decided = [&] { return upper - lower <= tolerance; };
  const auto rulings = [&] {  // ruling against ruling: n normal to both axes, towards b
    const S m = std::sqrt(bz.x() * bz.x() + bz.y() * bz.y());
    if (m > S(1e-6)) {
      Vec3<S> n(-bz.y() / m, bz.x() / m, S(0));
      if (n.dot(t) < S(0)) n = -n;
      const Vec3<S> tp = t - n.dot(t) * n;
      const S cb = bz.z(), w = S(1) - cb * cb;
      const S s2 = (cb * tp.z() - bz.dot(tp)) / w, s1 = tp.z() + cb * s2;  // s1 e_z - s2 bz = tp
      const S rho_a = std::min(a.radius, a.half_length - std::abs(s1)), rho_b = std::min(b.radius, b.half_length - std::abs(s2));
      if (rho_a >= S(0) && rho_b >= S(0)) {
        const Vec3<S> ca = (a.radius - rho_a) * n + Vec3<S>(S(0), S(0), s1);
        const Vec3<S> cbc = t - (b.radius - rho_b) * n + s2 * bz;
        // the two balls; and each ball against the whole other cylinder (a ball and a cylinder:
        // the ball's radius plus its centre's distance to the boundary), which holds deeper contacts
        S lb = rho_a + rho_b - (ca - cbc).norm();
        const InsideBall<S> in_a = inside_ball(a, cbc), in_b_ = inside_ball(b, in_b(ca));
        if (in_a.rho >= S(0)) lb = std::max(lb, rho_b + in_a.rho);
        if (in_b_.rho >= S(0)) lb = std::max(lb, rho_a + in_b_.rho);
        const Vec3<S> pa = a.radius * n + Vec3<S>(S(0), S(0), s1), pb = t - b.radius * n + s2 * bz;
        offer(n, Vec3<S>((pa + pb) / S(2)), lb);
      }
    }
  };
  // ruling of a against b's rims: the rim point nearest a's axis, pushed out radially
  const auto rims_of_b = [&] {
    for (const S s : {S(1), S(-1)}) {
      const Vec3<S> c = t + s * b.half_length * bz, u = b.radius * R.col(0), v = b.radius * R.col(1);
      S co, si;
      circle_nearest_z_axis(c, u, v, co, si);
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
      const Vec3<S> u = a.radius * R.row(0).transpose(), v = a.radius * R.row(1).transpose();
      S co, si;
      circle_nearest_z_axis(c, u, v, co, si);
      const Vec3<S> xb = c + co * u + si * v;
      const S rxy = std::sqrt(xb.x() * xb.x() + xb.y() * xb.y());
      const InsideBall<S> ball = inside_ball(b, xb);
      if (rxy > S(0) && ball.rho > S(0)) {
        const Vec3<S> x(co * a.radius, si * a.radius, s * a.half_length);
        offer(Vec3<S>(-(R * Vec3<S>(xb.x() / rxy, xb.y() / rxy, S(0)))), x, ball.rho);
      }
    }
  };
  if (!decided()) rulings();
  if (!decided()) rims_of_b();
  if (!decided()) rims_of_a();
  out.iterations = calls;
  out.normal = best_n;
  out.depth = upper;
  if (!(lower > S(0) && upper - lower <= tolerance)) return false;
  out.intersecting = true;
  out.normal = best_n;
  out.depth = std::max(upper, S(0));
  out.depth_gap = std::max(upper - lower, S(0));
  out.point = best_x;
  return true;
}

}  // namespace impact::detail
