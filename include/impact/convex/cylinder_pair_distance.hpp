// SPDX-License-Identifier: MIT
/// \file
/// The separation distance of two cylinders (convex_distance's cylinder–cylinder path in
/// convex/query.hpp), with GJK run only to a coarse gap and the closest features then found in
/// closed form or by Newton on one angle, the answer certified by the supports along its direction.
///
/// GJK converges only linearly between curved surfaces (on the bench's poses about two support
/// calls per decade of the gap: 6 to reach 1e-2 of the size, 21 to reach 1e-10). So:
///   1. the boolean test of convex/cylinder_intersect.hpp: when it proves contact, distance 0;
///   2. GJK to a gap of kCylinderDistanceCoarse of the size, whose witness points name the nearest
///      features roughly;
///   3. candidates, each a point x of a and a point y of b: a cap of a against b's lowest point
///      across it (and b's cap against a's), the two sides (the axes' common normal, both feet inside
///      their segments), a rim against the other's side (Newton on the rim's angle for the point
///      nearest the other's axis line), and rim against rim (Newton on b's rim angle, a's nearest
///      rim point in closed form);
///   4. the best, |y - x| = D, is certified by the planes normal to n = (y - x) / D supporting each
///      cylinder: their gap L = n . s_b(-n) - n . s_a(n) is a lower bound of the distance and D an
///      upper bound, so D is returned when D - L <= tolerance: the same contract as GJK's;
///   5. otherwise GJK again, to the tolerance, from the coarse run's direction.
///
/// Numerical contract: APPROXIMATE, as GJK's (convex/gjk_distance.hpp): d - tolerance <= d* <= d
/// up to rounding, witnesses points of the two cylinders d apart; intersecting when the boolean
/// test proves contact or GJK finds the distance within the tolerance; limit_reached as GJK's.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/cylinder_intersect.hpp"
#include "impact/convex/general_pair.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>

