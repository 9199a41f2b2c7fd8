// SPDX-License-Identifier: MIT
/// \file
/// The queries between two convex shapes, each placed by a rigid pose: convex_intersect (boolean),
/// convex_distance (separation distance with witness points) and convex_penetration (depth, normal
/// and contact point). Shapes: Sphere (geometry/sphere.hpp), Capsule, Cylinder, Cone, Box
/// (convex/shapes.hpp), ConvexHull (convex/convex_hull.hpp), in any order. Needs the impact::convex
/// target (libccd).
///
///   impact::Capsule<double> cap(0.5, 1.0);
///   impact::Cylinder<double> cyl(0.3, 0.8);
///   auto c = impact::convex_penetration(cap, pose_a, cyl, pose_b);
///   if (c.intersecting) apply(c.normal, c.depth, c.point);
///
/// Which method answers, per pair (first match):
///   sphere/capsule – sphere/capsule   closed form on the cores (centre, segment) and the radii
///   sphere – box                      closed form (closest point of the box, or its nearest face)
///   sphere – cylinder                 closed form: the closest point of the cylinder (a radial
///                                     and an axial clamp), or, centre inside, the nearer of side
///                                     and caps
///   sphere – cone                     closed form in the centre's meridian plane: the closest
///                                     point of the cone's side or base, or, centre inside, the
///                                     nearer of side and base
///   box – box                         separating axes (boolean, penetration); GJK for distance
///   sphere/capsule – other            GJK distance between the core and the other shape, minus
///                                     the radius (exact up to GJK's tolerance; a capsule's segment
///                                     against a cylinder by convex/segment_cylinder.hpp); when the
///                                     core itself meets the other shape: the own EPA on the core,
///                                     plus the radius
///   box – hull                        penetration: separating axes (convex/polytope_sat.hpp) for
///                                     hulls of up to 128 faces, else as the other pairs;
///   hull – hull                       penetration: the line between the centres (apart: done),
///                                     then as the other pairs;
///                                     boolean and distance as the other pairs below
///   cylinder – cylinder               boolean: separating and proving tests on the centres and
///                                     the axes, then GJK (convex/cylinder_intersect.hpp);
///                                     distance and penetration as the other pairs below
///   cylinder – box                    boolean: separating planes and common points, then GJK;
///                                     penetration: separating planes, the certified candidates,
///                                     else GJK and EPA with the local certificate
///                                     (convex/cylinder_box_pair.hpp); distance as below
///   other pairs                       boolean: libccd MPR (default) or GJK; distance: GJK
///                                     (gjk_distance.hpp); penetration: cylinders and cones with
///                                     parallel axes in closed form (convex/parallel_axes.hpp);
///                                     cylinder against cylinder or cone
///                                     first through the certified candidates of
///                                     convex/cylinder_pair.hpp, cone against box through those of
///                                     convex/cone_box_pair.hpp, cone against cone through those
///                                     of convex/cone_cone_pair.hpp, then EPA with the local
///                                     certificate of convex/cone_box_terms.hpp or
///                                     cone_cone_terms, else the own EPA (convex/epa.hpp;
///                                     Newton refinement optional; libccd's EPA or MPR with
///                                     options.libccd_penetration, and as the fallback when the
///                                     Minkowski difference is flat)
/// Definitions: the normal is a unit vector from a towards b; translating b by depth * normal
/// makes the shapes touch (for EPA: the least such translation within the solver's tolerance,
/// relative_tolerance of the size; for libccd's MPR: the one along the portal direction, which can
/// be larger); the contact point is midway
/// between the deepest points of a and b (point_a(), point_b()). Touching counts as intersecting.
///
/// Validation: each call throws InvalidInput on an invalid shape (validate_shape), pose
/// (validate_pose) or options, before computing anything. Iterative solvers are bounded by
/// options.max_iterations; a result stopped by the bound says limit_reached, and so does a
/// penetration whose bracket rounding or a degenerate polytope left open (penetration_unchecked).
/// Thread safety: the functions are pure; shapes and poses may be shared between threads.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/cone_box_pair.hpp"
#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/cone_cone_pair.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_box_pair.hpp"
#include "impact/convex/cylinder_hull_pair.hpp"
#include "impact/convex/cylinder_intersect.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/epa.hpp"
#include "impact/convex/polytope_sat.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/libccd_solver.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/parallel_axes.hpp"
#include "impact/convex/segment_cylinder.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/triangle_shape.hpp"

#include <type_traits>

