// SPDX-License-Identifier: MIT
/// \file
/// A triangle mesh in its hierarchy (MeshBvh, any BV) under a rigid pose against one convex shape of
/// the convex layer under its pose (Sphere, Capsule, Cylinder, Cone, Box, ConvexHull, TriangleShape):
///   mesh_convex_collides   does any triangle touch or overlap the shape? (stops at the first)
///   mesh_convex_distance   separation distance, witness points and the closest triangle
///   mesh_convex_contacts   every intersecting triangle's penetration (depth, normal, point)
/// Needs the impact::convex target (libccd).
///
///   impact::MeshBvh<impact::Aabb<double>> mesh(V, F);
///   impact::Cylinder<double> cyl(0.3, 0.8);
///   if (impact::mesh_convex_collides(mesh, mesh_pose, cyl, cyl_pose)) ...
///   auto d = impact::mesh_convex_distance(mesh, mesh_pose, cyl, cyl_pose);   // d.distance, d.triangle
///   auto c = impact::mesh_convex_contacts(mesh, mesh_pose, cyl, cyl_pose);   // c.contacts[i].triangle, .contact
///
/// How: the shape is moved into the mesh's frame (one relative pose per query, the tree is neither
/// copied nor refitted); its tight box there (six support calls) and its own box carried by the
/// relative pose (an oriented box: exact for a Box) cull the tree: a box node is entered when no
/// separating axis (15, obb_overlap) puts it beyond a pad of the oriented box and its hull box is
/// within the pad of the tight box; a sphere node when its distance to both is within the pad.
/// Each triangle left is a TriangleShape
/// (convex/triangle_shape.hpp) against the shape:
///   sphere     closed form: the triangle's closest point to the centre (narrow/closest_point.hpp)
///   capsule    closed form: the closest points of the core segment and the triangle (end points
///              against the triangle, the segment against the three edges, the crossing of the
///              triangle's plane); penetration: depth = radius - that distance; when the segment
///              itself meets the triangle (within the tolerance): EPA as below
///   box        boolean and penetration: the 13 separating axes (exact depth for the polytope
///              pair; triangle_box_contact); distance: GJK
///   hull       penetration: the separating axes of the pair (convex/triangle_hull_sat.hpp: the
///              exact polytope depth; hulls of more than 128 faces: EPA as below); else as others
///   others     boolean: GJK with margin 0 (stops as soon as a separating plane or a simplex
///              within the tolerance is found); distance: GJK (convex/gjk_distance.hpp);
///              penetration: the own EPA (convex/epa.hpp), certified as convex_penetration's;
///              cylinders and cones first try the shortcut of convex/deepest_point.hpp (one point
///              of the triangle decides, certified by the ball about it: most contacts, no EPA)
/// Needles: a capsule or cylinder much longer than a triangle meets it through the part of its
/// axis that decides (needle_window: as capsule_window of convex/round_shape_pair.hpp), so the solvers see
/// coordinates of the triangle's size, not the needle's length (the capsule's contact normal,
/// the cylinder's boolean, distance and contact; tests/convex/test_needle_mesh.cpp).
/// GJK and EPA run in the shape's frame (the triangle moved there: three rotations per triangle
/// instead of two per support call).
/// The distance query walks nearest node first (traverse_nearest) and skips a node whose lower
/// bound (the gap between its BV and the shape's boxes: the hull boxes' gap and the face-axis
/// separations of the two oriented boxes, less the pad) is above the best distance found; it stops
/// at the first intersecting triangle.
///
/// Semantics (as FCL's mesh–shape queries and the library's mesh–mesh ones): the mesh is a surface.
/// The shape collides with the mesh when it touches or overlaps one of its triangles; a shape
/// wholly inside a closed mesh does not collide with it (its distance is the distance to the
/// nearest triangle).
///
/// Depth and normal of a triangle against the shape (MeshConvexContact): the triangle is thin, so
/// its penetration is the convex one of the flat closed triangle T (the set a) and the solid
/// shape (b): `normal` is unit and points from the triangle towards the shape, and translating the
/// shape by depth * normal (or the triangle by -depth * normal) makes the two only touch; depth is
/// the least such translation (closed forms exactly, EPA within its tolerance, depth_gap bounding
/// the rest). Which side: the side of the least translation. A shape whose centre is in front of
/// the triangle's face (on the side of (b - a) x (c - a)) and that reaches through the plane gets
/// the face normal or an edge/vertex direction on the front side; a shape pushed through the
/// triangle past its middle gets the back side, since leaving that way is shorter: the mesh's
/// winding plays no part, and a solver that wants one-sided contacts (a closed mesh's outside)
/// should flip contacts whose normal opposes the triangle's face normal itself. The contact point
/// lies midway between the triangle's deepest point and the shape's (point_a() on the triangle,
/// point_b() on the shape). A sphere or capsule whose centre or core lies on the triangle gets the
/// face normal (front side) and the depth of its radius (plus, for a capsule core crossing the
/// triangle, EPA's).
///
/// Numerical contract: APPROXIMATE, with the per-triangle contracts of convex/query.hpp (closed
/// forms to rounding; GJK distances are upper bounds within relative_tolerance of the larger of the
/// two sizes; pairs closer than that count as intersecting). The tree answers as a loop over every
/// triangle with the same per-triangle tests would: a node is skipped only when it lies farther
/// from the shape's boxes than the tolerance of any triangle it holds (relative_tolerance times the
/// larger of the shape's size and the node's diameter) plus a bound of the rounding of the box and
/// the relative pose (16 ulps of the coordinates involved). The shape is moved into the mesh's frame
/// by the rounded relative pose: answers can differ from a computation in world coordinates only
/// for configurations within that rounding of touching. Results are in world coordinates.
///
/// Validation: each call throws InvalidInput, before computing anything, on an invalid shape
/// (validate_shape), a pose that is not rigid or finite (validate_pose) or bad options; a MeshBvh
/// cannot be empty (its constructor throws). Iterative solvers are bounded by
/// options.convex.max_iterations per triangle; a result that relied on a stopped solver says
/// limit_reached, and is then not decided (convex/query.hpp: a flagged boolean may be wrong either
/// way; depths and distances still bound the truth).
/// Thread safety: the functions only read the tree and the shape: any number of threads may query
/// one tree at once (see MeshBvh).
#pragma once