namespace impact::detail {

/// GJK's first run stops at this gap, relative to the pair's size.
inline constexpr double kCylinderDistanceCoarse = 3e-2;

/// A candidate pair of closest points: x in a, y in b (a's frame); valid when set.
template <class S>
struct CylinderDistanceCandidate {
  Vec3<S> x = Vec3<S>::Zero(), y = Vec3<S>::Zero();
  S d2 = std::numeric_limits<S>::infinity();  ///< |y - x|^2
  void offer(const Vec3<S>& px, const Vec3<S>& py) {
    const S e = (py - px).squaredNorm();
    if (e < d2) {
      x = px;
      y = py;
      d2 = e;
    }
  }
};

/// One Newton step on an angle t, (c, s) = (cos t, sin t), for a stationary point of a function
/// whose half first and second derivatives in t are d1 and d2 (a fixed step of 0.5 downhill where
/// d2 is not positive; every step clamped to 0.5 rad); true when the step fell below 1e-7 rad.
template <class S>
bool newton_angle_step(S d1, S d2, S& c, S& s) {
  S step = d2 > S(0) ? -d1 / d2 : (d1 > S(0) ? S(-0.5) : S(0.5));
  step = std::clamp(step, S(-0.5), S(0.5));
  const S cs = std::cos(step), sn = std::sin(step);
  const S nc = c * cs - s * sn;
  s = s * cs + c * sn;
  c = nc;
  return std::abs(step) < S(1e-7);
}

/// Newton on the angle of the circle c0 + rho (cos t e1 + sin t e2) (e1, e2 orthonormal) for its
/// point nearest the line q0 + s v (v unit), from (c, s) = (cos t, sin t); returns the point.
template <class S>
Vec3<S> circle_nearest_line(const Vec3<S>& c0, const Vec3<S>& e1, const Vec3<S>& e2, S rho, const Vec3<S>& q0, const Vec3<S>& v, S c,
                            S s) {
  const Vec3<S> w0 = c0 - q0;
  const S g1 = w0.dot(e1), g2 = w0.dot(e2), g0 = w0.dot(v), a1 = e1.dot(v), a2 = e2.dot(v);
  for (int k = 0; k < 8; ++k) {
    // f = |w|^2 - (w . v)^2 for w = x(t) - q0; half its first and second derivatives
    const S wv = g0 + rho * (c * a1 + s * a2), xv = rho * (c * a2 - s * a1);
    const S f1 = rho * (c * g2 - s * g1) - wv * xv;
    const S f2 = -rho * (c * g1 + s * g2) - xv * xv + wv * rho * (c * a1 + s * a2);
    if (newton_angle_step(f1, f2, c, s)) break;
  }
  return c0 + rho * (c * e1 + s * e2);
}

/// Newton on the angle of the circle c0 + rho (cos t e1 + sin t e2) for its point nearest the
/// circle of radius r about the z axis at height zc (a's rim), from (c, s); returns false when the
/// point comes near the z axis (the nearest rim point is not defined there).
template <class S>
bool circle_nearest_rim(const Vec3<S>& c0, const Vec3<S>& e1, const Vec3<S>& e2, S rho, S r, S zc, S c, S s, Vec3<S>& point) {
  for (int k = 0; k < 8; ++k) {
    const Vec3<S> u = c * e1 + s * e2, x = c0 + rho * u, x1 = rho * (c * e2 - s * e1), x2 = -rho * u;
    const S q = std::sqrt(x.x() * x.x() + x.y() * x.y());
    if (!(q > S(1e-6) * r)) return false;
    const S q1 = (x.x() * x1.x() + x.y() * x1.y()) / q;
    const S q2 = (x1.x() * x1.x() + x1.y() * x1.y() + x.x() * x2.x() + x.y() * x2.y()) / q - q1 * q1 / q;
    // g = (q - r)^2 + (x_z - zc)^2; half its derivatives
    const S g1 = (q - r) * q1 + (x.z() - zc) * x1.z();
    const S g2 = q1 * q1 + (q - r) * q2 + x1.z() * x1.z() + (x.z() - zc) * x2.z();
    if (newton_angle_step(g1, g2, c, s)) break;
  }
  point = c0 + rho * (c * e1 + s * e2);
  return true;
}

/// The point of the side of a cylinder (axis q0 + s v, |s| <= h, radius r) nearest a point x
/// outside it, offered with x when its foot on the axis lies on the segment (x_first: x is a's).
template <class S>
void offer_side_point(CylinderDistanceCandidate<S>& best, const Vec3<S>& x, const Vec3<S>& q0, const Vec3<S>& v, S h, S r,
                      bool x_first) {
  const S sx = (x - q0).dot(v);
  if (!(std::abs(sx) <= h)) return;
  const Vec3<S> foot = q0 + sx * v, off = x - foot;
  const S len = off.norm();
  if (!(len > r)) return;
  const Vec3<S> side = foot + (r / len) * off;
  if (x_first)
    best.offer(x, side);
  else
    best.offer(side, x);
}

/// Distance of cylinder a (pose pa) and b (pose pb) by the steps of the file comment.
template <class S>
ConvexDistance<S> cylinder_pair_distance(const Cylinder<S>& a, const RigidTransform<S>& pa, const Cylinder<S>& b, const RigidTransform<S>& pb,
                                         S scale, S tolerance, int max_iterations) {
  const PairFrame<S> f(pa, pb);
  const Mat3<S>& R = f.R;
  const Vec3<S>& t = f.t;
  ConvexDistance<S> out;
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const auto to_world = [&](ConvexDistance<S> r) {
    r.point_a = pa.apply(r.point_a);
    r.point_b = pa.apply(r.point_b);
    return r;
  };
  // max_iterations is one budget for the whole query: each GJK run gets what the runs before it
  // left (`spent` support calls so far), the query's iterations are their sum (and one for the
  // certificate of step 4), and a stage that finds nothing left returns the last run's answer
  // with limit_reached.
  int spent = 0;
  ConvexDistance<S> run;
  {  // 1. contact proven by the boolean test
    bool limit = false;
    const bool hit = cylinder_pair_intersect(a, b, R, t, scale, tolerance, max_iterations, limit, &run);
    spent = run.iterations;
    if (hit) {
      out.intersecting = true;
      out.limit_reached = limit;
      out.iterations = spent;
      out.point_a = pa.t;
      out.point_b = pb.t;
      return out;
    }
  }
  // `r` (an upper bound and its witnesses), as the query's answer stopped by the bound
  const auto stopped = [&](ConvexDistance<S> r) {
    r.iterations = spent;
    r.limit_reached = true;
    return to_world(r);
  };
  if (run.limit_reached || spent >= max_iterations) return stopped(run);
  // 2. GJK to a coarse gap, with what the boolean test left
  const S coarse = std::max(tolerance, S(kCylinderDistanceCoarse) * scale);
  const ConvexDistance<S> g = gjk_distance<S>(sa, sb, Vec3<S>(-t), coarse, max_iterations - spent);
  spent += g.iterations;
  if (spent >= max_iterations) return stopped(g);
  if (g.limit_reached) {  // a rounding stall: GJK again to the tolerance, from the start
    ConvexDistance<S> r = gjk_distance<S>(sa, sb, Vec3<S>(-t), tolerance, max_iterations - spent);
    r.iterations += spent;
    return to_world(r);
  }
  // 3. candidates
  CylinderDistanceCandidate<S> best;
  const Vec3<S> v = R.col(2), e1b = R.col(0), e2b = R.col(1);
  const S ra = a.radius, ha = a.half_length, rb = b.radius, hb = b.half_length;
  const Vec3<S> wa = g.point_a, wbb = R.transpose() * (g.point_b - t);  // b's witness in b's frame
  const S sza = wa.z() >= S(0) ? S(1) : S(-1), szb = wbb.z() >= S(0) ? S(1) : S(-1);
  {  // a's cap against b's lowest point across it
    const Vec3<S> y = sb(Vec3<S>(S(0), S(0), -sza));
    if (sza * y.z() > ha && y.x() * y.x() + y.y() * y.y() <= ra * ra) best.offer(Vec3<S>(y.x(), y.y(), sza * ha), y);
  }
  {  // b's cap against a's lowest point across it
    const Vec3<S> x = sa(Vec3<S>(-szb * v)), xb = R.transpose() * (x - t);
    if (szb * xb.z() > hb && xb.x() * xb.x() + xb.y() * xb.y() <= rb * rb) best.offer(x, Vec3<S>(R * Vec3<S>(xb.x(), xb.y(), szb * hb) + t));
  }
  {  // side against side: the axes' common normal
    const S uv = v.z(), ut = t.z(), vt = v.dot(t), den = S(1) - uv * uv;
    if (den > S(1e-12)) {
      const S s = (ut - uv * vt) / den, r = (uv * ut - vt) / den;
      if (std::abs(s) < ha && std::abs(r) < hb) {
        // each side point along q - p made normal to its own axis, so that rounding in s and r
        // (nearly parallel axes) leaves them on the sides, the certificate deciding the rest
        const Vec3<S> p(S(0), S(0), s), q = t + r * v, pq = q - p, mb = pq - pq.dot(v) * v;
        const S la = std::sqrt(pq.x() * pq.x() + pq.y() * pq.y()), lb = mb.norm();
        if (la > ra + rb && lb > S(0))
          best.offer(Vec3<S>(ra * pq.x() / la, ra * pq.y() / la, s), Vec3<S>(q - (rb / lb) * mb));
      }
    }
  }
  const S qa = std::sqrt(wa.x() * wa.x() + wa.y() * wa.y()), qb = std::sqrt(wbb.x() * wbb.x() + wbb.y() * wbb.y());
  if (qa > S(0)) {  // a's rim against b's side
    const Vec3<S> x = circle_nearest_line<S>(Vec3<S>(S(0), S(0), sza * ha), Vec3<S>::UnitX(), Vec3<S>::UnitY(), ra, t, v, wa.x() / qa,
                                             wa.y() / qa);
    offer_side_point<S>(best, x, t, v, hb, rb, true);
  }
  if (qb > S(0)) {
    const Vec3<S> cb = t + szb * hb * v;
    // b's rim against a's side
    const Vec3<S> y = circle_nearest_line<S>(cb, e1b, e2b, rb, Vec3<S>::Zero(), Vec3<S>::UnitZ(), wbb.x() / qb, wbb.y() / qb);
    offer_side_point<S>(best, y, Vec3<S>::Zero(), Vec3<S>::UnitZ(), ha, ra, false);
    // rim against rim
    Vec3<S> y2;
    if (circle_nearest_rim<S>(cb, e1b, e2b, rb, ra, sza * ha, wbb.x() / qb, wbb.y() / qb, y2)) {
      const S q = std::sqrt(y2.x() * y2.x() + y2.y() * y2.y());
      best.offer(Vec3<S>(ra * y2.x() / q, ra * y2.y() / q, sza * ha), y2);
    }
  }
  // 4. certified by the supporting planes normal to the best candidate's direction
  if (best.d2 < std::numeric_limits<S>::infinity()) {
    const S D = std::sqrt(best.d2);
    if (D > tolerance) {
      const Vec3<S> n = (best.y - best.x) / D;
      const S lower = n.dot(sb(Vec3<S>(-n))) - n.dot(sa(n));
      if (D - lower <= tolerance) {
        out.distance = D;
        out.point_a = pa.apply(best.x);
        out.point_b = pa.apply(best.y);
        out.iterations = spent + 1;
        return out;
      }
    }
  }
  // 5. GJK to the tolerance from the coarse direction
  ConvexDistance<S> r = gjk_distance<S>(sa, sb, Vec3<S>(g.point_a - g.point_b), tolerance, max_iterations - spent);
  r.iterations += spent;
  return to_world(r);
}

}  // namespace impact::detail
