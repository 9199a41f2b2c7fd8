// SPDX-License-Identifier: MIT
/// \file
/// Distance between a segment (a capsule's core) and a solid cylinder, certified, for the capsule–
/// cylinder queries (convex/query.hpp) instead of GJK on the core; the 1-D minimisation is shared
/// with the segment against a cone (convex/segment_cone.hpp). In the solid's frame the distance
/// from the segment's point p(t) = p0 + t (p1 - p0) to the solid, f(t), is convex in t and
/// differentiable where positive (f' = d . n, n = (p - q) / |p - q| the unit direction from q, the
/// solid's closest point to p; for the cylinder q is a radial and an axial clamp). Its minimum over
/// [0, 1] is at an end where f' does not point inwards, else at the root of f', found by regula
/// falsi (Illinois) on the bracket; it stops at a t with |f'(t)| <= the stopping slope, where
/// convexity gives f >= f(t) - |f'(t)| on [0, 1] and the direction p - q is normal to the segment
/// within it.
///
/// Numerical contract: APPROXIMATE, as GJK's: the distance is an upper bound within `tolerance`
/// of the true one (up to rounding). Declines (returns false, the caller runs GJK) when the segment
/// meets the solid, when the distance is within the tolerance of 0, or after 64 evaluations; the
/// caller's bound on the evaluations is kept (ConvexQueryOptions::max_iterations: one budget).
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// One evaluation of f at t: the segment's point p, the solid's closest point q, f = |p - q|, its
/// slope g = f'(t) and (where the evaluator gives it) n, the unit direction from q towards p, all
/// in the solid's frame.
template <class S>
struct SegmentSolidPoint {
  S t = S(0), f = S(0), g = S(0);
  Vec3<S> p = Vec3<S>::Zero(), q = Vec3<S>::Zero(), n = Vec3<S>::Zero();
};

/// How segment_solid_minimum ended.
enum class SegmentSearch {
  Answered,  ///< converged: `best` within the tolerance of the least f (or proven above the margin)
  Declined,  ///< the segment meets the solid, comes within the tolerance of it, or 64 evaluations
  Bound,     ///< `max_evaluations` (below 64) ran out: `best` is the nearest point evaluated
};