#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/convex/query.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/triangle_hull_sat.hpp"
#include "impact/convex/triangle_shape.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/query/mesh_collide.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

namespace impact {

/// Options of the mesh–convex queries.
template <class S>
struct MeshConvexOptions {
  ConvexQueryOptions<S> convex;  ///< the per-triangle solvers' options (tolerances, iteration bound)
  /// mesh_convex_contacts: stop after this many contacts (>= 1); the default reports all.
  std::size_t max_contacts = std::numeric_limits<std::size_t>::max();
  /// mesh_convex_contacts, triangles against cylinders, cones and hulls (and capsules whose core
  /// meets the triangle): false (default) runs the own EPA (convex/epa.hpp), certified as
  /// convex_penetration (the least depth within its tolerance, depth_gap bounding the rest), after
  /// the deepest-point shortcut for cylinders and cones (convex/deepest_point.hpp); true runs one
  /// libccd MPR per triangle (ccdMPRPenetration, as FCL does), settled along MPR's direction:
  /// translating the shape by depth * normal still leaves them touching, but the depth can exceed
  /// the least one and is not certified (depth_gap = depth). About 1.3x faster than the default
  /// (the separating axes) on the bench's hulls; slower on its cylinders and cones (2-3x), where
  /// the shortcut answers most triangles.
  bool fast_contacts = false;
};

/// Result of mesh_convex_distance, world coordinates.
template <class S>
struct MeshConvexDistance {
  S distance = S(0);                      ///< >= 0; 0 when the shape touches a triangle
  Vec3<S> point_mesh = Vec3<S>::Zero();   ///< closest point on the mesh (on `triangle`)
  Vec3<S> point_shape = Vec3<S>::Zero();  ///< closest point of the shape
  std::int32_t triangle = -1;             ///< row of F of the closest (or a touching) triangle
  bool intersecting = false;              ///< the shape touches or overlaps a triangle
  bool limit_reached = false;             ///< a per-triangle solver hit its iteration bound
  QueryStats stats;                       ///< node tests and triangle tests
};

/// One intersecting triangle's penetration (see the file comment for depth and normal).
template <class S>
struct MeshConvexContact {
  std::int32_t triangle = -1;  ///< row of F
  /// depth, normal (unit, from the triangle towards the shape), point (world); point_a() is the
  /// triangle's deepest point, point_b() the shape's
  ConvexContact<S> contact;
};

/// Result of mesh_convex_contacts.
template <class S>
struct MeshConvexContacts {
  bool colliding = false;
  std::vector<MeshConvexContact<S>> contacts;  ///< by increasing triangle id
  bool limit_reached = false;                ///< a per-triangle solver hit its iteration bound
  bool truncated = false;                    ///< options.max_contacts stopped the walk
  QueryStats stats;
  /// Index in `contacts` of the deepest contact, -1 when there is none.
  std::ptrdiff_t deepest() const {
    std::ptrdiff_t best = -1;
    for (std::size_t i = 0; i < contacts.size(); ++i)
      if (best < 0 || contacts[i].contact.depth > contacts[static_cast<std::size_t>(best)].contact.depth) best = std::ptrdiff_t(i);
    return best;
  }
};

namespace detail {

/// The closest points of a segment and a triangle (either may be degenerate).
template <class S>
struct SegmentTrianglePoints {
  Vec3<S> on_segment = Vec3<S>::Zero(), on_triangle = Vec3<S>::Zero();
  S squared_distance = S(0);
};

/// Closest points of the closed segment s and the closed triangle t: the best of the end points
/// against the triangle, the segment against the three edges and, when the end points lie on
/// opposite sides of the triangle's plane (or on it), the crossing point against the triangle.
/// When the segment does not meet the triangle one of the first two pairs is closest (a closest
/// pair has an end point of the segment or a point of an edge); when it meets the interior the
/// crossing point is at distance 0 (up to rounding).
template <class S>
SegmentTrianglePoints<S> closest_points_segment_triangle(const Segment<S>& s, const Triangle<S>& t) {
  SegmentTrianglePoints<S> best;
  best.squared_distance = std::numeric_limits<S>::infinity();
  const auto take = [&](const Vec3<S>& on_seg, const Vec3<S>& on_tri, S d2) {
    if (d2 < best.squared_distance) {
      best.on_segment = on_seg;
      best.on_triangle = on_tri;
      best.squared_distance = d2;
    }
  };
  const Vec3<S> n = t.scaled_normal();
  const S s0 = n.dot(s.p - t.a), s1 = n.dot(s.q - t.a);
  if (((s0 <= S(0) && s1 >= S(0)) || (s0 >= S(0) && s1 <= S(0))) && s0 != s1) {
    const Vec3<S> x = s.at(std::clamp(s0 / (s0 - s1), S(0), S(1)));
    const auto c = closest_point_on_triangle(x, t);
    take(x, c.point, c.squared_distance);
    if (best.squared_distance == S(0)) return best;
  }
  const auto cp = closest_point_on_triangle(s.p, t);
  take(s.p, cp.point, cp.squared_distance);
  const auto cq = closest_point_on_triangle(s.q, t);
  take(s.q, cq.point, cq.squared_distance);
  const Vec3<S>* v[3] = {&t.a, &t.b, &t.c};
  for (int k = 0; k < 3; ++k) {
    const auto e = closest_points_segment_segment(s, Segment<S>(*v[k], *v[(k + 1) % 3]));
    take(e.point_a, e.point_b, e.squared_distance);
  }
  return best;
}

/// The unit normal of t, or (degenerate t) a unit vector orthogonal to its longest edge, or +z.
template <class S>
Vec3<S> triangle_fallback_normal(const Triangle<S>& t) {
  const Vec3<S> n = t.scaled_normal();
  const S len = n.norm();
  if (len > S(0)) return n / len;
  Vec3<S> e = t.b - t.a;
  if ((t.c - t.a).squaredNorm() > e.squaredNorm()) e = t.c - t.a;
  if ((t.c - t.b).squaredNorm() > e.squaredNorm()) e = t.c - t.b;
  const S el = e.norm();
  return el > S(0) ? any_orthogonal(Vec3<S>(e / el)) : Vec3<S>(Vec3<S>::UnitZ());
}

/// A ball (centre c, radius r) and the closest point q of a triangle to c (squared distance d2):
/// the contact of the triangle (a) with the ball (b), in the triangle's frame.
template <class S>
ConvexContact<S> triangle_ball_contact(const Triangle<S>& t, const Vec3<S>& c, S r, const Vec3<S>& q, S d2) {
  ConvexContact<S> out;
  if (d2 > r * r) return out;
  out.intersecting = true;
  const S d = std::sqrt(d2);
  out.normal = d > S(0) ? Vec3<S>((c - q) / d) : triangle_fallback_normal(t);
  out.depth = r - d;
  // deepest points: q (triangle), c - r n (ball)
  out.point = (q + c - r * out.normal) / S(2);
  return out;
}

template <class S>
ConvexDistance<S> triangle_ball_distance(const Vec3<S>& c, S r, const Vec3<S>& q, S d2) {
  ConvexDistance<S> out;
  const S d = std::sqrt(d2);
  out.intersecting = d2 <= r * r;
  out.distance = std::max(d - r, S(0));
  out.point_a = q;
  out.point_b = d > S(0) ? Vec3<S>(c + (q - c) * (r / d)) : c;
  return out;
}

/// Triangle t against a box (half extents h) placed by `pose`, by the 13 separating axes of the
/// pair (the box's three face normals, the triangle's normal, the nine cross products of their
/// edges): with `want_contact` false only the boolean (`intersecting`); else the least overlap over
/// those axes, which for two polytopes is the penetration depth (the Minkowski difference's faces
/// lie on them), with its axis as the normal (from the triangle towards the box) and the point
/// midway between the centres of the two deepest features. Cross products of nearly parallel
/// edges (|e x f| < 1e-6 |e| |f|) are skipped as in box_box_contact: the face axes then decide
/// their separation within 1e-6 of the sizes (boolean: conservative by that much).
template <class S>
ConvexContact<S> triangle_box_contact(const Triangle<S>& tri, const Box<S>& box, const RigidTransform<S>& pose, bool want_contact) {
  ConvexContact<S> out;
  const Vec3<S>& h = box.half;
  // the triangle in the box's frame
  const Vec3<S> v[3] = {pose.R.transpose() * (tri.a - pose.t), pose.R.transpose() * (tri.b - pose.t), pose.R.transpose() * (tri.c - pose.t)};
  const Vec3<S> e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  S best = std::numeric_limits<S>::infinity();
  Vec3<S> best_axis = Vec3<S>::UnitZ();  // unit, box frame, from the triangle towards the box
  // false when `axis` (unit) separates; else records the least overlap
  const auto consider = [&](const Vec3<S>& axis) {
    const S p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
    const S lo = std::min({p0, p1, p2}), hi = std::max({p0, p1, p2});
    const S r = axis.cwiseAbs().dot(h);
    if (lo > r || hi < -r) return false;
    const S up = hi + r, down = r - lo;  // moving the box along +axis, along -axis
    if (up < best) {
      best = up;
      best_axis = axis;
    }
    if (down < best) {
      best = down;
      best_axis = -axis;
    }
    return true;
  };
  for (int i = 0; i < 3; ++i)
    if (!consider(Vec3<S>::Unit(i))) return out;
  const Vec3<S> n = e[0].cross(-e[2]);
  const S nn = n.norm();
  if (nn > S(0) && !consider(Vec3<S>(n / nn))) return out;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const Vec3<S> axis = Vec3<S>::Unit(i).cross(e[k]);
      const S len = axis.norm();
      if (!(len > S(1e-6) * e[k].norm())) continue;
      if (!consider(Vec3<S>(axis / len))) return out;
    }
  out.intersecting = true;
  if (!want_contact) return out;
  out.depth = std::max(best, S(0));
  out.normal = pose.rotate(best_axis);
  // deepest features: the triangle's vertices farthest along the normal (their centre), the box's
  // feature farthest against it (its centre)
  const S top = std::max({best_axis.dot(v[0]), best_axis.dot(v[1]), best_axis.dot(v[2])});
  const S tie = S(1e-9) * (v[0] - v[1]).cwiseAbs().sum() + S(1e-9) * (v[2] - v[1]).cwiseAbs().sum();
  Vec3<S> ta = Vec3<S>::Zero();
  int count = 0;
  for (const auto& x : v)
    if (best_axis.dot(x) >= top - tie) {
      ta += x;
      ++count;
    }
  ta /= S(count);
  Vec3<S> tb;
  for (int k = 0; k < 3; ++k) tb[k] = std::abs(best_axis[k]) < S(1e-9) ? S(0) : (best_axis[k] > S(0) ? -h[k] : h[k]);
  out.point = pose.apply(Vec3<S>((ta + tb) / S(2)));
  return out;
}

/// A needle's window: capsule or cylinder a (placed in the mesh frame by pa) much longer than
/// triangle tri, cut to the part of it that decides the pair (as capsule_window of
/// convex/query.hpp does for shape pairs, whose argument this follows). The window is the axis
/// interval |t - t0| <= L about the projection t0 of the triangle's centroid, L = 2 (rho + rb)
/// for a capsule and 2 (rho + rb + r) for a cylinder (rho the centroid's distance to the axis,
/// rb the triangle's size about it, r the radius), kept where it passes an end, and at least 2 r
/// long for a cylinder. False (a as it is) unless the window is less than half the segment and
/// holds a point of it; with `distance` also unless t0 lies on the segment.
/// Why a cylinder's window needs the radius more: along a unit n at angle theta from the plane
/// normal to the axis the cut cylinder overlaps the triangle by r cos(theta) + g(n) + L sin(theta)
/// on a cut side (g as for the capsule, Lipschitz with constant K = rho + rb), which is at least
/// r + g(n') at n's projection n' when (L - pi/2 K) sin(theta) >= r (1 - cos(theta)), true for
/// L >= pi/2 K + r. So the least overlap (the depth, or minus the distance) is the whole
/// cylinder's, and the solvers see coordinates of the triangle's size instead of the needle's
/// length (GJK on a cylinder 1e8 times longer than wide called pairs 1.8 deep apart).
/// `low`, `high`: whether the window cuts the axis below, above.
template <class S>
struct NeedleWindow {
  RigidTransform<S> pose, to_shape;
  S half_length = S(0);
  bool low = false, high = false;
};
template <class S>
bool needle_window(const Capsule<S>& a, const RigidTransform<S>& pa, const Triangle<S>& tri, bool distance, NeedleWindow<S>& w) {
  CapsuleCut<S> cut;
  if (!capsule_window(a, pa, TriangleShape<S>(tri), RigidTransform<S>(), cut, distance)) return false;
  w.pose = cut.pose;
  w.half_length = cut.capsule.half_length;
  w.low = cut.low;
  w.high = cut.high;
  w.to_shape = w.pose.inverse();
  return true;
}
template <class S>
bool needle_window(const Cylinder<S>& a, const RigidTransform<S>& pa, const Triangle<S>& tri, bool distance, NeedleWindow<S>& w) {
  const S h = a.half_length, r = a.radius;
  if (!(S(8) * r < h)) return false;  // the window is at least 4 r long
  const TriangleShape<S> t(tri);
  const Vec3<S> cb = pa.R.transpose() * (interior_point(t) - pa.t);  // in a's frame
  const S rho = std::sqrt(cb.x() * cb.x() + cb.y() * cb.y());
  const S len = S(2) * (rho + shape_size(t) + r);
  if (!(S(2) * len < h)) return false;  // also for NaN
  if (distance && !(std::abs(cb.z()) <= h)) return false;
  S t1 = std::max(cb.z() - len, -h), t2 = std::min(cb.z() + len, h);
  if (!(t1 <= t2)) return false;
  w.low = t1 > -h;
  w.high = t2 < h;
  if (t2 - t1 < S(2) * r) {  // the window passes an end (both ends when it is 2 len >= 4 r long)
    if (w.high) {
      t2 = t1 + S(2) * r;
    } else {
      t1 = t2 - S(2) * r;
    }
  }
  w.half_length = (t2 - t1) / S(2);
  w.pose.R = pa.R;
  w.pose.t = pa.t + pa.R.col(2) * ((t1 + t2) / S(2));
  w.to_shape = w.pose.inverse();
  return true;
}

/// The per-triangle tests: triangle t (mesh frame) against `shape` placed in the mesh frame by
/// `pose`. Boolean, distance and penetration, the triangle as a (see the file comment).
template <class S, class Shape>
struct TriangleConvexTests {
  /// The shape as the solvers see it: the query's, or a needle's window (needle_window).
  struct Placed {
    const Shape& shape;
    const RigidTransform<S>& pose;
    const RigidTransform<S>& to_shape;  // the mesh frame into the shape's: GJK and EPA run there
    S size;
  };

