// SPDX-License-Identifier: MIT
/// \file
/// Distance between a segment (a capsule's core) and a solid cylinder, certified, for the capsule–
/// cylinder queries (convex/query.hpp) instead of GJK on the core. In the cylinder's frame the
/// distance from the segment's point p(t) = p0 + t (p1 - p0) to the cylinder, f(t), is convex in
/// t and differentiable where positive (f' = d . (p - q) / |p - q|, q the cylinder's closest point
/// to p: a radial and an axial clamp). Its minimum over [0, 1] is at an end where f' does not
/// point inwards, else at the root of f', found by regula falsi (Illinois) on the bracket; it stops
/// at a t with |f'(t)| <= tolerance, where convexity gives f >= f(t) - |f'(t)| on [0, 1] and the
/// direction p - q is normal to the segment within the tolerance.
///
/// Numerical contract: APPROXIMATE, as GJK's: the distance is an upper bound within `tolerance`
/// of the true one (up to rounding). Declines (returns false, the caller runs GJK) when the segment
/// meets the cylinder, when the distance is within the tolerance of 0, or after 64 evaluations.
/// Thread safety: a pure function.
#pragma once

#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <cmath>

namespace impact::detail {

/// The segment of half length h along a's z axis (pose pa) against cylinder c (pose pc): true and
/// `out` set (distance, point_a on the segment, point_b on the cylinder, world; iterations counts
/// the evaluations of f) when the segment stays more than `tolerance` from the cylinder.
template <class S>
bool segment_cylinder_distance(S h, const RigidTransform<S>& pa, const Cylinder<S>& c, const RigidTransform<S>& pc, S tolerance,
                               ConvexDistance<S>& out) {
  const RigidTransform<S> rel = pc.inverse() * pa;  // a's frame into the cylinder's
  const Vec3<S> p0 = rel.apply(Vec3<S>(S(0), S(0), -h)), d = rel.rotate(Vec3<S>(S(0), S(0), S(2) * h));
  struct Eval {
    S t, f, g;
    Vec3<S> p, q;
  };
  const auto eval = [&](S t) {
    Eval e;
    e.t = t;
    e.p = p0 + t * d;
    const S rxy = std::sqrt(e.p.x() * e.p.x() + e.p.y() * e.p.y());
    const S s = rxy > c.radius ? c.radius / rxy : S(1);
    e.q = Vec3<S>(e.p.x() * s, e.p.y() * s, std::clamp(e.p.z(), -c.half_length, c.half_length));
    const Vec3<S> v = e.p - e.q;
    e.f = v.norm();
    e.g = e.f > S(0) ? d.dot(v) / e.f : S(0);
    return e;
  };
  Eval a = eval(S(0)), b = eval(S(1));
  int evaluations = 2;
  const auto done = [&](const Eval& e) {
    if (!(e.f > tolerance)) return false;  // touching within the tolerance: GJK decides as before
    out.distance = e.f;
    out.point_a = pc.apply(e.p);
    out.point_b = pc.apply(e.q);
    out.intersecting = false;
    out.limit_reached = false;
    out.iterations = evaluations;
    return true;
  };
  if (!(a.f > S(0) && b.f > S(0))) return false;
  if (a.g >= S(0)) return done(a);  // f increases from t = 0
  if (b.g <= S(0)) return done(b);  // f decreases up to t = 1
  S ga = a.g, gb = b.g;  // Illinois-scaled slopes for the next abscissa
  int side = 0;
  while (evaluations < 64) {
    S t = (a.t * gb - b.t * ga) / (gb - ga);
    if (!(t > a.t && t < b.t)) t = (a.t + b.t) / S(2);
    const Eval m = eval(t);
    ++evaluations;
    if (!(m.f > S(0))) return false;  // the segment meets the cylinder
    // f(s) >= f(t) + f'(t) (s - t) >= f(t) - |f'(t)| on [0, 1]: within the tolerance of the least
    // distance, and the direction p - q normal to the segment within it (the witness points are
    // then the supports of the capsule and the cylinder along it)
    if (std::abs(m.g) <= tolerance) return done(m);
    if (m.g < S(0)) {
      a = m;
      ga = m.g;
      if (side == -1) gb /= S(2);
      side = -1;
    } else {
      b = m;
      gb = m.g;
      if (side == 1) ga /= S(2);
      side = 1;
    }
  }
  return false;
}

}  // namespace impact::detail
