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
///                                     distance: that boolean test, GJK to a coarse gap, then the
///                                     nearest features (caps, sides, rims) certified by the
///                                     supporting planes, else GJK to the tolerance
///                                     (convex/cylinder_pair_distance.hpp); penetration as the
///                                     other pairs below
///   cylinder – box                    boolean: separating planes and common points, then GJK;
///                                     penetration: separating planes, the certified candidates,
///                                     else GJK and EPA with the local certificate
///                                     (convex/cylinder_box_pair.hpp); distance as below
///   other pairs                       boolean: cylinders, cones, boxes and hulls first the plane
///                                     normal to the line between the centres (separating: no
///                                     contact), then libccd MPR (default) or GJK; distance: GJK
///                                     (gjk_distance.hpp); penetration: cylinders and cones with
///                                     parallel axes in closed form (convex/parallel_axes.hpp);
///                                     cylinder against cylinder or cone
///                                     first through the certified candidates of
///                                     convex/cylinder_pair.hpp, cone against box through those of
///                                     convex/cone_box_pair.hpp, cone against cone through those
///                                     of convex/cone_cone_pair.hpp, then EPA with the local
///                                     certificate of convex/cone_box_terms.hpp or
///                                     cone_cone_terms; cone against hull: the centre line,
///                                     the certified candidates of convex/cone_hull_pair.hpp,
///                                     GJK, EPA with the local certificate of
///                                     convex/cone_hull_terms.hpp; else the own EPA (convex/epa.hpp;
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
/// options.max_iterations, one budget for the whole query that every stage's support calls count in
/// (candidates and normal refinements too: ConvexQueryOptions); a result stopped or changed by the
/// bound says limit_reached, and so does a
/// penetration whose bracket rounding or a degenerate polytope left open (penetration_unchecked).
/// An answer without limit_reached is decided. A flagged one is not: its boolean (the value of
/// convex_intersect, `intersecting` of a distance or penetration) may be wrong either way, while
/// its numbers still hold: a distance is never below the true one, and a penetration's
/// [depth - depth_gap, depth] holds the true depth, its lower end above 0 only when the
/// intersection was proven (docs/convex-notes.md, note 28); its normal may be EPA's unrefined one
/// (note 36).
/// Thread safety: the functions are pure; shapes and poses may be shared between threads.
///
/// Where the parts live: the options and the validation in convex/query_options.hpp; the general
/// path (GJK, EPA, libccd, settling a contact along its normal) in convex/general_pair.hpp; a
/// sphere or capsule against the other shapes in convex/round_shape_pair.hpp; the certified pair
/// paths, which combine each pair's candidates (in its own file, named in the table above) with
/// GJK and EPA, in convex/certified_pair.hpp. This file holds the choice of method per pair and
/// the three public queries.
#pragma once

#include "impact/convex/certified_pair.hpp"
#include "impact/convex/closed_form.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_box_pair.hpp"
#include "impact/convex/cylinder_pair_distance.hpp"
#include "impact/convex/cylinder_hull_pair.hpp"
#include "impact/convex/cylinder_intersect.hpp"
#include "impact/convex/general_pair.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/libccd_solver.hpp"
#include "impact/convex/polytope_sat.hpp"
#include "impact/convex/query_options.hpp"
#include "impact/convex/round_shape_pair.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/triangle_shape.hpp"

#include <limits>
#include <type_traits>