  const Shape& shape;
  const RigidTransform<S>& pose;
  const ConvexQueryOptions<S>& options;
  S shape_size_;
  RigidTransform<S> to_shape;  // the mesh frame into the shape's

  bool fast = false;  // MeshConvexOptions::fast_contacts

  TriangleConvexTests(const Shape& s, const RigidTransform<S>& p, const ConvexQueryOptions<S>& o, bool fast_contacts = false)
      : shape(s), pose(p), options(o), shape_size_(shape_size(s)), to_shape(p.inverse()), fast(fast_contacts) {}

  Placed whole() const { return Placed{shape, pose, to_shape, shape_size_}; }

  S tolerance(const Placed& ps, const TriangleShape<S>& t) const { return options.relative_tolerance * std::max(ps.size, shape_size(t)); }

  /// The triangle in the shape's frame: three rotations per triangle instead of two per support
  /// call of the shape in the iterative solvers.
  static TriangleShape<S> in_shape_frame(const Placed& ps, const Triangle<S>& tri) {
    return TriangleShape<S>(ps.to_shape.apply(tri.a), ps.to_shape.apply(tri.b), ps.to_shape.apply(tri.c));
  }

  /// GJK in the shape's frame; witness points in the mesh frame.
  ConvexDistance<S> gjk_pair(const Placed& ps, const Triangle<S>& tri, S margin) const {
    const TriangleShape<S> t = in_shape_frame(ps, tri);
    const auto sa = [&t](const Vec3<S>& d) { return support(t, d); };
    const auto sb = [&ps](const Vec3<S>& d) { return support(ps.shape, d); };
    ConvexDistance<S> r =
        gjk_distance<S>(sa, sb, Vec3<S>(interior_point(t) - interior_point(ps.shape)), tolerance(ps, t), options.max_iterations, margin);
    r.point_a = ps.pose.apply(r.point_a);
    r.point_b = ps.pose.apply(r.point_b);
    return r;
  }

