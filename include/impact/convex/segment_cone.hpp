// SPDX-License-Identifier: MIT
/// \file
/// Distance between a segment (a capsule's core) and a solid cone, certified, for the capsule–cone
/// penetration and distance (convex/round_shape_pair.hpp) instead of GJK on the core: the convex
/// 1-D minimisation of convex/segment_cylinder.hpp over the segment's parameter, with the cone's
/// closest point to a point in closed form (cone_point, convex/closed_form.hpp). Why not GJK: its
/// distance converges to the tolerance, but the direction of its witness points only to about the
/// square root of it (up to 2.6e-5 rad on the bench's poses where the cone's apex and rim tie near
/// the normal), and a normal certified through GJK's lower bound cost 16 % more instructions
/// (docs/convex-notes.md, notes 29 and 30). Here the slope f'(t) = d . n is driven to 1e-3 of the
/// tolerance, so n, the unit direction from the cone's closest point to the segment's (the face's
/// normal on the side or the base, cone_point), is the normal of the least distance to within that
/// over f's curvature along the segment; the minimum is found in about 11 evaluations of
/// cone_point against GJK's 17 support calls with simplex updates.
///
/// Numerical contract: APPROXIMATE, as GJK's: the distance is an upper bound within `tolerance`
/// of the true one (up to rounding). Declines (returns false, the caller runs GJK) when the segment
/// meets the cone, when the distance is within the tolerance of 0, or after 64 evaluations; the
/// caller's bound on the evaluations is kept (ConvexQueryOptions::max_iterations: one budget).
/// Thread safety: a pure function.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/segment_cylinder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// The segment of half length h along a's z axis (pose pa) against cone c (pose pc): true and
/// `out` set (distance, point_a on the segment, point_b on the cone, world; iterations counts the
/// evaluations of f) when the segment stays more than `tolerance` from the cone; `plane` (world)
/// then receives the unit direction from the cone's closest point towards the segment's (GJK's v
/// of gjk_distance: the normal from the segment towards the cone is -plane). With `margin` >= 0
/// it may stop as soon as the distance is proven above the margin (then not converged: `out` holds
/// an upper bound above the margin). At most `max_evaluations` evaluations of f: when they run out
/// (below 64) `out` holds the nearest point evaluated, an upper bound, with limit_reached set.
/// Declined, out.iterations still counts the evaluations spent.
template <class S>
bool segment_cone_distance(S h, const RigidTransform<S>& pa, const Cone<S>& c, const RigidTransform<S>& pc, S tolerance, S margin,
                           int max_evaluations, ConvexDistance<S>& out, Vec3<S>* plane = nullptr) {
  const RigidTransform<S> rel = pc.inverse() * pa;  // a's frame into the cone's
  const Vec3<S> p0 = rel.apply(Vec3<S>(S(0), S(0), -h)), d = rel.rotate(Vec3<S>(S(0), S(0), S(2) * h));
  const auto eval = [&](S t) {
    SegmentSolidPoint<S> e;
    e.t = t;
    e.p = p0 + t * d;
    const ConePoint<S> q = cone_point(c, e.p);
    e.f = q.distance;
    e.q = q.closest;
    e.n = q.outward;
    e.g = e.f > S(0) ? d.dot(q.outward) : S(0);
    return e;
  };
  // The normal's error is about the slope at the stop over f's curvature along the segment: a
  // stop at 1e-3 of the tolerance (a few more evaluations, superlinear) keeps it below 1e-6 rad
  // where the segment is nearly parallel to a flat direction of the cone (a ruling, the base); not
  // below the slope's rounding (float: 1e-3 of its tolerance is below it)
  const S stop = std::max(S(1e-3) * tolerance, S(16) * std::numeric_limits<S>::epsilon() * d.norm());
  SegmentSolidPoint<S> best;
  int evaluations = 0;
  const SegmentSearch r = segment_solid_minimum(eval, tolerance, stop, margin, max_evaluations, best, evaluations);
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
