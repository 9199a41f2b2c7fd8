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
///
/// Where the parts live: the options and the validation in convex/query_options.hpp; the general
/// path (GJK, EPA, libccd, settling a contact along its normal) in convex/general_pair.hpp; a
/// sphere or capsule against the other shapes in convex/round_shape_pair.hpp; each certified pair
/// in its own file (named in the table above). This file holds the choice of method per pair, the
/// certified pair paths that combine those parts, and the three public queries.
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
#include "impact/convex/general_pair.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/libccd_solver.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/parallel_axes.hpp"
#include "impact/convex/polytope_sat.hpp"
#include "impact/convex/query_options.hpp"
#include "impact/convex/round_shape_pair.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/triangle_shape.hpp"

#include <algorithm>
#include <cmath>
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
    const CcdSettings settings = ccd_settings(options, query_scale<S>(a, b));
    if constexpr (general_swapped_v<S, A, B>) {
      return ccd_intersect(b, pose_b, a, pose_a, options.boolean_algorithm, settings, limit_reached);
    } else {
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
/// an iteration bound decided the answer.
template <class S, class A, class B>
bool convex_intersect(const A& a, const RigidTransform<S>& pose_a, const B& b, const RigidTransform<S>& pose_b,
                      const ConvexQueryOptions<S>& options = {}, bool* limit_reached = nullptr) {
  detail::validate_query(a, pose_a, b, pose_b, options, "convex_intersect");
  return detail::intersect_unchecked(a, pose_a, b, pose_b, options, limit_reached);
}

}  // namespace impact