  /// The own EPA in the shape's frame, settled as general_penetration settles it (the point onto
  /// the mid plane, the depth the overlap along the normal when smaller); false when it met a
  /// degenerate Minkowski difference. The contact in the mesh frame.
  bool epa_pair(const Placed& ps, const Triangle<S>& tri, ConvexContact<S>& c) const {
    const TriangleShape<S> t = in_shape_frame(ps, tri);
    const auto sa = [&t](const Vec3<S>& d) { return support(t, d); };
    const auto sb = [&ps](const Vec3<S>& d) { return support(ps.shape, d); };
    const bool refine = options.newton_refinement && !(is_polytope_v<Shape, S>);
    int shortcut_calls = 0;
    if constexpr (std::is_same_v<Shape, Cylinder<S>> || std::is_same_v<Shape, Cone<S>>) {  // one point of the triangle decides (convex/deepest_point.hpp)
      if (triangle_deepest_point_contact(t, ps.shape, options.relative_tolerance * query_scale<S>(t, ps.shape), c)) {
        c.normal = ps.pose.rotate(c.normal);
        c.point = ps.pose.apply(c.point);
        return true;
      }
      shortcut_calls = c.iterations;
    }
    bool failed = false;
    c = own_epa_in_frame(sa, sb, interior_point(t), interior_point(ps.shape), query_scale<S>(t, ps.shape), options, refine, failed);
    c.iterations += shortcut_calls;
    if (failed) return false;
    if (c.intersecting) {
      const S depth = c.depth;
      const RigidTransform<S> identity;
      settle_contact(t, identity, ps.shape, identity, c);
      c.depth = std::min(c.depth, depth);
      c.normal = ps.pose.rotate(c.normal);
      c.point = ps.pose.apply(c.point);
    }
    return true;
  }