namespace impact {

template <class S>
struct ConvexQueryOptions {
  /// Bound on the iterations (support calls per shape) of GJK, MPR and EPA; 1 .. 100000.
  int max_iterations = 512;
  /// Tolerance of the iterative solvers relative to the larger shape's size (shape_size()); in
  /// (0, 0.1]. The default is 1e-10 for double, 1e-5 for float.
  S relative_tolerance = std::is_same_v<S, float> ? S(1e-5) : S(1e-10);
  /// Tolerance of libccd's EPA expansion relative to the larger shape's size (libccd's
  /// epa_tolerance is its square times the size squared), used with libccd_penetration; in (0, 0.1].
  /// The own EPA stops at relative_tolerance.
  S epa_relative_tolerance = std::is_same_v<S, float> ? S(1e-5) : S(1e-8);
  CcdAlgorithm boolean_algorithm = CcdAlgorithm::Mpr;     ///< libccd algorithm of general boolean tests (cylinder–cylinder has its own)
  CcdAlgorithm penetration_algorithm = CcdAlgorithm::Gjk; ///< libccd algorithm of general penetrations (GJK+EPA)
  /// General penetrations through libccd (penetration_algorithm) instead of the library's own EPA
  /// with Newton refinement (convex/epa.hpp), which is the default; libccd also answers when the
  /// own solver meets a degenerate (flat) Minkowski difference.
  bool libccd_penetration = false;
  /// Curved pairs: stop the own EPA at a gap of 1e-3 of the size and refine the normal by Newton's
  /// method (convex/epa.hpp), going on with EPA when the refinement does not verify. Off by
  /// default: on the zoo's cylinders and cones the support's edges (rulings, rims) stop it on most
  /// poses (verified on 10 of 130 cylinder–cylinder penetrations), so it cost more support calls
  /// than it saved (38.9 against 31.5 per query there), while EPA alone closes its gap to 1e-10.
  bool newton_refinement = false;
  /// Cylinder against cylinder or cone, and cone against box: stop EPA early with the local certificate of
  /// convex/local_certificate.hpp (Newton on the closed-form overlap, a certified quadratic lower
  /// bound on a cap of directions about its minimiser, EPA's polytope for the rest); off: EPA to
  /// relative_tolerance alone (the answers agree within relative_tolerance; tested).
  bool local_certificate = true;
};

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

template <class T, class S>
inline constexpr bool is_round_v = std::is_same_v<T, Sphere<S>> || std::is_same_v<T, Capsule<S>>;

/// The method that answers a pair of shape types (the table of the file comment): the first entry
/// that matches, in this order. Decided at compile time: each query branches on it with
/// if constexpr, so nothing is dispatched at run time.
enum class PairMethod {
  RoundRound,  ///< both spheres or capsules: closed form on the cores and the radii
  SphereBox,   ///< closed form (closest point of the box, or its nearest face)
  BoxSphere,   ///< the same with the roles swapped (the result swapped back)
  SphereCylinder,  ///< closed form (closest point of the cylinder, or the nearer of side and caps)
  CylinderSphere,  ///< the same with the roles swapped
  SphereCone,  ///< closed form (closest point of the cone's meridian triangle, or the nearer of side and base)
  ConeSphere,  ///< the same with the roles swapped
  BoxBox,      ///< separating axes (boolean, penetration); GJK for distance
  RoundOther,  ///< a sphere or capsule against any other shape: GJK on its core, EPA when the core touches
  OtherRound,  ///< the same with b the sphere or capsule
  General      ///< libccd (boolean, penetration), GJK (distance)
};

template <class S, class A, class B>
constexpr PairMethod pair_method() {
  constexpr bool sphere_a = std::is_same_v<A, Sphere<S>>, sphere_b = std::is_same_v<B, Sphere<S>>;
  constexpr bool box_a = std::is_same_v<A, Box<S>>, box_b = std::is_same_v<B, Box<S>>;
  if (is_round_v<A, S> && is_round_v<B, S>) return PairMethod::RoundRound;
  if (sphere_a && box_b) return PairMethod::SphereBox;
  if (box_a && sphere_b) return PairMethod::BoxSphere;
  if (sphere_a && std::is_same_v<B, Cylinder<S>>) return PairMethod::SphereCylinder;
  if (std::is_same_v<A, Cylinder<S>> && sphere_b) return PairMethod::CylinderSphere;
  if (sphere_a && std::is_same_v<B, Cone<S>>) return PairMethod::SphereCone;
  if (std::is_same_v<A, Cone<S>> && sphere_b) return PairMethod::ConeSphere;
  if (box_a && box_b) return PairMethod::BoxBox;
  if (is_round_v<A, S>) return PairMethod::RoundOther;
  if (is_round_v<B, S>) return PairMethod::OtherRound;
  return PairMethod::General;
}

template <class S>
void validate_query_options(const ConvexQueryOptions<S>& o, const char* where) {
  if (IMPACT_LIKELY(o.max_iterations >= 1 && o.max_iterations <= 100000 && o.relative_tolerance > S(0) && o.relative_tolerance <= S(0.1) &&
                    o.epa_relative_tolerance > S(0) && o.epa_relative_tolerance <= S(0.1)))
    return;
  validate_in_range(o.max_iterations, 1, 100000, where, "options.max_iterations");
  if (!(o.relative_tolerance > S(0) && o.relative_tolerance <= S(0.1)))
    throw InvalidInput(describe_rejected(where, "options.relative_tolerance", "be in (0, 0.1]", o.relative_tolerance));
  if (!(o.epa_relative_tolerance > S(0) && o.epa_relative_tolerance <= S(0.1)))
    throw InvalidInput(describe_rejected(where, "options.epa_relative_tolerance", "be in (0, 0.1]", o.epa_relative_tolerance));
}

template <class S, class A, class B>
void validate_query(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, const ConvexQueryOptions<S>& o,
                    const char* where) {
  static_assert(is_supported_scalar_v<S>, "convex queries: S must be float or double");
  validate_shape(a, where);
  validate_shape(b, where);
  validate_pose(pa, where, "pose_a");
  validate_pose(pb, where, "pose_b");
  validate_query_options(o, where);
}

template <class S, class A, class B>
S query_scale(const A& a, const B& b) {
  return std::max(shape_size(a), shape_size(b));
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
                      const Vec3<S>& ib, S tolerance, int max_iterations, S margin = S(-1), bool stop_within_margin = true) {
  const PairFrame<S> f(pa, pb);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  ConvexDistance<S> r = gjk_distance<S>(sa, sb, Vec3<S>(ia - f.b_to_a(ib)), tolerance, max_iterations, margin, stop_within_margin);
  r.point_a = pa.apply(r.point_a);
  r.point_b = pa.apply(r.point_b);
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
template <class S, class A, class B>
void settle_contact(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, ConvexContact<S>& c) {
  if (!c.intersecting) return;
  const S top_a = c.normal.dot(support(a, pa, c.normal));
  const S low_b = c.normal.dot(support(b, pb, Vec3<S>(-c.normal)));
  c.depth = std::max(top_a - low_b, S(0));
  c.point += ((top_a + low_b) / S(2) - c.normal.dot(c.point)) * c.normal;
}

/// settle_contact for a contact whose depth is already certified (EPA's, or a pair's closed-form
/// candidates'): the point onto the mid plane, the depth the smaller of the two.
template <class S, class A, class B>
void settle_certified_contact(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, ConvexContact<S>& c) {
  const S depth = c.depth;
  settle_contact(a, pa, b, pb, c);
  c.depth = std::min(c.depth, depth);
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
/// `simplex` as for own_epa_in_frame, in a's frame (PairFrame's support functions).
template <class S, class A, class B, class Local = NoLocalCertificate>
ConvexContact<S> own_epa(const A& a, const RigidTransform<S>& pa, const Vec3<S>& ia, const B& b, const RigidTransform<S>& pb,
                         const Vec3<S>& ib, S scale, const ConvexQueryOptions<S>& o, bool& failed, const SimplexPoint<S>* simplex = nullptr,
                         int simplex_calls = 0, const Local& local = Local{}, const Vec3<S>* seed = nullptr) {
  const PairFrame<S> f(pa, pb);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const bool refine = o.newton_refinement && !(is_polytope_v<A, S> && is_polytope_v<B, S>);
  ConvexContact<S> c = own_epa_in_frame(sa, sb, ia, f.b_to_a(ib), scale, o, refine, failed, simplex, simplex_calls, local, seed);
  if (!c.intersecting) return c;
  c.normal = pa.rotate(c.normal);
  c.point = pa.apply(c.point);
  return c;
}

/// The general penetration: the own EPA unless options.libccd_penetration, libccd when it fails.
/// `simplex` as for own_epa (a's frame), when the caller's GJK enclosed the origin already.
template <class S, class A, class B, class Local = NoLocalCertificate>
ConvexContact<S> general_penetration(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                     const ConvexQueryOptions<S>& o, const SimplexPoint<S>* simplex = nullptr, int simplex_calls = 0,
                                     const Local& local = Local{}, const Vec3<S>* seed = nullptr) {
  if (!o.libccd_penetration) {
    bool failed = false;
    ConvexContact<S> c =
        own_epa(a, pa, interior_point(a), b, pb, interior_point(b), query_scale<S>(a, b), o, failed, simplex, simplex_calls, local, seed);
    if (!failed) {
      if (c.intersecting) settle_certified_contact(a, pa, b, pb, c);
      return c;
    }
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

/// Two cylinders or cones whose axes are within a small tilt of parallel, after the general
/// penetration: when it stopped with its bracket open (a coaxial pair's least-overlap normals form
/// a circle EPA cannot close: about 515 support calls and a bracket of 7.5e-5 of the size at a tilt
/// of 1e-9 rad), the parallel-axes closed form certifies a bracket of about twice the tilt times
/// b's reach (convex/parallel_axes.hpp). The narrower of the two is kept; limit_reached stays set
/// unless it is within the tolerance.
template <class S, class A, class B>
void narrow_by_parallel_axes(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                             const ConvexQueryOptions<S>& o, ConvexContact<S>& g) {
  if (!g.intersecting || !g.limit_reached) return;
  const PairFrame<S> f(pa, pb);
  ConvexContact<S> p;
  if (!parallel_axes_contact(a, b, f.R, f.t, g.depth_gap, p) || !(p.depth_gap < g.depth_gap)) return;
  settle_certified_from_frame(a, pa, b, pb, p);
  p.iterations += g.iterations;
  p.limit_reached = !(p.depth_gap <= o.relative_tolerance * query_scale<S>(a, b));
  g = p;
}

/// A cylinder and a cylinder or cone: the overlap along the line between their centres (a negative
/// one separates them: no contact; 85-90 % of the bench's separated poses end here), then
/// the certified candidates of convex/cylinder_pair.hpp (caps, rulings, a ruling or a side against
/// a rim point; their certificate, a positive lower bound of the depth, proves the intersection,
/// so no GJK runs), else GJK until it encloses the origin or separates them (no contact), and EPA
/// from GJK's tetrahedron.
template <class S, class B>
ConvexContact<S> cylinder_pair_penetration(const Cylinder<S>& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                           const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const Vec3<S> centre_b = f.b_to_a(interior_point(b));  // a's centre is its frame's origin
  // a plane normal to the line between the centres separates them (by more than rounding: a pair
  // touching within rounding goes on to GJK, which decides it)
  if (separated_along(sa, sb, centre_b, scale)) return one_plane_apart<S>();
  ConvexContact<S> c;
  if (parallel_axes_contact(a, b, f.R, f.t, o.relative_tolerance * scale, c)) {  // parallel axes: closed form
    c.iterations += 1;
    settle_certified_from_frame(a, pa, b, pb, c);
    return c;
  }
  bool certified;
  if constexpr (std::is_same_v<B, Cone<S>>) {
    certified = cylinder_cone_contact(a, b, f.R, f.t, o.relative_tolerance * scale, c);
  } else {
    certified = cylinder_pair_contact(a, b, f.R, f.t, o.relative_tolerance * scale, c);
  }
  if (certified) {
    c.iterations += 1;
    settle_certified_from_frame(a, pa, b, pb, c);
    return c;
  }
  SimplexPoint<S> simplex[4];
  int its = 0;
  bool limit = false, failed = false;
  if (!gjk_enclose(sa, sb, Vec3<S>(-centre_b), scale, o.max_iterations, simplex, its, limit, failed)) {
    if (limit || failed) return general_penetration(a, pa, b, pb, o);
    ConvexContact<S> none;
    none.iterations = its + 1 + c.iterations;
    return none;
  }
  // EPA from GJK's tetrahedron (its support calls counted once, in g.iterations), stopped early by
  // the local certificate of convex/local_certificate.hpp where it holds
  const auto local = [&](const Vec3<S>& n) {
    if constexpr (std::is_same_v<B, Cone<S>>) {
      // a bound through the cone's branch or a body inside it is exact only where that branch or
      // body touches the contact: accepted when the true overlap at the certified normal is within
      // the tolerance of the bound
      const S tol = o.relative_tolerance * scale;
      const auto exact = [&](const LocalCertificate<S>& lc) {
        const Vec3<S>& k = lc.normal;
        return lc.ok && k.dot(sa(k)) - k.dot(sb(Vec3<S>(-k))) - lc.lower <= tol;
      };
      OverlapTerms<S> terms;
      if (cylinder_cone_terms(a, b, f.R, f.t, n, terms)) {
        const LocalCertificate<S> lc = local_certificate(terms, n);
        if (exact(lc)) return lc;
      }
      // the cone's side: the minimiser along b's side normals (Newton on the azimuth), then the
      // body inside b along that ruling (its overlap is exact there)
      Vec3<S> m = n;
      if (cone_side_newton(a, b, f.R, f.t, m) && cylinder_cone_side_terms(a, b, f.R, f.t, m, terms)) {
        const LocalCertificate<S> lc = local_certificate(terms, m);
        if (exact(lc)) return lc;
      }
      // else (a's rim or ruling against b's side) no certificate: moving the body round by round
      // to the ruling of the minimiser found (up to 8 rounds) certified 9 of the 88 queries that got
      // this far on the bench's 2000 poses at 226 certificate evaluations, more than it saved
      return LocalCertificate<S>();
    } else {
      return local_certificate(cylinder_pair_terms(a, b, f.R, f.t), n);
    }
  };
  // EPA evaluates the best candidate's direction first (an upper bound near the answer, and the
  // local certificate's first start)
  const Vec3<S>* seed = c.depth < std::numeric_limits<S>::infinity() ? &c.normal : nullptr;
  ConvexContact<S> g = o.local_certificate ? general_penetration(a, pa, b, pb, o, simplex, its, local, seed)
                                           : general_penetration(a, pa, b, pb, o, simplex, its, NoLocalCertificate{}, seed);
  g.iterations += 1 + c.iterations;
  narrow_by_parallel_axes(a, pa, b, pb, o, g);
  return g;
}

/// Two cones: the closed form of convex/parallel_axes.hpp when their axes are parallel; else a
/// plane normal to the line between the centres (separating: no contact; most separated poses),
/// GJK until it encloses the origin or separates them (no contact), then the certified candidates
/// of convex/cone_cone_pair.hpp (bases, apexes, rims against sides, rulings), else EPA from GJK's
/// tetrahedron, seeded with the best candidate's direction and stopped early by the local
/// certificate of convex/local_certificate.hpp on the terms of each cone's branch active at EPA's
/// normal (none where a branch ties: a side ruling); accepted when the true overlap at its normal
/// is within the tolerance of its lower bound.
template <class S>
ConvexContact<S> cone_pair_penetration(const Cone<S>& a, const RigidTransform<S>& pa, const Cone<S>& b, const RigidTransform<S>& pb,
                                       const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b), tol = o.relative_tolerance * scale;
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const Vec3<S> centre_line = f.b_to_a(interior_point(b)) - interior_point(a);
  // a plane normal to the line between the centres separates them (most separated poses)
  if (separated_along(sa, sb, centre_line, scale)) return one_plane_apart<S>();
  ConvexContact<S> cand;
  if (parallel_axes_contact(a, b, f.R, f.t, tol, cand)) {
    cand.iterations += 1;
    settle_certified_from_frame(a, pa, b, pb, cand);
    return cand;
  }
  SimplexPoint<S> simplex[4];
  int its = 1;
  bool limit = false, failed = false;
  if (!gjk_enclose(sa, sb, Vec3<S>(-centre_line), scale, o.max_iterations, simplex, its, limit, failed)) {
    if (limit || failed) {
      ConvexContact<S> g = general_penetration(a, pa, b, pb, o);
      narrow_by_parallel_axes(a, pa, b, pb, o, g);
      return g;
    }
    ConvexContact<S> none;
    none.iterations = its;
    return none;
  }
  cand = ConvexContact<S>();
  if (cone_cone_contact(a, b, f.R, f.t, tol, cand)) {
    cand.iterations += its;
    settle_certified_from_frame(a, pa, b, pb, cand);
    return cand;
  }
  const auto local = [&](const Vec3<S>& n) {
    OverlapTerms<S> terms;
    if (cone_cone_terms(a, b, f.R, f.t, n, terms)) {
      const LocalCertificate<S> lc = local_certificate(terms, n);
      const Vec3<S>& k = lc.normal;
      if (lc.ok && k.dot(sa(k)) - k.dot(sb(Vec3<S>(-k))) - lc.lower <= tol) return lc;
    }
    return LocalCertificate<S>();
  };
  const Vec3<S>* seed = cand.depth < std::numeric_limits<S>::infinity() ? &cand.normal : nullptr;
  ConvexContact<S> g = o.local_certificate ? general_penetration(a, pa, b, pb, o, simplex, its, local, seed)
                                           : general_penetration(a, pa, b, pb, o, simplex, its, NoLocalCertificate{}, seed);
  g.iterations += cand.iterations;
  narrow_by_parallel_axes(a, pa, b, pb, o, g);
  return g;
}

/// A cone (a) and a box (b): planes normal to the line between the centres and to the box's axes
/// (separating: no contact), GJK until it encloses the origin or separates them (no contact), then
/// the certified candidates of convex/cone_box_pair.hpp (a face of the box against the cone's
/// deepest point, a corner or an edge of the box through the cone's side or base), else
/// EPA from GJK's tetrahedron, stopped early by the local certificate of
/// convex/local_certificate.hpp on the terms of convex/cone_box_terms.hpp (the cone's branch active
/// at EPA's normal; none on a side ruling). A bound through one branch is exact only where that
/// branch touches the contact, so a certificate is accepted when the true overlap at its normal is
/// within the tolerance of its lower bound.
template <class S>
ConvexContact<S> cone_box_penetration(const Cone<S>& a, const RigidTransform<S>& pa, const Box<S>& b, const RigidTransform<S>& pb,
                                      const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b), tol = o.relative_tolerance * scale;
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const Vec3<S> centre_line = f.t - interior_point(a);
  // a plane normal to the line between the centres separates them (most separated poses)
  if (separated_along(sa, sb, centre_line, scale)) return one_plane_apart<S>();
  // a plane normal to one of the box's axes (about half of the separated poses left, without GJK)
  if (cone_box_apart_along_box_axes(a, b, f.R, f.t, std::numeric_limits<S>::epsilon() * S(16) * scale))
    return one_plane_apart<S>();
  SimplexPoint<S> simplex[4];
  int its = 1;
  bool limit = false, failed = false;
  if (!gjk_enclose(sa, sb, Vec3<S>(-centre_line), scale, o.max_iterations, simplex, its, limit, failed)) {
    if (limit || failed) return general_penetration(a, pa, b, pb, o);
    ConvexContact<S> none;
    none.iterations = its;
    return none;
  }
  // intersecting: the certified candidates of convex/cone_box_pair.hpp (after GJK, which decides
  // the separated poses more cheaply than they would), else EPA from GJK's tetrahedron
  ConvexContact<S> cand;
  if (cone_box_contact(a, b, f.R, f.t, tol, cand)) {
    cand.iterations += its;
    settle_certified_from_frame(a, pa, b, pb, cand);
    return cand;
  }
  const auto local = [&](const Vec3<S>& n) {
    const auto exact = [&](const LocalCertificate<S>& lc) {
      const Vec3<S>& k = lc.normal;
      return lc.ok && k.dot(sa(k)) - k.dot(sb(Vec3<S>(-k))) - lc.lower <= tol;
    };
    OverlapTerms<S> terms;
    if (cone_box_terms(a, b, f.R, f.t, n, terms)) {
      const LocalCertificate<S> lc = local_certificate(terms, n);
      if (exact(lc)) return lc;
    }
    return LocalCertificate<S>();
  };
  const Vec3<S>* seed = cand.depth < std::numeric_limits<S>::infinity() ? &cand.normal : nullptr;  // as for cylinder pairs
  ConvexContact<S> g = o.local_certificate ? general_penetration(a, pa, b, pb, o, simplex, its, local, seed)
                                           : general_penetration(a, pa, b, pb, o, simplex, its, NoLocalCertificate{}, seed);
  g.iterations += cand.iterations;
  return g;
}

/// A cylinder (a) and a box (b): the planes of convex/cylinder_box_pair.hpp (the line between the
/// centres, the box's axes, the cylinder's axis, normal to the axis and a box edge; separating: no
/// contact), the certified candidates of convex/cylinder_box_pair.hpp (a certified lower bound is
/// positive, so it proves the intersection: no GJK; before GJK saves 4 % of the instructions on
/// the bench's poses), else GJK until it encloses the origin or separates them, and EPA from its
/// tetrahedron seeded with the best candidate's direction and stopped early by the local
/// certificate on cylinder_box_terms (the overlap's exact terms, so no check of a branch).
template <class S>
ConvexContact<S> cylinder_box_penetration(const Cylinder<S>& a, const RigidTransform<S>& pa, const Box<S>& b, const RigidTransform<S>& pb,
                                          const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b), tol = o.relative_tolerance * scale;
  const S margin = std::numeric_limits<S>::epsilon() * S(16) * scale;
  {  // a plane normal to the line between the centres separates them (most separated poses)
    const S len = f.t.norm();
    if (len > S(0) && cylinder_box_overlap(a, b, f.R, f.t, Vec3<S>(f.t / len)) < -margin) {
      ConvexContact<S> c;
      c.iterations = 1;
      return c;
    }
  }
  if (cylinder_box_apart(a, b, f.R, f.t, margin)) {
    ConvexContact<S> c;
    c.iterations = 1;
    return c;
  }
  ConvexContact<S> cand;
  if (cylinder_box_contact(a, b, f.R, f.t, tol, cand)) {
    cand.iterations += 1;
    settle_certified_from_frame(a, pa, b, pb, cand);
    return cand;
  }
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  SimplexPoint<S> simplex[4];
  int its = 1;
  bool limit = false, failed = false;
  if (!gjk_enclose(sa, sb, Vec3<S>(-f.t), scale, o.max_iterations, simplex, its, limit, failed)) {
    if (limit || failed) return general_penetration(a, pa, b, pb, o);
    ConvexContact<S> none;
    none.iterations = its + cand.iterations;
    return none;
  }
  const OverlapTerms<S> terms = cylinder_box_terms(a, b, f.R, f.t);
  const auto local = [&](const Vec3<S>& n) { return local_certificate(terms, n); };
  const Vec3<S>* seed = cand.depth < std::numeric_limits<S>::infinity() ? &cand.normal : nullptr;
  ConvexContact<S> g = o.local_certificate ? general_penetration(a, pa, b, pb, o, simplex, its, local, seed)
                                           : general_penetration(a, pa, b, pb, o, simplex, its, NoLocalCertificate{}, seed);
  g.iterations += cand.iterations;
  return g;
}

/// A cylinder (a) and a convex hull (b): a plane normal to the line between the centres, then the
/// candidates of convex/cylinder_hull_pair.hpp (the hull's face planes, which also separate most
/// of the separated poses left; faces, caps and edges across the side, certified by a ball inside
/// one shape; a certified lower bound is positive, so it proves the intersection: no GJK), else
/// GJK until it encloses the origin or separates them, and EPA from its tetrahedron seeded with
/// the best candidate's direction and stopped early by the local certificate on
/// cylinder_hull_terms (the hull's vertex or edge at EPA's normal), accepted when the true overlap
/// at its normal is within the tolerance of its lower bound.
template <class S>
ConvexContact<S> cylinder_hull_penetration(const Cylinder<S>& a, const RigidTransform<S>& pa, const ConvexHull<S>& b,
                                           const RigidTransform<S>& pb, const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b), tol = o.relative_tolerance * scale;
  const S margin = std::numeric_limits<S>::epsilon() * S(16) * scale;
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const Vec3<S> centre_b = f.b_to_a(interior_point(b));
  {  // a plane normal to the line between the centres separates them (most separated poses)
    const S len = centre_b.norm();
    if (len > S(0)) {
      const Vec3<S> m = centre_b / len;
      if (m.dot(sa(m)) - m.dot(sb(Vec3<S>(-m))) < -margin) {
        ConvexContact<S> c;
        c.iterations = 1;
        return c;
      }
    }
  }
  ConvexContact<S> cand;
  const CylinderHullVerdict verdict = cylinder_hull_candidates(a, b, f.R, f.t, margin, tol, cand);
  if (verdict == CylinderHullVerdict::Apart) {
    ConvexContact<S> c;
    c.iterations = 1;
    return c;
  }
  if (verdict == CylinderHullVerdict::Certified) {
    cand.iterations += 1;
    settle_certified_from_frame(a, pa, b, pb, cand);
    return cand;
  }
  SimplexPoint<S> simplex[4];
  int its = 1;
  bool limit = false, failed = false;
  if (!gjk_enclose(sa, sb, Vec3<S>(-centre_b), scale, o.max_iterations, simplex, its, limit, failed)) {
    if (limit || failed) return general_penetration(a, pa, b, pb, o);
    ConvexContact<S> none;
    none.iterations = its + cand.iterations;
    return none;
  }
  const auto local = [&](const Vec3<S>& n) {
    const LocalCertificate<S> lc = local_certificate(cylinder_hull_terms(a, b, f.R, f.t, n), n);
    const Vec3<S>& k = lc.normal;
    if (lc.ok && k.dot(sa(k)) - k.dot(sb(Vec3<S>(-k))) - lc.lower <= tol) return lc;
    return LocalCertificate<S>();
  };
  const Vec3<S>* seed = cand.depth < std::numeric_limits<S>::infinity() ? &cand.normal : nullptr;
  ConvexContact<S> g = o.local_certificate ? general_penetration(a, pa, b, pb, o, simplex, its, local, seed)
                                           : general_penetration(a, pa, b, pb, o, simplex, its, NoLocalCertificate{}, seed);
  g.iterations += cand.iterations;
  return g;
}

/// GJK between a round shape's core (at pa) and shape b (at pb), as gjk(); a capsule's segment
/// against a cylinder by the certified 1-D minimisation of convex/segment_cylinder.hpp instead
/// when the segment stays clear of the cylinder (GJK otherwise).
template <class S, class C, class B>
ConvexDistance<S> core_distance(const C& core, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, S tolerance,
                                int max_iterations, S margin = S(-1), bool stop_within_margin = true) {
  if constexpr (std::is_same_v<C, SegmentCore<S>> && std::is_same_v<B, Cylinder<S>>) {
    ConvexDistance<S> d;
    if (segment_cylinder_distance(core.h, pa, b, pb, tolerance, d)) return d;
  }
  return gjk(core, pa, core_interior(core), b, pb, interior_point(b), tolerance, max_iterations, margin, stop_within_margin);
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
  const ConvexDistance<S> d = core_distance(core, pa, b, pb, tol, o.max_iterations, r, false);
  if (!d.intersecting && d.distance > tol) {
    ConvexContact<S> c;
    c.iterations = d.iterations;
    c.limit_reached = d.limit_reached;
    if (d.distance > r) return c;
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
    if (flip) c.normal = -c.normal;
    return c;
  }
  if (!o.libccd_penetration) {  // the core meets b: EPA on the core, plus the radius
    bool failed = false;
    ConvexContact<S> c = own_epa(core, pa, core_interior(core), b, pb, interior_point(b), scale, o, failed);
    if (!failed) {
      c.iterations += d.iterations;
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
        c.depth = r;
        c.point = (d.point_a + d.point_b) / S(2);
        settle_certified_contact(a, pa, b, pb, c);
        c.depth_gap = std::max(c.depth - std::max(r - apart, S(0)), S(0));
      } else {  // EPA's depth plus the radius is the overlap along its normal too: settled, the smaller
        c.depth += r;
        settle_certified_contact(a, pa, b, pb, c);
      }
      if (flip) c.normal = -c.normal;
      return c;
    }
  }
  return flip ? epa(b, pb, a, pa, o) : epa(a, pa, b, pb, o);
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

namespace detail {
/// convex_penetration without the validation, for callers that validated the shapes, poses and
/// options once (the scene of convex/scene_shapes.hpp). Also takes what validate_shape rejects but
/// the queries handle: a sphere of radius 0 (a point) and a box with a zero half extent (flat).
template <class S, class A, class B>
ConvexContact<S> penetration_by_method(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                                       const ConvexQueryOptions<S>& options) {
  constexpr PairMethod method = pair_method<S, A, B>();
  if constexpr (method == PairMethod::RoundRound) {
    return round_pair_contact(a, pose_a, b, pose_b);
  } else if constexpr (method == PairMethod::SphereBox) {
    return sphere_box_contact(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::BoxSphere) {
    return swapped(sphere_box_contact(pose_b.apply(b.center), b.radius, a, pose_a));
  } else if constexpr (method == PairMethod::SphereCylinder) {
    return sphere_cylinder_contact(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::CylinderSphere) {
    return swapped(sphere_cylinder_contact(pose_b.apply(b.center), b.radius, a, pose_a));
  } else if constexpr (method == PairMethod::SphereCone) {
    return sphere_cone_contact(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::ConeSphere) {
    return swapped(sphere_cone_contact(pose_b.apply(b.center), b.radius, a, pose_a));
  } else if constexpr (method == PairMethod::BoxBox) {
    return box_box_contact(a, pose_a, b, pose_b, true);
  } else if constexpr (method == PairMethod::RoundOther) {
    return round_contact(a, pose_a, b, pose_b, options, false);
  } else if constexpr (method == PairMethod::OtherRound) {
    return round_contact(b, pose_b, a, pose_a, options, true);
  } else {
    if constexpr (std::is_same_v<A, Cylinder<S>> && (std::is_same_v<B, Cylinder<S>> || std::is_same_v<B, Cone<S>>)) {
      if (!options.libccd_penetration) return cylinder_pair_penetration(a, pose_a, b, pose_b, options);
    } else if constexpr (std::is_same_v<A, Cone<S>> && std::is_same_v<B, Cylinder<S>>) {
      if (!options.libccd_penetration) return swapped(cylinder_pair_penetration(b, pose_b, a, pose_a, options));
    } else if constexpr (std::is_same_v<A, Cone<S>> && std::is_same_v<B, Cone<S>>) {
      if (!options.libccd_penetration) return cone_pair_penetration(a, pose_a, b, pose_b, options);
    } else if constexpr (std::is_same_v<A, Cone<S>> && std::is_same_v<B, Box<S>>) {
      if (!options.libccd_penetration) return cone_box_penetration(a, pose_a, b, pose_b, options);
    } else if constexpr (std::is_same_v<A, Box<S>> && std::is_same_v<B, Cone<S>>) {
      if (!options.libccd_penetration) return swapped(cone_box_penetration(b, pose_b, a, pose_a, options));
    } else if constexpr (std::is_same_v<A, Cylinder<S>> && std::is_same_v<B, Box<S>>) {
      if (!options.libccd_penetration) return cylinder_box_penetration(a, pose_a, b, pose_b, options);
    } else if constexpr (std::is_same_v<A, Box<S>> && std::is_same_v<B, Cylinder<S>>) {
      if (!options.libccd_penetration) return swapped(cylinder_box_penetration(b, pose_b, a, pose_a, options));
    } else if constexpr (std::is_same_v<A, Cylinder<S>> && std::is_same_v<B, ConvexHull<S>>) {
      if (!options.libccd_penetration && use_cylinder_hull_candidates(b)) return cylinder_hull_penetration(a, pose_a, b, pose_b, options);
    } else if constexpr (std::is_same_v<A, ConvexHull<S>> && std::is_same_v<B, Cylinder<S>>) {
      if (!options.libccd_penetration && use_cylinder_hull_candidates(a)) return swapped(cylinder_hull_penetration(b, pose_b, a, pose_a, options));
    } else if constexpr (std::is_same_v<A, Box<S>> && std::is_same_v<B, ConvexHull<S>>) {  // separating axes
      if (!options.libccd_penetration && use_box_hull_sat(b)) return box_hull_sat(a, pose_a, b, pose_b);
    } else if constexpr (std::is_same_v<A, ConvexHull<S>> && std::is_same_v<B, Box<S>>) {
      if (!options.libccd_penetration && use_box_hull_sat(a)) return swapped(box_hull_sat(b, pose_b, a, pose_a));
    } else if constexpr (std::is_same_v<A, ConvexHull<S>> && std::is_same_v<B, ConvexHull<S>>) {
      if (!options.libccd_penetration && centre_line_separates(a, pose_a, b, pose_b)) return ConvexContact<S>{};
    }
    return general_penetration(a, pose_a, b, pose_b, options);
  }
}

/// penetration_by_method, with limit_reached also set when an iterative solver returned a bracket
/// [depth - depth_gap, depth] wider than its tolerance without reaching an iteration bound
/// (rounding or a degenerate polytope stopped it: its "no progress" exit, or libccd answering for
/// a flat Minkowski difference). The own solvers stop at relative_tolerance of the size, libccd's
/// within 100 times that (epa() above); a Newton-refined depth keeps EPA's coarse bracket by design.
/// Fuzzing found such open brackets without a flag (two coincident cylinders far from the origin,
/// relative gap 0.019; cylinders side by side, 6e-9 against a tolerance of 1e-10).
template <class S, class A, class B>
ConvexContact<S> penetration_unchecked(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                                       const ConvexQueryOptions<S>& options) {
  ConvexContact<S> c = penetration_by_method(a, pose_a, b, pose_b, options);
  if (c.intersecting && !c.refined && c.depth_gap > S(0)) {
    const S slack = options.libccd_penetration ? S(100) : S(2);
    if (!(c.depth_gap <= slack * options.relative_tolerance * query_scale<S>(a, b))) c.limit_reached = true;
  }
  return c;
}

/// convex_intersect without the validation (as penetration_unchecked).
template <class S, class A, class B>
bool intersect_unchecked(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                         const ConvexQueryOptions<S>& options, bool* limit_reached) {
  if (limit_reached) *limit_reached = false;
  constexpr PairMethod method = pair_method<S, A, B>();
  if constexpr (method == PairMethod::RoundRound) {
    const CorePoints<S> q = core_points(a, pose_a, b, pose_b);
    const S r = round_radius(a) + round_radius(b);
    return (q.b - q.a).squaredNorm() <= r * r;
  } else if constexpr (method == PairMethod::SphereBox) {
    return sphere_box_overlap(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::BoxSphere) {
    return sphere_box_overlap(pose_b.apply(b.center), b.radius, a, pose_a);
  } else if constexpr (method == PairMethod::SphereCylinder) {
    return sphere_cylinder_overlap(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::CylinderSphere) {
    return sphere_cylinder_overlap(pose_b.apply(b.center), b.radius, a, pose_a);
  } else if constexpr (method == PairMethod::SphereCone) {
    return sphere_cone_overlap(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::ConeSphere) {
    return sphere_cone_overlap(pose_b.apply(b.center), b.radius, a, pose_a);
  } else if constexpr (method == PairMethod::BoxBox) {
    return box_box_contact(a, pose_a, b, pose_b, false).intersecting;
  } else if constexpr (method == PairMethod::RoundOther || method == PairMethod::OtherRound) {
    // GJK on the core with the radius as margin: stops as soon as the answer is decided; a needle
    // capsule as the part of it that decides (capsule_window)
    if constexpr (std::is_same_v<A, Capsule<S>>) {
      CapsuleCut<S> cut;
      if (capsule_window(a, pose_a, b, pose_b, cut)) return intersect_unchecked(cut.capsule, cut.pose, b, pose_b, options, limit_reached);
    } else if constexpr (std::is_same_v<B, Capsule<S>>) {
      CapsuleCut<S> cut;
      if (capsule_window(b, pose_b, a, pose_a, cut)) return intersect_unchecked(a, pose_a, cut.capsule, cut.pose, options, limit_reached);
    }
    ConvexDistance<S> d;
    const S tol = options.relative_tolerance * query_scale<S>(a, b);
    if constexpr (method == PairMethod::RoundOther) {
      const auto core = core_of(a);
      d = gjk(core, pose_a, core_interior(core), b, pose_b, interior_point(b), tol, options.max_iterations, round_radius(a));
    } else {
      const auto core = core_of(b);
      d = gjk(a, pose_a, interior_point(a), core, pose_b, core_interior(core), tol, options.max_iterations, round_radius(b));
    }
    if (limit_reached) *limit_reached = d.limit_reached;
    return d.intersecting;
  } else if constexpr (std::is_same_v<A, Cylinder<S>> && std::is_same_v<B, Cylinder<S>>) {  // convex/cylinder_intersect.hpp
    const PairFrame<S> f(pose_a, pose_b);
    const S scale = query_scale<S>(a, b);
    bool limit = false;
    const bool hit = cylinder_pair_intersect(a, b, f.R, f.t, scale, options.relative_tolerance * scale, options.max_iterations, limit);
    if (limit_reached) *limit_reached = limit;
    return hit;
  } else if constexpr ((std::is_same_v<A, Cylinder<S>> && std::is_same_v<B, Box<S>>) ||
                       (std::is_same_v<A, Box<S>> && std::is_same_v<B, Cylinder<S>>)) {  // convex/cylinder_box_pair.hpp
    const S scale = query_scale<S>(a, b);
    bool limit = false, hit;
    if constexpr (std::is_same_v<A, Cylinder<S>>) {
      const PairFrame<S> f(pose_a, pose_b);
      hit = cylinder_box_intersect(a, b, f.R, f.t, scale, options.relative_tolerance * scale, options.max_iterations, limit);
    } else {
      const PairFrame<S> f(pose_b, pose_a);
      hit = cylinder_box_intersect(b, a, f.R, f.t, scale, options.relative_tolerance * scale, options.max_iterations, limit);
    }
    if (limit_reached) *limit_reached = limit;
    return hit;
  } else {
    return ccd_intersect(a, pose_a, b, pose_b, options.boolean_algorithm, ccd_settings(options, query_scale<S>(a, b)), limit_reached);
  }
}
}  // namespace detail

/// Penetration of shapes a (at pose_a) and b (at pose_b): when they intersect, depth, normal (from
/// a towards b) and contact point (see the file comment for the method per pair).
template <class S, class A, class B>
ConvexContact<S> convex_penetration(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                                    const ConvexQueryOptions<S>& options = {}) {
  detail::validate_query(a, pose_a, b, pose_b, options, "convex_penetration");
  return detail::penetration_unchecked(a, pose_a, b, pose_b, options);
}

/// Separation distance of shapes a and b with the closest points of each (0 when they intersect).
template <class S, class A, class B>
ConvexDistance<S> convex_distance(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                                  const ConvexQueryOptions<S>& options = {}) {
  using namespace detail;
  detail::validate_query(a, pose_a, b, pose_b, options, "convex_distance");
  constexpr PairMethod method = pair_method<S, A, B>();
  if constexpr (method == PairMethod::RoundRound) {
    const CorePoints<S> q = core_points(a, pose_a, b, pose_b);
    return balls_distance(q.a, round_radius(a), q.b, round_radius(b), Vec3<S>(Vec3<S>::UnitZ()));
  } else if constexpr (method == PairMethod::SphereBox) {
    return sphere_box_distance(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::BoxSphere) {
    return swapped(sphere_box_distance(pose_b.apply(b.center), b.radius, a, pose_a));
  } else if constexpr (method == PairMethod::SphereCylinder) {
    return sphere_cylinder_distance(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::CylinderSphere) {
    return swapped(sphere_cylinder_distance(pose_b.apply(b.center), b.radius, a, pose_a));
  } else if constexpr (method == PairMethod::SphereCone) {
    return sphere_cone_distance(pose_a.apply(a.center), a.radius, b, pose_b);
  } else if constexpr (method == PairMethod::ConeSphere) {
    return swapped(sphere_cone_distance(pose_b.apply(b.center), b.radius, a, pose_a));
  } else if constexpr (method == PairMethod::RoundOther) {
    return round_distance(a, pose_a, b, pose_b, options);
  } else if constexpr (method == PairMethod::OtherRound) {
    return swapped(round_distance(b, pose_b, a, pose_a, options));
  } else {  // BoxBox and General: GJK
    const S tol = options.relative_tolerance * query_scale<S>(a, b);
    return gjk(a, pose_a, interior_point(a), b, pose_b, interior_point(b), tol, options.max_iterations);
  }
}

/// Boolean test: do shapes a and b touch or overlap? `limit_reached`, when not null, says whether
/// an iteration bound decided the answer.
template <class S, class A, class B>
bool convex_intersect(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                      const ConvexQueryOptions<S>& options = {}, bool* limit_reached = nullptr) {
  detail::validate_query(a, pose_a, b, pose_b, options, "convex_intersect");
  return detail::intersect_unchecked(a, pose_a, b, pose_b, options, limit_reached);
}

}  // namespace impact
