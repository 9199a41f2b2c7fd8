// SPDX-License-Identifier: MIT
/// \file
/// A round shape (sphere or capsule: a core plus a radius) against any convex shape, for the pairs
/// without a closed form: the core's GJK distance minus the radius while the core stays clear (a
/// capsule's segment against a cylinder or a cone by convex/segment_cylinder.hpp and
/// convex/segment_cone.hpp), the own EPA on the core plus the radius when the core touches; a
/// capsule much longer than the other shape goes on as the part of it that decides
/// (capsule_window). Needs the impact::convex target (libccd).
#pragma once

#include "impact/convex/certified_pair.hpp"
#include "impact/convex/closed_form.hpp"
#include "impact/convex/general_pair.hpp"
#include "impact/convex/query_options.hpp"
#include "impact/convex/segment_cone.hpp"
#include "impact/convex/segment_cylinder.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace impact {
namespace detail {

/// GJK between a round shape's core (at pa) and shape b (at pb), as gjk(); a capsule's segment
/// against a cylinder or a cone by the certified 1-D minimisation of convex/segment_cylinder.hpp
/// and convex/segment_cone.hpp instead when the segment stays clear of it (GJK otherwise, with what
/// the search left of the bound). `plane` as gjk_distance's.
template <class S, class C, class B>
ConvexDistance<S> core_distance(const C& core, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, S tolerance,
                                int max_iterations, S margin = S(-1), bool stop_within_margin = true, Vec3<S>* plane = nullptr) {
  if constexpr (std::is_same_v<C, SegmentCore<S>> && (std::is_same_v<B, Cylinder<S>> || std::is_same_v<B, Cone<S>>)) {
    ConvexDistance<S> d;
    if constexpr (std::is_same_v<B, Cylinder<S>>) {
      if (segment_cylinder_distance(core.h, pa, b, pb, tolerance, margin, max_iterations, d, plane)) return d;
    } else {
      if (segment_cone_distance(core.h, pa, b, pb, tolerance, margin, max_iterations, d, plane)) return d;
    }
    // declined (the segment meets the solid or touches it): GJK with what is left of the bound
    const int spent = d.iterations;
    if (spent >= max_iterations) {
      ConvexDistance<S> none;  // undecided; the distance an upper bound
      none.distance = std::numeric_limits<S>::infinity();
      none.iterations = spent;
      none.limit_reached = true;
      if (plane) *plane = Vec3<S>::Zero();
      return none;
    }
    ConvexDistance<S> g = gjk(core, pa, core_interior(core), b, pb, interior_point(b), tolerance, max_iterations - spent, margin,
                              stop_within_margin, plane);
    g.iterations += spent;
    return g;
  }
  return gjk(core, pa, core_interior(core), b, pb, interior_point(b), tolerance, max_iterations, margin, stop_within_margin, plane);
}

/// The contact of round shape a (core + radius r) with b whose core is apart from b (core_distance
/// d, not intersecting, d.distance in (0, r]), along the better of two normals: the witnesses'
/// direction and GJK's best separating plane's (`plane`, zero if none). The depth is the overlap
/// along it (settled: an upper bound of the true depth), and depth_gap its distance to
/// r - d.distance, a lower bound (d.distance is an upper bound of the core's distance, a point of
/// the Minkowski difference). Why two normals: GJK's distance converges to its tolerance, its
/// witnesses' direction only to about the square root of it, and where the other shape has a kink
/// near the normal (a cone's apex and rim) the overlap along that direction stood up to 1.6e-9 of
/// the size above the depth, with a depth_gap of 0 (docs/convex-notes.md, note 30); along the
/// plane's normal the overlap is r minus GJK's lower bound, within its tolerance of the depth. A
/// bound that stops GJK early leaves the two ends far apart, and the gap says so (bounds 1-4: the
/// overlap along the first directions, up to twice the true depth).
template <class S, class R, class B>
ConvexContact<S> round_contact_apart(const R& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, const ConvexDistance<S>& d,
                                     const Vec3<S>& plane, S r) {
  ConvexContact<S> c;
  c.intersecting = true;
  // the witnesses' difference, normalised: GJK's distance and the witnesses' distance differ by
  // rounding (fuzzing: by 1.4e-3 of the distance in float, and the overlap along the unnormalised
  // normal was that much too deep)
  const Vec3<S> gap = d.point_b - d.point_a;
  const S len = gap.norm();
  c.normal = len > S(0) ? Vec3<S>(gap / len) : Vec3<S>(Vec3<S>::UnitZ());
  c.depth = r - d.distance;
  c.point = (d.point_a + r * c.normal + d.point_b) / S(2);
  settle_contact(a, pa, b, pb, c);
  const S plane_len = plane.norm();
  if (plane_len > S(0)) {
    ConvexContact<S> p = c;
    p.normal = -plane / plane_len;
    settle_contact(a, pa, b, pb, p);
    if (p.depth < c.depth) c = p;
  }
  c.depth_gap = std::max(c.depth - std::max(r - d.distance, S(0)), S(0));
  return c;
}

/// The part of capsule a (at pa) that decides its penetration with a shape b whose ball (centre cb
/// in the world, radius rb, shape_size about interior_point) is small beside a's length: the
/// capsule cut to the axis window |t - t0| <= L about b's centre's projection t0, L = 2 (rho + rb)
/// with rho the centre's distance to the axis (and kept where the window passes an end). Returns
/// false (a as it is) unless the window is less than half of a's segment and holds a point of it.
/// The boolean follows (the least overlap is >= 0 for both or for neither). With `distance`, also
/// false unless t0 lies on the segment: then p0's distance to b is at most rho (b holds its centre)
/// and every point outside the window is farther than L - rb >= rho from b, so the closest points
/// and the distance are the same too.
/// Why the depth is the same: the overlap along n of the cut capsule is r + g(n) + (its end's t -
/// t0) n_z, g(n) = n . p0 - min_b n . x (p0 = the axis point at t0) being Lipschitz with constant
/// max_b |p0 - x| <= rho + rb =: K. On a side where the window passes the end it equals the whole
/// capsule's; where it cuts, it is at least r + g(n) + L sin(theta) >= its value at n's projection
/// n' onto the plane normal to the axis (|n - n'| <= pi/2 sin(theta) and L >= pi/2 K), where the
/// two agree. So the least overlap, the depth, is the same, and the cut capsule, a subset, touches
/// b exactly when the whole does. What changes: tolerances relative to the cut length, and no
/// rounding of the axis' length along a normal that rounding tilted (a capsule 1e9 times longer
/// than wide across a cone had depths off by 1e-6 of its length that way: GJK's witness points at
/// 1e9 from each other, 1.5 apart, gave a normal tilted by 3e-7).
template <class S>
struct CapsuleCut {
  Capsule<S> capsule{S(1), S(0)};
  RigidTransform<S> pose;
  bool low = false, high = false;  ///< whether the window cuts the segment below, above
};
template <class S, class B>
bool capsule_window(const Capsule<S>& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, CapsuleCut<S>& cut,
                    bool distance = false) {
  const S h = a.half_length;
  const Vec3<S> cb = pa.R.transpose() * (pb.apply(interior_point(b)) - pa.t);  // in a's frame
  const S rho = std::sqrt(cb.x() * cb.x() + cb.y() * cb.y());
  const S len = S(2) * (rho + shape_size(b));
  if (!(S(2) * len < h)) return false;  // also for NaN
  if (distance && !(std::abs(cb.z()) <= h)) return false;
  const S t1 = std::max(cb.z() - len, -h), t2 = std::min(cb.z() + len, h);
  if (!(t1 <= t2)) return false;  // b's ball is more than 2 rho + 2 rb beyond an end
  cut.capsule.radius = a.radius;
  cut.capsule.half_length = (t2 - t1) / S(2);
  cut.pose.R = pa.R;
  cut.pose.t = pa.t + pa.R.col(2) * ((t1 + t2) / S(2));
  cut.low = t1 > -h;
  cut.high = t2 < h;
  return true;
}

/// The overlap of a capsule's segment (half length h along a's z axis, a's frame) and cylinder b
/// placed by R, t there, as the terms of convex/local_certificate.hpp: the segment is a cylinder of
/// radius 0. The capsule's overlap is this plus its radius, so the two share their minimiser.
template <class S>
OverlapTerms<S> segment_cylinder_terms(S h, const Cylinder<S>& b, const Mat3<S>& R, const Vec3<S>& t) {
  OverlapTerms<S> f;
  f.add(Vec3<S>::UnitZ(), h, false);
  f.add(R.col(2), b.radius, true);
  f.add(R.col(2), b.half_length, false);
  f.linear = -t;
  return f;
}

/// The same for cone b, with the cone's branch active along n (its apex, or its base rim, as
/// cylinder_cone_terms of convex/local_certificate.hpp); false where the two tie within 1e-6 of
/// the size (n a side normal: refine_on_cone_side's case).
template <class S>
bool segment_cone_terms(S h, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f) {
  f = OverlapTerms<S>();
  f.add(Vec3<S>::UnitZ(), h, false);
  return add_cone_branch_terms(b, R, t, n, f);
}

/// Round shape a (core + radius) against any shape b: exact from the core's distance unless the
/// core touches b. `flip` swaps the roles back for the caller (b was the round one). A capsule
/// much longer than b goes on as the part of it that decides (capsule_window).
template <class S, class R, class B>
ConvexContact<S> round_contact(const R& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                               const ConvexQueryOptions<S>& o, bool flip) {
  if constexpr (std::is_same_v<R, Capsule<S>>) {
    CapsuleCut<S> cut;
    if (capsule_window(a, pa, b, pb, cut)) {
      ConvexContact<S> c = round_contact(cut.capsule, cut.pose, b, pb, o, false);
      // The whole capsule overlaps more than the cut one along a normal with a component towards
      // a cut side, by the length cut off times that component (4e-11 of a tilt, within the cut
      // query's tolerance, times 4e9). Dropping the component does not raise the cut capsule's
      // overlap (capsule_window's bound), and there the two agree.
      const Vec3<S> u = pa.R.col(2);
      const S nz = c.normal.dot(u);
      if (c.intersecting && ((nz > S(0) && cut.high) || (nz < S(0) && cut.low))) {
        const Vec3<S> m = c.normal - nz * u;
        const S len = m.norm();
        if (len > S(0)) {
          const S lower = c.depth - c.depth_gap;
          c.normal = m / len;
          settle_contact(a, pa, b, pb, c);
          c.depth_gap = std::max(c.depth - lower, S(0));
        }
      }
      if (flip) c.normal = -c.normal;
      return c;
    }
  }
  const auto core = core_of(a);
  const S scale = query_scale<S>(a, b);
  const S tol = o.relative_tolerance * scale;
  const S r = round_radius(a);
  // the radius as margin, stopping only when the core is farther than it (no contact: the common
  // case, decided as cheaply as the boolean); else converged as without a margin
  Vec3<S> plane = Vec3<S>::Zero();
  const ConvexDistance<S> d = core_distance(core, pa, b, pb, tol, o.max_iterations, r, false, &plane);
  if (!d.intersecting && d.distance > tol) {
    if (d.distance > r) {
      ConvexContact<S> c;
      c.iterations = d.iterations;
      c.limit_reached = d.limit_reached;
      return c;
    }
    ConvexContact<S> c = round_contact_apart(a, pa, b, pb, d, plane, r);
    c.iterations = d.iterations;
    c.limit_reached = d.limit_reached;
    if (flip) c.normal = -c.normal;
    return c;
  }
  // the core meets b: EPA on the core, plus the radius, with what GJK left of the bound
  ConvexQueryOptions<S> rest;
  if (!budget_left(o, d.iterations, rest)) return out_of_budget<S>(d.iterations);
  int epa_calls = 0;  // of a failed own EPA
  if (!o.libccd_penetration) {
    bool failed = false;
    ConvexContact<S> c = own_epa(core, pa, core_interior(core), b, pb, interior_point(b), scale, rest, failed);
    epa_calls = c.iterations;
    if (!failed) {
      c.iterations += d.iterations;
      const bool epa_stopped = c.limit_reached;  // the bound, not a plane, ended EPA's GJK
      c.limit_reached = c.limit_reached || d.limit_reached;
      if (!c.intersecting) {
        // The core comes within GJK's tolerance of b, and EPA's GJK found a plane between them: the
        // depth is at most r (the core is apart) and at least r minus GJK's distance, an upper
        // bound of the core's (the tolerance where GJK called them touching). Along GJK's line.
        // Settled, the depth stays at most r: the overlap along a normal that is off by rounding
        // grows with the shape's length (fuzzing: a needle capsule 2^42 times longer than wide,
        // 0.003 beside a box, was given a depth of 1.7e5 from the overlap along such a normal).
        const Vec3<S> gap = d.point_b - d.point_a;
        const S len = d.intersecting ? S(0) : gap.norm();
        const S apart = d.intersecting ? tol : d.distance;
        c.intersecting = true;
        c.normal = len > S(0) ? Vec3<S>(gap / len) : Vec3<S>(Vec3<S>::UnitZ());
        // When the bound stopped EPA's GJK, no plane was found and the core may overlap b: the depth
        // is then bounded above only by the overlap along the normal (sphere against hull, bounds
        // 5-7 left by the core's GJK: a depth of r, 0.5, bracketed within 6e-11, for a true 0.55).
        c.depth = epa_stopped ? std::numeric_limits<S>::infinity() : r;
        c.point = (d.point_a + d.point_b) / S(2);
        settle_certified_contact(a, pa, b, pb, c);
        c.depth_gap = std::max(c.depth - std::max(r - apart, S(0)), S(0));
      } else {  // EPA's depth plus the radius is the overlap along its normal too: settled, the smaller
        c.depth += r;
        settle_certified_contact(a, pa, b, pb, c);
        // EPA stops on its depth's tolerance; its normal is then within only about the square root
        // of it of the minimiser where the overlap is smooth (a capsule's segment through a
        // cylinder: up to 2.6e-5 rad, docs/convex-notes.md, note 32): Newton from EPA's normal on
        // the overlap's closed form (refine_normal_locally), kept where it is no deeper; their
        // support calls count in the query's bound (one budget)
        if constexpr (std::is_same_v<R, Capsule<S>> && std::is_same_v<B, Cylinder<S>>) {
          const PairFrame<S> f(pa, pb);
          refine_normal_locally(a, pa, b, pb, segment_cylinder_terms(a.half_length, b, f.R, f.t), c, o.max_iterations);
          // the normal across the segment near the cylinder's axis: the terms' certificate jumps
          // to the axis (its disc kink); the valley of the segment's normals (note 34)
          refine_on_capsule_segment(a, pa, b, pb, c, o.max_iterations);
        } else if constexpr (std::is_same_v<R, Capsule<S>> && std::is_same_v<B, Cone<S>>) {
          const PairFrame<S> f(pa, pb);
          OverlapTerms<S> terms;
          if (segment_cone_terms(a.half_length, b, f.R, f.t, Vec3<S>(pa.R.transpose() * c.normal), terms)) {
            refine_normal_locally(a, pa, b, pb, terms, c, o.max_iterations);
          }
          refine_on_cone_side(a, pa, b, pb, c, o.max_iterations);
        }
      }
      if (flip) c.normal = -c.normal;
      return c;
    }
  }
  // libccd on the whole shapes, with what GJK and a failed own EPA left of the bound
  const int spent = d.iterations + epa_calls;
  if (!budget_left(o, spent, rest)) return out_of_budget<S>(spent);
  ConvexContact<S> l = flip ? epa(b, pb, a, pa, rest) : epa(a, pa, b, pb, rest);
  l.iterations += spent;
  return l;
}

template <class S, class R, class B>
ConvexDistance<S> round_distance(const R& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                 const ConvexQueryOptions<S>& o) {
  if constexpr (std::is_same_v<R, Capsule<S>>) {  // a needle: the part of it that decides
    CapsuleCut<S> cut;
    if (capsule_window(a, pa, b, pb, cut, true)) return round_distance(cut.capsule, cut.pose, b, pb, o);
  }
  const auto core = core_of(a);
  const S tol = o.relative_tolerance * query_scale<S>(a, b);
  ConvexDistance<S> d = core_distance(core, pa, b, pb, tol, o.max_iterations);
  const S r = round_radius(a);
  if (d.intersecting || d.distance <= r) {
    d.intersecting = true;
    d.distance = S(0);
    return d;
  }
  const Vec3<S> n = (d.point_b - d.point_a) / d.distance;
  d.point_a += r * n;
  d.distance -= r;
  return d;
}

}  // namespace detail
}  // namespace impact