  /// A needle's contact found on its window: a normal with a component along the axis towards a
  /// side the window cuts is projected onto the plane normal to the axis (the whole needle
  /// overlaps more than the window along it, by the length cut off times that component; at the
  /// projection the two agree and the window's overlap is not larger: needle_window), then
  /// settled there.
  void settle_on_window(const Placed& ps, const NeedleWindow<S>& w, const Triangle<S>& tri, ConvexContact<S>& c) const {
    if (!c.intersecting) return;
    const Vec3<S> u = w.pose.R.col(2);
    const S nz = c.normal.dot(u);
    if (!((nz > S(0) && w.high) || (nz < S(0) && w.low))) return;
    const Vec3<S> m = c.normal - nz * u;
    const S len = m.norm();
    if (!(len > S(0))) return;
    const S lower = c.depth - c.depth_gap;
    c.normal = m / len;
    const RigidTransform<S> identity;
    settle_contact(TriangleShape<S>(tri), identity, ps.shape, ps.pose, c);
    c.depth_gap = std::max(c.depth - lower, S(0));
  }

  /// Runs f(placed) on the needle's window of tri when there is one (capsules and cylinders far
  /// longer than the triangle: needle_window), else on the whole shape. `settle`: a contact's
  /// normal made normal to the axis where the window cuts (settle_on_window).
  template <class F>
  auto on_needle(const Triangle<S>& tri, bool distance, F&& f) const {
    if constexpr (std::is_same_v<Shape, Capsule<S>> || std::is_same_v<Shape, Cylinder<S>>) {
      NeedleWindow<S> w;
      if (needle_window(shape, pose, tri, distance, w)) {
        Shape cut = shape;
        cut.half_length = w.half_length;  // a part of a valid shape, at least 2 r long for a cylinder
        const Placed ps{cut, w.pose, w.to_shape, shape_size(cut)};
        auto out = f(ps);
        if constexpr (std::is_same_v<decltype(out), ConvexContact<S>>) settle_on_window(ps, w, tri, out);
        return out;
      }
    }
    return f(whole());
  }

  bool intersect(const Triangle<S>& tri, bool& limit) const {
    if constexpr (std::is_same_v<Shape, Sphere<S>>) {
      const Vec3<S> c = pose.apply(shape.center);
      return closest_point_on_triangle(c, tri).squared_distance <= shape.radius * shape.radius;
    } else if constexpr (std::is_same_v<Shape, Capsule<S>>) {
      return closest_points_segment_triangle(capsule_segment(shape, pose), tri).squared_distance <= shape.radius * shape.radius;
    } else if constexpr (std::is_same_v<Shape, Box<S>>) {
      return triangle_box_contact(tri, shape, pose, false).intersecting;
    } else {
      const ConvexDistance<S> d = on_needle(tri, false, [&](const Placed& ps) { return gjk_pair(ps, tri, S(0)); });
      limit = limit || d.limit_reached;
      return d.intersecting;
    }
  }

  ConvexDistance<S> distance(const Triangle<S>& tri) const {
    if constexpr (std::is_same_v<Shape, Sphere<S>>) {
      const Vec3<S> c = pose.apply(shape.center);
      const auto q = closest_point_on_triangle(c, tri);
      return triangle_ball_distance(c, shape.radius, q.point, q.squared_distance);
    } else if constexpr (std::is_same_v<Shape, Capsule<S>>) {
      const auto q = closest_points_segment_triangle(capsule_segment(shape, pose), tri);
      return triangle_ball_distance(q.on_segment, shape.radius, q.on_triangle, q.squared_distance);
    } else {
      return on_needle(tri, true, [&](const Placed& ps) { return gjk_pair(ps, tri, S(-1)); });
    }
  }