/// The least f over [0, 1] (the file comment) from eval(t) -> SegmentSolidPoint<S>, in at most
/// min(64, max_evaluations) calls of eval (counted in `evaluations`). Answered with `best` set when
/// the segment stays more than `tolerance` from the solid; it stops at a slope within
/// `stop_slope`, or, with `margin` >= 0, as soon as the tangents at the bracket's ends put f above
/// the margin everywhere (then `best` is the nearest point evaluated, farther than the margin: an
/// upper bound of the distance, not converged).
template <class S, class Eval>
SegmentSearch segment_solid_minimum(const Eval& eval, S tolerance, S stop_slope, S margin, int max_evaluations, SegmentSolidPoint<S>& best,
                                    int& evaluations) {
  const int cap = std::min(64, max_evaluations);
  SegmentSolidPoint<S> a = eval(S(0));
  evaluations = 1;
  if (!(a.f > S(0))) return SegmentSearch::Declined;
  if (cap < 2) {
    best = a;
    return SegmentSearch::Bound;
  }
  SegmentSolidPoint<S> b = eval(S(1));
  evaluations = 2;
  const auto done = [&](const SegmentSolidPoint<S>& e) {
    if (!(e.f > tolerance)) return SegmentSearch::Declined;  // touching within the tolerance: GJK decides as before
    best = e;
    return SegmentSearch::Answered;
  };
  if (!(b.f > S(0))) return SegmentSearch::Declined;
  if (a.g >= S(0)) return done(a);  // f increases from t = 0
  if (b.g <= S(0)) return done(b);  // f decreases up to t = 1
  // f >= max of the tangents at a and b on [a.t, b.t]: their crossing's value is a lower bound of f
  const auto clear_of_margin = [&]() {
    if (!(margin >= S(0))) return false;
    const S s = (b.f - a.f + a.g * a.t - b.g * b.t) / (a.g - b.g);
    return a.f + a.g * (s - a.t) > margin;
  };
  S ga = a.g, gb = b.g;  // Illinois-scaled slopes for the next abscissa
  int side = 0;
  while (evaluations < cap) {
    if (clear_of_margin()) return done(a.f < b.f ? a : b);
    // the bracket shrunk to rounding: f' changes sign between two neighbouring abscissae
    if (!(b.t - a.t > S(8) * std::numeric_limits<S>::epsilon())) return done(a.f < b.f ? a : b);
    S t = (a.t * gb - b.t * ga) / (gb - ga);
    if (!(t > a.t && t < b.t)) t = (a.t + b.t) / S(2);
    const SegmentSolidPoint<S> m = eval(t);
    ++evaluations;
    if (!(m.f > S(0))) return SegmentSearch::Declined;  // the segment meets the solid
    // f(s) >= f(t) + f'(t) (s - t) >= f(t) - |f'(t)| on [0, 1]: within the tolerance of the least
    // distance, and the direction p - q normal to the segment within it (the witness points are
    // then the supports of the capsule and the solid along it)
    if (std::abs(m.g) <= stop_slope) return done(m);
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
  if (cap == 64) return SegmentSearch::Declined;
  best = a.f < b.f ? a : b;
  return SegmentSearch::Bound;
}

/// The segment of half length h along a's z axis (pose pa) against cylinder c (pose pc): true and
/// `out` set (distance, point_a on the segment, point_b on the cylinder, world; iterations counts
/// the evaluations of f) when the segment stays more than `tolerance` from the cylinder; `plane`
/// (world) then receives the unit direction from the cylinder's closest point towards the
/// segment's. `margin` and `max_evaluations` as segment_cone_distance's (convex/segment_cone.hpp):
/// one budget with the caller's (ConvexQueryOptions::max_iterations); when it runs out (below 64)
/// `out` holds the nearest point evaluated, an upper bound, with limit_reached set. Declined,
/// out.iterations still counts the evaluations spent.
template <class S>
bool segment_cylinder_distance(S h, const RigidTransform<S>& pa, const Cylinder<S>& c, const RigidTransform<S>& pc, S tolerance, S margin,
                               int max_evaluations, ConvexDistance<S>& out, Vec3<S>* plane = nullptr) {
  const RigidTransform<S> rel = pc.inverse() * pa;  // a's frame into the cylinder's
  const Vec3<S> p0 = rel.apply(Vec3<S>(S(0), S(0), -h)), d = rel.rotate(Vec3<S>(S(0), S(0), S(2) * h));
  const auto eval = [&](S t) {
    SegmentSolidPoint<S> e;
    e.t = t;
    e.p = p0 + t * d;
    const S rxy = std::sqrt(e.p.x() * e.p.x() + e.p.y() * e.p.y());
    const S s = rxy > c.radius ? c.radius / rxy : S(1);
    e.q = Vec3<S>(e.p.x() * s, e.p.y() * s, std::clamp(e.p.z(), -c.half_length, c.half_length));
    const Vec3<S> v = e.p - e.q;
    e.f = v.norm();
    if (e.f > S(0)) {
      e.n = v / e.f;
      e.g = d.dot(e.n);
    }
    return e;
  };
  SegmentSolidPoint<S> best;
  int evaluations = 0;
  const SegmentSearch r = segment_solid_minimum(eval, tolerance, tolerance, margin, max_evaluations, best, evaluations);
  out.iterations = evaluations;
  if (r == SegmentSearch::Declined) return false;
  out.distance = best.f;
  out.point_a = pc.apply(best.p);
  out.point_b = pc.apply(best.q);
  out.intersecting = false;
  out.limit_reached = r == SegmentSearch::Bound;
  if (plane) *plane = pc.rotate(best.n);
  return true;
}

}  // namespace impact::detail