namespace impact {
namespace detail {

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

/// The order in which the general solvers (GJK, EPA, libccd) see a pair of shape types: a pair
/// whose b ranks lower than its a runs them on (b, a) and turns the answer back (swapped). So (b, a)
/// gets exactly the mirror image of (a, b)'s answer, and each unordered pair of types instantiates
/// those solvers once. The ranks follow the certified paths' order (cylinder before cone before box
/// before hull).
template <class T, class S>
constexpr int general_rank() {
  if constexpr (std::is_same_v<T, TriangleShape<S>>) {
    return 0;
  } else if constexpr (std::is_same_v<T, Cylinder<S>>) {
    return 1;
  } else if constexpr (std::is_same_v<T, Cone<S>>) {
    return 2;
  } else if constexpr (std::is_same_v<T, Box<S>>) {
    return 3;
  } else if constexpr (std::is_same_v<T, ConvexHull<S>>) {
    return 4;
  } else {
    return 5;
  }
}
template <class S, class A, class B>
inline constexpr bool general_swapped_v = general_rank<B, S>() < general_rank<A, S>();

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
    } else if constexpr (std::is_same_v<A, Cone<S>> && std::is_same_v<B, ConvexHull<S>>) {
      if (!options.libccd_penetration && use_cylinder_hull_candidates(b)) return cone_hull_penetration(a, pose_a, b, pose_b, options);
    } else if constexpr (std::is_same_v<A, ConvexHull<S>> && std::is_same_v<B, Cone<S>>) {
      if (!options.libccd_penetration && use_cylinder_hull_candidates(a)) return swapped(cone_hull_penetration(b, pose_b, a, pose_a, options));
    } else if constexpr (std::is_same_v<A, Box<S>> && std::is_same_v<B, ConvexHull<S>>) {  // separating axes
      if (!options.libccd_penetration && use_box_hull_sat(b)) return box_hull_sat(a, pose_a, b, pose_b);
    } else if constexpr (std::is_same_v<A, ConvexHull<S>> && std::is_same_v<B, Box<S>>) {
      if (!options.libccd_penetration && use_box_hull_sat(a)) return swapped(box_hull_sat(b, pose_b, a, pose_a));
    } else if constexpr (std::is_same_v<A, ConvexHull<S>> && std::is_same_v<B, ConvexHull<S>>) {
      if (!options.libccd_penetration && centre_line_separates(a, pose_a, b, pose_b)) return ConvexContact<S>{};
    }
    if constexpr (general_swapped_v<S, A, B>) {
      return swapped(general_penetration(b, pose_b, a, pose_a, options));
    } else {
      return general_penetration(a, pose_a, b, pose_b, options);
    }
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

/// The boolean's general pairs that try centre_line_separates before libccd: cylinders, cones,
/// boxes and hulls (on the convex bench's poses it ends about 70 % of the cylinder–cone boolean
/// queries before libccd, whose MPR or GJK decides the rest as before).
template <class S, class T>
inline constexpr bool centre_line_first_v = std::is_same_v<T, Cylinder<S>> || std::is_same_v<T, Cone<S>> ||
                                            std::is_same_v<T, Box<S>> || std::is_same_v<T, ConvexHull<S>>;

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
    // a plane normal to the line between the centres (one support call of each shape, not counted
    // against the bound, as the planes of the cylinder pairs' tests) decides most separated poses
    // without libccd (centre_line_separates), in the general solvers' order of the pair
    const CcdSettings settings = ccd_settings(options, query_scale<S>(a, b));
    constexpr bool plane_first = centre_line_first_v<S, A> && centre_line_first_v<S, B>;
    if constexpr (general_swapped_v<S, A, B>) {
      if constexpr (plane_first)
        if (centre_line_separates(b, pose_b, a, pose_a)) return false;
      return ccd_intersect(b, pose_b, a, pose_a, options.boolean_algorithm, settings, limit_reached);
    } else {
      if constexpr (plane_first)
        if (centre_line_separates(a, pose_a, b, pose_b)) return false;
      return ccd_intersect(a, pose_a, b, pose_b, options.boolean_algorithm, settings, limit_reached);
    }
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
  } else if constexpr (std::is_same_v<A, Cylinder<S>> && std::is_same_v<B, Cylinder<S>>) {  // convex/cylinder_pair_distance.hpp
    const S scale = query_scale<S>(a, b);
    return cylinder_pair_distance(a, pose_a, b, pose_b, scale, options.relative_tolerance * scale, options.max_iterations);
  } else {  // BoxBox and General: GJK
    const S tol = options.relative_tolerance * query_scale<S>(a, b);
    if constexpr (general_swapped_v<S, A, B>) {
      return swapped(gjk(b, pose_b, interior_point(b), a, pose_a, interior_point(a), tol, options.max_iterations));
    } else {
      return gjk(a, pose_a, interior_point(a), b, pose_b, interior_point(b), tol, options.max_iterations);
    }
  }
}

/// Boolean test: do shapes a and b touch or overlap? `limit_reached`, when not null, says whether
/// an iteration bound stopped the test: the answer is then not decided (either value may be wrong).
template <class S, class A, class B>
bool convex_intersect(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                      const ConvexQueryOptions<S>& options = {}, bool* limit_reached = nullptr) {
  detail::validate_query(a, pose_a, b, pose_b, options, "convex_intersect");
  return detail::intersect_unchecked(a, pose_a, b, pose_b, options, limit_reached);
}

}  // namespace impact