  ConvexContact<S> penetration(const Triangle<S>& tri) const {
    if constexpr (std::is_same_v<Shape, Sphere<S>>) {
      const Vec3<S> c = pose.apply(shape.center);
      const auto q = closest_point_on_triangle(c, tri);
      return triangle_ball_contact(tri, c, shape.radius, q.point, q.squared_distance);
    } else if constexpr (std::is_same_v<Shape, Box<S>>) {
      ConvexContact<S> c = triangle_box_contact(tri, shape, pose, true);
      const RigidTransform<S> identity;
      settle_contact(TriangleShape<S>(tri), identity, shape, pose, c);
      return c;
    } else {
      if constexpr (std::is_same_v<Shape, ConvexHull<S>>) {  // the separating axes of the pair (convex/triangle_hull_sat.hpp)
        if (!fast && !options.libccd_penetration && use_triangle_hull_sat(shape)) {
          ConvexContact<S> c = triangle_hull_sat(in_shape_frame(whole(), tri).triangle, shape);
          c.normal = pose.rotate(c.normal);
          c.point = pose.apply(c.point);
          return c;
        }
      }
      const TriangleShape<S> t(tri);
      if constexpr (std::is_same_v<Shape, Capsule<S>>) {
        const auto q = closest_points_segment_triangle(capsule_segment(shape, pose), tri);
        const S tol = tolerance(whole(), t);
        if (q.squared_distance > tol * tol) {
          if (q.squared_distance > shape.radius * shape.radius) return ConvexContact<S>();
          // a contact: its normal from the needle's window when there is one (the closest points
          // on a segment 1e9 times longer than the radius tilt the normal by up to 4e-6 along it)
          return on_needle(tri, false, [&](const Placed& ps) {
            const auto w = closest_points_segment_triangle(capsule_segment(ps.shape, ps.pose), tri);
            return triangle_ball_contact(tri, w.on_segment, shape.radius, w.on_triangle, w.squared_distance);
          });
        }
      }
      // the general pair, or a capsule whose core meets the triangle
      const RigidTransform<S> identity;
      if (fast) {
        ConvexContact<S> c =
            to_contact(ccd_penetration(t, identity, shape, pose, CcdAlgorithm::Mpr, ccd_settings(options, query_scale<S>(t, shape))));
        settle_contact(t, identity, shape, pose, c);
        c.depth_gap = c.depth;
        return c;
      }
      if constexpr (pair_method<S, TriangleShape<S>, Shape>() == PairMethod::General) {
        if (options.libccd_penetration) return penetration_unchecked(t, identity, shape, pose, options);
        return on_needle(tri, false, [&](const Placed& ps) {
          ConvexContact<S> c;
          if (epa_pair(ps, tri, c)) return c;
          return epa(t, identity, ps.shape, ps.pose, options);  // a degenerate Minkowski difference: libccd, as the pairwise query
        });
      } else {
        return penetration_unchecked(t, identity, shape, pose, options);  // a capsule through its core, as the pairwise query
      }
    }
  }
};

/// Diameter of a node's BV (bounds the size of every triangle in it).
template <class S>
S bv_diameter(const Aabb<S>& b) {
  return (b.max - b.min).norm();
}
template <class S>
S bv_diameter(const Obb<S>& b) {
  return S(2) * b.half.norm();
}
template <class S>
S bv_diameter(const Sphere<S>& b) {
  return S(2) * b.radius;
}

/// The shape's bounding volumes in the mesh's frame: its tight axis-aligned box there, and its own
/// box (from six support calls in its frame) carried by the relative pose, an oriented box (exact
/// for a Box, tight for capsules, cylinders and cones whatever the rotation).
template <class S>
struct ShapeBounds {
  Aabb<S> box;
  Obb<S> obb;
};

/// A box holding the oriented box b, for the node tests: bounding_aabb(b) without its six
/// nextafter calls (a third of a node test's instructions on OBB trees), grown instead by
/// 2 eps (|c| + r) per axis, which covers the rounding of c -+ r (half an ulp of |c| + r each)
/// and, through the factor 1 + 8 eps, of the radius r = |axes| half (three non-negative products
/// and two sums). An invalid box (a negative half extent) gives the empty box, as bounding_aabb.
template <class S>
Aabb<S> obb_hull_box(const Obb<S>& b) {
  if ((b.half.array() < S(0)).any()) return Aabb<S>();
  constexpr S eps = std::numeric_limits<S>::epsilon();
  const Vec3<S> r = (b.axes.cwiseAbs() * b.half) * (S(1) + S(8) * eps);
  const Vec3<S> grown = r + S(2) * eps * (b.center.cwiseAbs() + r);
  Aabb<S> box;
  box.min = b.center - grown;
  box.max = b.center + grown;
  return box;
}

/// The largest separation of two boxes along the six face axes (negative when none separates):
/// box A axis-aligned about the origin with half extents ea, box B with axes R (columns) about tb
/// with half extents eb, as obb_overlap takes them. Each axis's separation is a lower bound of the
/// distance between the boxes.
template <class S>
S face_axes_gap(const Vec3<S>& ea, const Mat3<S>& R, const Vec3<S>& tb, const Vec3<S>& eb) {
  const Mat3<S> absR = R.cwiseAbs();
  S gap = -std::numeric_limits<S>::infinity();
  for (int i = 0; i < 3; ++i) gap = std::max(gap, std::abs(tb[i]) - ea[i] - absR.row(i).dot(eb));
  for (int j = 0; j < 3; ++j) gap = std::max(gap, std::abs(R.col(j).dot(tb)) - absR.col(j).dot(ea) - eb[j]);
  return gap;
}

/// A lower bound of the distance between a node's BV and the shape (0 when they may overlap): the
/// gap between the node's (hull) box and the shape's box, and the face-axis separations of the
/// node's box against the shape's oriented box.
template <class S>
S bv_shape_gap(const Aabb<S>& b, const ShapeBounds<S>& sb) {
  const Vec3<S> e = (b.min - sb.box.max).cwiseMax(sb.box.min - b.max).cwiseMax(Vec3<S>::Zero());
  const Vec3<S> c = (b.max + b.min) / S(2);
  return std::max(e.norm(), face_axes_gap(Vec3<S>((b.max - b.min) / S(2)), sb.obb.axes, Vec3<S>(sb.obb.center - c), sb.obb.half));
}
template <class S>
S bv_shape_gap(const Obb<S>& b, const ShapeBounds<S>& sb) {
  const Aabb<S> h = obb_hull_box(b);
  const S hull = (h.min - sb.box.max).cwiseMax(sb.box.min - h.max).cwiseMax(Vec3<S>::Zero()).norm();
  const Mat3<S> R = b.axes.transpose() * sb.obb.axes;
  const Vec3<S> tb = b.axes.transpose() * (sb.obb.center - b.center);
  return std::max(hull, face_axes_gap(b.half, R, tb, sb.obb.half));
}
template <class S>
S bv_shape_gap(const Sphere<S>& b, const ShapeBounds<S>& sb) {
  const Vec3<S> q = b.center.cwiseMax(sb.box.min).cwiseMin(sb.box.max);
  const Vec3<S> l = sb.obb.axes.transpose() * (b.center - sb.obb.center);
  const S to_obb = (l - l.cwiseMax(-sb.obb.half).cwiseMin(sb.obb.half)).norm();
  return std::max(std::max((b.center - q).norm(), to_obb) - b.radius, S(0));
}

/// May the node's BV come within `pad` of the shape? (Culls the boolean and contact walks.) Boxes:
/// the gap of bv_shape_gap, then the 15 separating axes of the node's box grown by pad against the
/// shape's oriented box (obb_overlap).
template <class S>
bool bv_shape_near(const Aabb<S>& b, const ShapeBounds<S>& sb, S pad) {
  const Vec3<S> e = (b.min - sb.box.max).cwiseMax(sb.box.min - b.max).cwiseMax(Vec3<S>::Zero());
  if (!(e.norm() <= pad)) return false;
  const Vec3<S> ea = (b.max - b.min) / S(2) + Vec3<S>::Constant(pad);
  return obb_overlap<S>(ea, sb.obb.axes, Vec3<S>(sb.obb.center - (b.max + b.min) / S(2)), sb.obb.half);
}
template <class S>
bool bv_shape_near(const Obb<S>& b, const ShapeBounds<S>& sb, S pad) {
  const Aabb<S> hull = obb_hull_box(b);
  const Vec3<S> e = (hull.min - sb.box.max).cwiseMax(sb.box.min - hull.max).cwiseMax(Vec3<S>::Zero());
  if (!(e.norm() <= pad)) return false;
  const Mat3<S> R = b.axes.transpose() * sb.obb.axes;
  const Vec3<S> tb = b.axes.transpose() * (sb.obb.center - b.center);
  return obb_overlap<S>(Vec3<S>(b.half + Vec3<S>::Constant(pad)), R, tb, sb.obb.half);
}
template <class S>
bool bv_shape_near(const Sphere<S>& b, const ShapeBounds<S>& sb, S pad) {
  return bv_shape_gap(b, sb) <= pad;
}

/// What every query sets up: the shape in the mesh's frame, its bounds there, and the pads.
template <class S, class Shape>
struct MeshConvexFrame {
  RigidTransform<S> pose;  // the shape's pose in the mesh's frame
  ShapeBounds<S> bounds;   // its boxes there
  S rounding_pad = S(0);   // bound of the rounding of the boxes and the pose
  S shape_size_ = S(0);
  S relative_tolerance = S(0);

