// SPDX-License-Identifier: MIT
/// \file
/// The general path of a convex pair, and the pieces every other path of convex/query.hpp is
/// built from: the cores of round shapes (a sphere's centre, a capsule's segment), the pair frame
/// (b seen from a), GJK in that frame, libccd's penetration, the settling of a contact along its
/// normal (depth := the overlap along it), the own EPA (convex/epa.hpp, optionally stopped by a
/// local certificate and seeded with a candidate normal) and general_penetration, which runs the
/// own EPA and falls back to libccd. Needs the impact::convex target (libccd).
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/epa.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/libccd_solver.hpp"
#include "impact/convex/query_options.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/signed_volumes.hpp"
#include "impact/convex/triangle_shape.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <limits>
#include <type_traits>
#include <utility>

namespace impact {
namespace detail {

/// The core of a round shape: a sphere's centre, a capsule's segment (a radius is added to it).
template <class S>
struct PointCore {
  Vec3<S> c;
};
template <class S>
struct SegmentCore {
  S h;
};
template <class S>
inline Vec3<S> support(const PointCore<S>& p, const Vec3<S>&) {
  return p.c;
}
template <class S>
inline Vec3<S> support(const SegmentCore<S>& s, const Vec3<S>& d) {
  return {S(0), S(0), d.z() >= S(0) ? s.h : -s.h};
}
template <class S>
inline PointCore<S> core_of(const Sphere<S>& s) {
  return {s.center};
}
template <class S>
inline SegmentCore<S> core_of(const Capsule<S>& c) {
  return {c.half_length};
}
template <class S>
inline Vec3<S> core_interior(const PointCore<S>& p) {
  return p.c;
}
template <class S>
inline Vec3<S> core_interior(const SegmentCore<S>&) {
  return Vec3<S>::Zero();
}

/// b's frame seen from a's: EPA runs in a's frame, where a's support needs no rotation and b's one
/// rotation each way (instead of two rotations per shape in the world).
template <class S>
struct PairFrame {
  Mat3<S> R;  ///< pa.R^T pb.R
  Vec3<S> t;  ///< pa.R^T (pb.t - pa.t)
  PairFrame(const RigidTransform<S>& pa, const RigidTransform<S>& pb) : R(pa.R.transpose() * pb.R), t(pa.R.transpose() * (pb.t - pa.t)) {}
  Vec3<S> b_to_a(const Vec3<S>& p) const { return R * p + t; }
  template <class B>
  Vec3<S> support_b(const B& b, const Vec3<S>& d) const {
    return b_to_a(support(b, Vec3<S>(R.transpose() * d)));
  }
};

/// GJK distance of shape a at pa and shape b at pb (any shapes or cores with support()), run in
/// a's frame (PairFrame: a's support without rotation, b's with one each way); witness points in
/// the world.
template <class S, class A, class B>
ConvexDistance<S> gjk(const A& a, const RigidTransform<S>& pa, const Vec3<S>& ia, const B& b, const RigidTransform<S>& pb,
                      const Vec3<S>& ib, S tolerance, int max_iterations, S margin = S(-1), bool stop_within_margin = true,
                      Vec3<S>* plane = nullptr) {
  const PairFrame<S> f(pa, pb);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  ConvexDistance<S> r = gjk_distance<S>(sa, sb, Vec3<S>(ia - f.b_to_a(ib)), tolerance, max_iterations, margin, stop_within_margin, plane);
  r.point_a = pa.apply(r.point_a);
  r.point_b = pa.apply(r.point_b);
  if (plane) *plane = pa.rotate(*plane);
  return r;
}

template <class S>
CcdSettings ccd_settings(const ConvexQueryOptions<S>& o, S scale) {
  CcdSettings c;
  c.max_iterations = o.max_iterations;
  c.length_scale = double(scale);
  c.epa_tolerance = double(o.epa_relative_tolerance) * double(o.epa_relative_tolerance);
  c.mpr_tolerance = double(o.relative_tolerance);
  return c;
}

/// max_iterations is one budget for a whole query: `rest` receives the options of a later stage
/// (another solver, a retry) after `spent` support calls, with what is left as its bound; false
/// when nothing is left, and the caller answers with out_of_budget.
template <class S>
bool budget_left(const ConvexQueryOptions<S>& o, int spent, ConvexQueryOptions<S>& rest) {
  rest = o;
  rest.max_iterations = o.max_iterations - spent;
  return rest.max_iterations >= 1;
}

/// The answer of a penetration query whose bound ran out after `spent` support calls before any
/// solver decided: no contact found, limit_reached (as EPA's when its GJK hits the bound).
template <class S>
ConvexContact<S> out_of_budget(int spent) {
  ConvexContact<S> c;
  c.iterations = spent;
  c.limit_reached = true;
  return c;
}

/// A libccd penetration result as a contact: whether the shapes intersect, the normal, the point
/// and the solver's counters. The depth is left to settle_contact, which measures it.
template <class S>
ConvexContact<S> to_contact(const CcdPenetration<S>& r) {
  ConvexContact<S> c;
  c.intersecting = r.intersecting;
  c.normal = r.normal;
  c.point = r.point;
  c.iterations = r.iterations;
  c.limit_reached = r.limit_reached;
  return c;
}

/// Makes an iterative solver's contact exact along its normal: depth := h_a(n) + h_b(-n) (the
/// overlap of the shapes along n, computed from the support functions, so that translating b by
/// depth * n makes them touch, and depth >= the true penetration depth), and the point moved along
/// n onto the plane midway between the two supporting planes (keeping its tangential position).
/// Returns the overlap along n before the clamp to 0 (negative: the planes separate the shapes).
template <class S, class A, class B>
S settle_contact(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, ConvexContact<S>& c) {
  if (!c.intersecting) return S(0);
  const S top_a = c.normal.dot(support(a, pa, c.normal));
  const S low_b = c.normal.dot(support(b, pb, Vec3<S>(-c.normal)));
  c.depth = std::max(top_a - low_b, S(0));
  c.point += ((top_a + low_b) / S(2) - c.normal.dot(c.point)) * c.normal;
  return top_a - low_b;
}

/// settle_contact for a contact whose depth is already certified (EPA's, or a pair's closed-form
/// candidates'): the point onto the mid plane, the depth the smaller of the two.
template <class S, class A, class B>
S settle_certified_contact(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, ConvexContact<S>& c) {
  const S depth = c.depth;
  const S overlap = settle_contact(a, pa, b, pb, c);
  c.depth = std::min(c.depth, depth);
  return overlap;
}

/// A certified contact found in a's frame (a pair's closed form or candidates, run on PairFrame):
/// its normal and point to the world, then settle_certified_contact.
template <class S, class A, class B>
void settle_certified_from_frame(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, ConvexContact<S>& c) {
  c.normal = pa.rotate(c.normal);
  c.point = pa.apply(c.point);
  settle_certified_contact(a, pa, b, pb, c);
}

/// libccd's penetration, settled (settle_contact) and certified: EPA's own depth is the distance
/// to its inner polytope, a lower bound of the true depth, and the overlap along its normal an
/// upper bound. libccd 2.1's EPA sometimes stops early (on a polytope vertex or edge, or when a
/// support point falls within its tolerance of a face that is not on the boundary); the gap then
/// shows it, and the query is run again in two other normalised frames (scaled by 0.77 and 1.3)
/// and by MPR, keeping the smallest upper bound and the largest lower bound.
template <class S, class A, class B>
ConvexContact<S> epa(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, const ConvexQueryOptions<S>& o) {
  const S scale = query_scale<S>(a, b);
  CcdSettings settings = ccd_settings(o, scale);
  ConvexContact<S> best;
  S lower = S(0);
  const double frames[3] = {1.0, 0.77, 1.3};
  for (int attempt = 0; attempt < 4; ++attempt) {
    CcdSettings st = settings;
    if (attempt > 0) {  // a retry gets what the attempts before it left of the bound
      st.max_iterations = settings.max_iterations - best.iterations;
      if (st.max_iterations < 1) {
        best.limit_reached = true;
        break;
      }
    }
    CcdAlgorithm algo = o.penetration_algorithm;
    if (attempt < 3) {
      st.length_scale = settings.length_scale * frames[attempt];
    } else {
      algo = o.penetration_algorithm == CcdAlgorithm::Gjk ? CcdAlgorithm::Mpr : CcdAlgorithm::Gjk;
    }
    const auto r = ccd_penetration(a, pa, b, pb, algo, st);
    ConvexContact<S> c = to_contact(r);
    if (attempt == 0) {
      if (!r.intersecting) return c;
      best = c;
      best.depth = std::numeric_limits<S>::infinity();
    } else {
      best.iterations += r.iterations;
      best.limit_reached = best.limit_reached || r.limit_reached;
      if (!r.intersecting) continue;
    }
    settle_contact(a, pa, b, pb, c);
    // EPA's depth is a certified lower bound; MPR's is not (its portal is not a supporting face).
    if (algo == CcdAlgorithm::Gjk && !r.limit_reached) lower = std::max(lower, std::min(r.depth, c.depth));
    if (c.depth < best.depth) {
      const int its = best.iterations;
      const bool lim = best.limit_reached;
      best = c;
      best.iterations = its;
      best.limit_reached = lim;
    }
    best.depth_gap = std::max(best.depth - lower, S(0));
    if (best.depth_gap <= o.relative_tolerance * scale * S(100)) break;
  }
  return best;
}

template <class T, class S>
inline constexpr bool is_polytope_v = std::is_same_v<T, Box<S>> || std::is_same_v<T, ConvexHull<S>> || std::is_same_v<T, TriangleShape<S>> ||
                                      std::is_same_v<T, PointCore<S>> || std::is_same_v<T, SegmentCore<S>>;

/// The own EPA (convex/epa.hpp) on support functions sa, sb of one frame, from interior points
/// la of a and lb of b there, translated to their midpoint (for precision far from the frame's
/// origin). `failed` is set when it meets a degenerate Minkowski difference. Results in that frame.
/// With `simplex` (a tetrahedron of support points of these functions holding the origin, from
/// gjk_enclose, which took `simplex_calls` support calls) EPA starts from it instead of running GJK.
template <class S, class SupportA, class SupportB, class Local = NoLocalCertificate>
ConvexContact<S> own_epa_in_frame(const SupportA& support_a, const SupportB& support_b, const Vec3<S>& la, const Vec3<S>& lb, S scale,
                                  const ConvexQueryOptions<S>& o, bool refine, bool& failed, const SimplexPoint<S>* simplex = nullptr,
                                  int simplex_calls = 0, const Local& local = Local{}, const Vec3<S>* seed = nullptr) {
  const Vec3<S> origin = (la + lb) / S(2);
  const auto sa = [&](const Vec3<S>& d) { return Vec3<S>(support_a(d) - origin); };
  const auto sb = [&](const Vec3<S>& d) { return Vec3<S>(support_b(d) - origin); };
  EpaSettings<S> st;
  st.scale = scale;
  st.tolerance = o.relative_tolerance * scale;
  st.coarse_tolerance = S(1e-3) * scale;
  st.max_iterations = o.max_iterations;
  st.refine = refine;
  if (seed) {
    st.seeded = true;
    st.seed = *seed;
  }
  EpaPenetration<S> r;
  if (simplex) {
    SimplexPoint<S> moved[4];  // into the frame centred at `origin` (w = a - b is unchanged)
    for (int i = 0; i < 4; ++i) moved[i] = SimplexPoint<S>{simplex[i].w, Vec3<S>(simplex[i].a - origin), Vec3<S>(simplex[i].b - origin)};
    r = epa_penetration_local(sa, sb, moved, simplex_calls, st, local);
  } else {
    r = epa_penetration(sa, sb, Vec3<S>(la - lb), st);
  }
  ConvexContact<S> c;
  failed = r.failed;
  c.iterations = r.iterations;
  c.limit_reached = r.limit_reached;
  if (!r.intersecting || r.failed) return c;
  c.intersecting = true;
  c.normal = r.normal;
  c.depth = r.depth;
  c.point = (r.point_a + r.point_b) / S(2) + origin;
  c.depth_gap = std::max(r.depth - r.lower, S(0));
  c.refined = r.refined;
  return c;
}

/// The own EPA on a and b in a's frame (PairFrame: a's support without rotation, b's with one each
/// way). `failed` is set when it meets a degenerate Minkowski difference. Results in the world.
/// `simplex` as for own_epa_in_frame, in a's frame (PairFrame's support functions); `frame`, when
/// given, is PairFrame(pa, pb), which the caller has already.
template <class S, class A, class B, class Local = NoLocalCertificate>
ConvexContact<S> own_epa(const A& a, const RigidTransform<S>& pa, const Vec3<S>& ia, const B& b, const RigidTransform<S>& pb,
                         const Vec3<S>& ib, S scale, const ConvexQueryOptions<S>& o, bool& failed, const SimplexPoint<S>* simplex = nullptr,
                         int simplex_calls = 0, const Local& local = Local{}, const Vec3<S>* seed = nullptr,
                         const PairFrame<S>* frame = nullptr) {
  const PairFrame<S> f = frame ? *frame : PairFrame<S>(pa, pb);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const bool refine = o.newton_refinement && !(is_polytope_v<A, S> && is_polytope_v<B, S>);
  ConvexContact<S> c = own_epa_in_frame(sa, sb, ia, f.b_to_a(ib), scale, o, refine, failed, simplex, simplex_calls, local, seed);
  if (!c.intersecting) return c;
  c.normal = pa.rotate(c.normal);
  c.point = pa.apply(c.point);
  return c;
}

/// Whether an overlap along a solver's normal (settle_contact's value) proves the shapes apart:
/// below minus the solver's tolerance and the rounding of support points at the poses' distance
/// from the origin. Two intersecting convex shapes overlap by at least their depth along every
/// direction, so such a normal is a separating plane, whatever the solver that gave it believed.
template <class S>
bool normal_separates(S overlap, const RigidTransform<S>& pa, const RigidTransform<S>& pb, S scale, const ConvexQueryOptions<S>& o) {
  const S reach = scale + std::max(pa.t.cwiseAbs().maxCoeff(), pb.t.cwiseAbs().maxCoeff());
  return overlap < -(o.relative_tolerance * scale + S(64) * std::numeric_limits<S>::epsilon() * reach);
}

/// The answer "no contact" for a contact whose own normal separates the shapes (normal_separates),
/// keeping its counters.
template <class S>
ConvexContact<S> separated_by_normal(const ConvexContact<S>& c) {
  ConvexContact<S> none;
  none.iterations = c.iterations;
  none.limit_reached = c.limit_reached;
  return none;
}

/// The general penetration: the own EPA unless options.libccd_penetration, libccd when it fails.
/// A contact whose normal separates the shapes (normal_separates) is no contact: EPA started from
/// a tetrahedron that GJK took for one holding the origin when it did not (fuzzing: two float cones
/// 5.5e-4 apart, 5.5e-4 of the size; GJK stalled at 6.2e-4 on a nearly flat triangle, the distance
/// solver's witnesses gave no separating plane, and EPA's answer was a contact of depth 0 along a
/// normal that separates them by 5.4e-4).
/// `simplex` as for own_epa (a's frame), when the caller's GJK enclosed the origin already;
/// `frame` as for own_epa.
template <class S, class A, class B, class Local = NoLocalCertificate>
ConvexContact<S> general_penetration(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                     const ConvexQueryOptions<S>& o, const SimplexPoint<S>* simplex = nullptr, int simplex_calls = 0,
                                     const Local& local = Local{}, const Vec3<S>* seed = nullptr, const PairFrame<S>* frame = nullptr) {
  if (!o.libccd_penetration) {
    bool failed = false;
    const S scale = query_scale<S>(a, b);
    ConvexContact<S> c = own_epa(a, pa, interior_point(a), b, pb, interior_point(b), scale, o, failed, simplex, simplex_calls, local, seed, frame);
    if (!failed) {
      if (c.intersecting && normal_separates(settle_certified_contact(a, pa, b, pb, c), pa, pb, scale, o))
        return separated_by_normal(c);
      return c;
    }
    // libccd with what the own EPA left of the bound
    ConvexQueryOptions<S> rest;
    if (!budget_left(o, c.iterations, rest)) return out_of_budget<S>(c.iterations);
    ConvexContact<S> l = epa(a, pa, b, pb, rest);
    l.iterations += c.iterations;
    return l;
  }
  return epa(a, pa, b, pb, o);
}

/// The answer "no contact" of a pair that one plane (one support call of each shape) separated.
template <class S>
ConvexContact<S> one_plane_apart() {
  ConvexContact<S> c;
  c.iterations = 1;
  return c;
}

/// A pair's answer computed with the roles of a and b swapped, turned back: witness points
/// exchanged, the normal reversed.
template <class S>
ConvexDistance<S> swapped(ConvexDistance<S> d) {
  std::swap(d.point_a, d.point_b);
  return d;
}
template <class S>
ConvexContact<S> swapped(ConvexContact<S> c) {
  c.normal = -c.normal;
  return c;
}

}  // namespace detail
}  // namespace impact