  template <class BV>
  MeshConvexFrame(const MeshBvh<BV>& mesh, const RigidTransform<S>& mesh_pose, const Shape& shape, const RigidTransform<S>& shape_pose,
                  const ConvexQueryOptions<S>& o)
      : pose(mesh_pose.inverse() * shape_pose), shape_size_(shape_size(shape)), relative_tolerance(o.relative_tolerance) {
    bounds.box = bounding_box(shape, pose);
    const Aabb<S> local = bounding_box(shape, RigidTransform<S>());
    bounds.obb.center = pose.apply(local.center());
    bounds.obb.axes = pose.R;
    bounds.obb.half = (local.max - local.min) / S(2);
    constexpr S eps = std::numeric_limits<S>::epsilon();
    rounding_pad = S(16) * eps *
                   (mesh.coordinate_bound() + shape_pose.t.cwiseAbs().maxCoeff() + mesh_pose.t.cwiseAbs().maxCoeff() + shape_size_ +
                    bounds.box.min.cwiseAbs().maxCoeff() + bounds.box.max.cwiseAbs().maxCoeff());
  }
  /// The pad of a node: any triangle in it may count as touching the shape within its tolerance.
  template <class BV>
  S pad(const BV& bv) const {
    return relative_tolerance * std::max(shape_size_, bv_diameter(bv)) + rounding_pad;
  }
};

template <class S, class Shape>
void validate_mesh_convex(const RigidTransform<S>& mesh_pose, const Shape& shape, const RigidTransform<S>& shape_pose,
                          const MeshConvexOptions<S>& o, const char* where) {
  static_assert(is_supported_scalar_v<S>, "mesh-convex queries: S must be float or double");
  validate_shape(shape, where);
  validate_pose(mesh_pose, where, "mesh_pose");
  validate_pose(shape_pose, where, "shape_pose");
  validate_query_options(o.convex, where);
  if (o.max_contacts < 1) throw InvalidInput(std::string(where) + ": options.max_contacts must be >= 1");
}

}  // namespace detail

/// Does the shape (at shape_pose) touch or overlap any triangle of the mesh (at mesh_pose)? Stops
/// at the first such triangle. `stats` (optional) receives the work counters, `limit_reached`
/// (optional) whether an iteration bound decided a triangle's test.
template <class BV, class Shape, class S = typename BvTraits<BV>::Scalar>
bool mesh_convex_collides(const MeshBvh<BV>& mesh, const RigidTransform<S>& mesh_pose, const Shape& shape,
                          const RigidTransform<S>& shape_pose, const MeshConvexOptions<S>& options = {}, QueryStats* stats = nullptr,
                          bool* limit_reached = nullptr) {
  detail::validate_mesh_convex(mesh_pose, shape, shape_pose, options, "mesh_convex_collides");
  const detail::MeshConvexFrame<S, Shape> frame(mesh, mesh_pose, shape, shape_pose, options.convex);
  const detail::TriangleConvexTests<S, Shape> tests(shape, frame.pose, options.convex);
  QueryStats st;
  bool hit = false, limit = false;
  traverse(
      mesh.tree(),
      [&](const BV& bv) {
        ++st.bv_tests;
        return detail::bv_shape_near(bv, frame.bounds, frame.pad(bv));
      },
      [&](std::int32_t k) {
        ++st.primitive_tests;
        hit = tests.intersect(mesh.triangle(k), limit);
        return !hit;
      });
  if (stats) *stats = st;
  if (limit_reached) *limit_reached = limit;
  return hit;
}

/// Separation distance between the mesh's surface and the shape, the closest points of each and
/// the closest triangle; 0 (intersecting) as soon as a triangle touching the shape is found.
template <class BV, class Shape, class S = typename BvTraits<BV>::Scalar>
MeshConvexDistance<S> mesh_convex_distance(const MeshBvh<BV>& mesh, const RigidTransform<S>& mesh_pose, const Shape& shape,
                                           const RigidTransform<S>& shape_pose, const MeshConvexOptions<S>& options = {}) {
  detail::validate_mesh_convex(mesh_pose, shape, shape_pose, options, "mesh_convex_distance");
  const detail::MeshConvexFrame<S, Shape> frame(mesh, mesh_pose, shape, shape_pose, options.convex);
  const detail::TriangleConvexTests<S, Shape> tests(shape, frame.pose, options.convex);
  MeshConvexDistance<S> out;
  out.distance = std::numeric_limits<S>::infinity();
  ConvexDistance<S> best;
  traverse_nearest(
      mesh.tree(),
      [&](const BV& bv) -> std::optional<S> {
        ++out.stats.bv_tests;
        return std::max(detail::bv_shape_gap(bv, frame.bounds) - frame.pad(bv), S(0));
      },
      [&]() { return out.distance; },
      [&](std::int32_t k) {
        ++out.stats.primitive_tests;
        const ConvexDistance<S> d = tests.distance(mesh.triangle(k));
        out.limit_reached = out.limit_reached || d.limit_reached;
        if (d.intersecting || d.distance < out.distance || out.triangle < 0) {
          best = d;
          out.distance = d.intersecting ? S(0) : d.distance;
          out.triangle = mesh.triangle_id(k);
          out.intersecting = d.intersecting;
        }
        return !d.intersecting;
      });
  out.point_mesh = mesh_pose.apply(best.point_a);
  out.point_shape = mesh_pose.apply(best.point_b);
  return out;
}

/// Every triangle of the mesh that touches or overlaps the shape, with its penetration (depth,
/// normal from the triangle towards the shape, contact point; see the file comment), by increasing
/// triangle id, up to options.max_contacts.
template <class BV, class Shape, class S = typename BvTraits<BV>::Scalar>
MeshConvexContacts<S> mesh_convex_contacts(const MeshBvh<BV>& mesh, const RigidTransform<S>& mesh_pose, const Shape& shape,
                                           const RigidTransform<S>& shape_pose, const MeshConvexOptions<S>& options = {}) {
  detail::validate_mesh_convex(mesh_pose, shape, shape_pose, options, "mesh_convex_contacts");
  const detail::MeshConvexFrame<S, Shape> frame(mesh, mesh_pose, shape, shape_pose, options.convex);
  const detail::TriangleConvexTests<S, Shape> tests(shape, frame.pose, options.convex, options.fast_contacts);
  MeshConvexContacts<S> out;
  traverse(
      mesh.tree(),
      [&](const BV& bv) {
        ++out.stats.bv_tests;
        return detail::bv_shape_near(bv, frame.bounds, frame.pad(bv));
      },
      [&](std::int32_t k) {
        ++out.stats.primitive_tests;
        ConvexContact<S> c = tests.penetration(mesh.triangle(k));
        out.limit_reached = out.limit_reached || c.limit_reached;
        if (!c.intersecting) return true;
        c.normal = mesh_pose.rotate(c.normal);
        c.point = mesh_pose.apply(c.point);
        out.contacts.push_back({mesh.triangle_id(k), c});
        if (out.contacts.size() >= options.max_contacts) {
          out.truncated = true;
          return false;
        }
        return true;
      });
  std::sort(out.contacts.begin(), out.contacts.end(), [](const MeshConvexContact<S>& x, const MeshConvexContact<S>& y) { return x.triangle < y.triangle; });
  out.colliding = !out.contacts.empty();
  return out;
}

}  // namespace impact
