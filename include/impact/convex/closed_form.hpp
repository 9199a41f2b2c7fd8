// SPDX-License-Identifier: MIT
/// \file
/// Closed-form queries for the pairs that have one: sphere–sphere, sphere–capsule, capsule–capsule
/// (point and segment distances), sphere–box (closest point of the box), sphere–cylinder (closest
/// point of the cylinder by a radial and an axial clamp), box–box (separating axes: boolean and
/// penetration). Eigen only; convex/query.hpp picks them before any iterative solver. Also the
/// one-plane separation test along a given line (separated_along, centre_line_separates) that the
/// iterative pairs try first.
///
/// Numerical contract: APPROXIMATE, but without iteration: each answer is a few dozen floating
/// point operations from the inputs, so distances, depths and normals carry only rounding error
/// (a few ulps of the shapes' size). Touching counts as intersecting. The box–box separating-axis
/// test skips edge–edge axes of nearly parallel edges (|e_a x e_b| < 1e-6 for unit edges), whose
/// separation the face axes then decide within 1e-6 of the boxes' size (boolean: conservative, a
/// pair that close may be reported intersecting).
#pragma once

#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace impact {

/// A penetration (contact) between two convex shapes, in world coordinates.
template <class S>
struct ConvexContact {
  bool intersecting = false;          ///< the shapes touch or overlap; the fields below are set only then
  S depth = S(0);                     ///< >= 0: translating b by depth * normal makes them touch
  Vec3<S> normal = Vec3<S>::UnitZ();  ///< unit, from a towards b
  Vec3<S> point = Vec3<S>::Zero();    ///< midway between the deepest points of a and b
  int iterations = 0;                 ///< support calls of the iterative solver used (0: closed form)
  /// The solver stopped before its tolerance: an iteration bound, or (penetration) rounding or a
  /// degenerate polytope left the bracket [depth - depth_gap, depth] wider than it (query.hpp).
  /// `intersecting` is then not decided (either value may be wrong); the bracket still holds the
  /// true depth, with depth - depth_gap > 0 only when the intersection was proven. The normal may
  /// be EPA's, unrefined, when the bound cut a refinement short (ConvexQueryOptions::max_iterations).
  bool limit_reached = false;
  /// Iterative solvers (EPA, MPR): depth minus a certified lower bound of the true depth (the
  /// distance from the origin to the boundary of the solver's inner polytope of the Minkowski
  /// difference). The true depth lies in [depth - depth_gap, depth]. 0 for closed forms.
  S depth_gap = S(0);
  /// The depth is EPA's refined by Newton's method (convex/epa.hpp): f(normal) at a verified local
  /// minimum of the overlap f inside EPA's certified bracket [depth - depth_gap, depth] (the
  /// bracket stays the coarse EPA one; the refined depth is typically within 1e-9 of the size).
  bool refined = false;
  /// The deepest point of a inside b (on a's surface): point + depth / 2 * normal.
  Vec3<S> point_a() const { return point + depth / S(2) * normal; }
  /// The deepest point of b inside a (on b's surface): point - depth / 2 * normal.
  Vec3<S> point_b() const { return point - depth / S(2) * normal; }
};

namespace detail {

/// Whether the overlap of two shapes along a unit direction, h_a(m) + h_b(-m), proves them apart:
/// below -16 eps `scale` (`scale` the larger shape's size; touching, and touching within rounding,
/// do not separate; false for NaN).
template <class S> bool overlap_separates(S overlap, S scale) {
  return overlap < -std::numeric_limits<S>::epsilon() * S(16) * scale;
}

/// Whether a plane normal to `line` separates two convex sets given by their support functions
/// sa, sb (both in one frame): the overlap along m = line / |line|, h_a(m) + h_b(-m), below
/// -16 eps `scale` (`scale` the larger shape's size; touching, and touching within rounding, do not
/// separate). One support call each; true is a proof, false says nothing (also for a zero or NaN
/// line). The early out of the iterative pairs along the line between the centres.
template <class S, class SupportA, class SupportB>
bool separated_along(const SupportA& sa, const SupportB& sb, const Vec3<S>& line, S scale) {
  const S len = line.norm();
  if (!(len > S(0))) return false;
  const Vec3<S> m = line / len;
  return overlap_separates(m.dot(sa(m)) - m.dot(sb(Vec3<S>(-m))), scale);
}

/// Whether a plane normal to the line between the interior points of shapes a (at pa) and b (at pb)
/// separates them (overlap_separates at the larger shape_size()): one support call each, each taken
/// in its shape's frame with the positions relative to a's (the values stay of the shapes' size far
/// from the origin), without the pair frame's matrix product. True is a proof, false says nothing.
/// The first test of the general boolean (cylinders, cones, boxes, hulls) and of hull-hull
/// penetration.
template <class S, class A, class B>
bool centre_line_separates(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb) {
  // a shape's interior point turned into the world's axes (boxes' and cylinders' are their origin)
  const auto turned_interior = [](const auto& shape, const RigidTransform<S>& pose) -> Vec3<S> {
    using T = std::decay_t<decltype(shape)>;
    if constexpr (std::is_same_v<T, Box<S>> || std::is_same_v<T, Cylinder<S>>) {
      (void)shape;
      (void)pose;
      return Vec3<S>::Zero();
    } else {
      return pose.R * interior_point(shape);
    }
  };
  const Vec3<S> d = pb.t - pa.t;
  const Vec3<S> line = d + turned_interior(b, pb) - turned_interior(a, pa);
  const S len = line.norm();
  if (!(len > S(0))) return false;
  const Vec3<S> m = line / len;
  const Vec3<S> ma = pa.R.transpose() * m, mb = -(pb.R.transpose() * m);
  return overlap_separates(ma.dot(support(a, ma)) + mb.dot(support(b, mb)) - m.dot(d), std::max(shape_size(a), shape_size(b)));
}

/// Two balls (centres ca, cb; radii ra, rb): the base of every round closed form. `fallback` is the
/// normal used when the centres coincide.
template <class S>
inline ConvexContact<S> balls_contact(const Vec3<S>& ca, S ra, const Vec3<S>& cb, S rb, const Vec3<S>& fallback) {
  ConvexContact<S> c;
  const Vec3<S> d = cb - ca;
  const S r = ra + rb;
  const S d2 = d.squaredNorm();
  if (d2 > r * r) return c;
  c.intersecting = true;
  const S dist = std::sqrt(d2);
  c.normal = dist > S(0) ? Vec3<S>(d / dist) : fallback;
  c.depth = r - dist;
  // deepest points: ca + ra n (of a) and cb - rb n (of b)
  c.point = (ca + ra * c.normal + cb - rb * c.normal) / S(2);
  return c;
}

template <class S>
inline ConvexDistance<S> balls_distance(const Vec3<S>& ca, S ra, const Vec3<S>& cb, S rb, const Vec3<S>& fallback) {
  ConvexDistance<S> out;
  const Vec3<S> d = cb - ca;
  const S dist = d.norm();
  out.distance = std::max(dist - ra - rb, S(0));
  out.intersecting = dist <= ra + rb;
  if (dist > S(0)) {  // one division: the witnesses along d scaled by the radii over |d|
    const S inv = S(1) / dist;
    out.point_a = ca + (ra * inv) * d;
    out.point_b = cb - (rb * inv) * d;
  } else {
    out.point_a = ca + ra * fallback;
    out.point_b = cb - rb * fallback;
  }
  return out;
}

/// The core segment of a capsule in world coordinates.
template <class S>
inline Segment<S> capsule_segment(const Capsule<S>& c, const RigidTransform<S>& p) {
  const Vec3<S> axis = p.R.col(2) * c.half_length;
  return {p.t - axis, p.t + axis};
}

/// The closest pair of points of the cores of two round shapes (sphere: its centre, capsule: its
/// segment), world coordinates: `a` on a's core, `b` on b's.
template <class S>
struct CorePoints {
  Vec3<S> a, b;
};
template <class S>
inline CorePoints<S> core_points(const Sphere<S>& a, const RigidTransform<S>& pa, const Sphere<S>& b,
                                 const RigidTransform<S>& pb) {
  return {pa.apply(a.center), pb.apply(b.center)};
}
template <class S>
inline CorePoints<S> core_points(const Sphere<S>& a, const RigidTransform<S>& pa, const Capsule<S>& b,
                                 const RigidTransform<S>& pb) {
  const Vec3<S> qa = pa.apply(a.center);
  return {qa, closest_point_on_segment(qa, capsule_segment(b, pb)).point};
}
template <class S>
inline CorePoints<S> core_points(const Capsule<S>& a, const RigidTransform<S>& pa, const Sphere<S>& b,
                                 const RigidTransform<S>& pb) {
  const Vec3<S> qb = pb.apply(b.center);
  return {closest_point_on_segment(qb, capsule_segment(a, pa)).point, qb};
}
template <class S>
inline CorePoints<S> core_points(const Capsule<S>& a, const RigidTransform<S>& pa, const Capsule<S>& b,
                                 const RigidTransform<S>& pb) {
  const auto cp = closest_points_segment_segment(capsule_segment(a, pa), capsule_segment(b, pb));
  return {cp.point_a, cp.point_b};
}

/// The world axis of a round shape's core: a capsule's when its segment has a length, else zero.
template <class S>
inline Vec3<S> core_axis(const Sphere<S>&, const RigidTransform<S>&) {
  return Vec3<S>::Zero();
}
template <class S>
inline Vec3<S> core_axis(const Capsule<S>& c, const RigidTransform<S>& p) {
  return c.half_length > S(0) ? Vec3<S>(p.R.col(2)) : Vec3<S>::Zero();
}

/// The normal used when two cores meet (the core points coincide and give no direction). Moving b
/// by ra + rb along it must make the shapes touch, so it is perpendicular to every segment core:
/// the cross product of two axes that are not parallel; else, with one axis (or two parallel
/// ones), the line of the poses' origins without its component along the axis, or any direction
/// perpendicular to the axis when that line runs along it; else (two points) the line of the
/// origins, or +z. (Any other direction needs a longer move along a segment: fuzzing found a
/// sphere centred on a capsule's axis given the capsule's axis as its normal.)
template <class S, class A, class B>
inline Vec3<S> core_fallback_normal(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb) {
  const Vec3<S> ua = core_axis(a, pa), ub = core_axis(b, pb);
  const bool has_a = ua.squaredNorm() > S(0), has_b = ub.squaredNorm() > S(0);
  const Vec3<S> d = pb.t - pa.t;
  if (has_a && has_b) {
    Vec3<S> n = ua.cross(ub);
    if (n.squaredNorm() > S(1e-12)) {
      n.normalize();
      return n.dot(d) >= S(0) ? n : Vec3<S>(-n);
    }
  }
  if (has_a || has_b) {
    const Vec3<S> axis = (has_a ? ua : ub).normalized();
    Vec3<S> across = d - axis.dot(d) * axis;
    across -= axis.dot(across) * axis;  // twice: perpendicular to rounding of its own length
    if (across.squaredNorm() > S(1e-12) * d.squaredNorm()) return across.normalized();
    int least = 0;  // else the axis crossed with the coordinate axis it is least along
    axis.cwiseAbs().minCoeff(&least);
    return axis.cross(Vec3<S>::Unit(least)).normalized();
  }
  if (d.squaredNorm() > S(0)) return d.normalized();
  return Vec3<S>::UnitZ();
}

template <class S>
inline S round_radius(const Sphere<S>& s) {
  return s.radius;
}
template <class S>
inline S round_radius(const Capsule<S>& s) {
  return s.radius;
}

/// Length of a round shape's core: a capsule's segment, 0 for a sphere.
template <class S>
inline S core_length(const Sphere<S>&) {
  return S(0);
}
template <class S>
inline S core_length(const Capsule<S>& c) {
  return S(2) * c.half_length;
}

/// Penetration of two round shapes (spheres, capsules) from the closest points of their cores.
/// Cores closer than the rounding of those points (64 epsilons of the coordinates and the
/// segments' lengths) meet: the line between the points is noise there, and the normal is
/// core_fallback_normal's (perpendicular to the segments), with the depth ra + rb.
template <class S, class A, class B>
inline ConvexContact<S> round_pair_contact(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb) {
  const CorePoints<S> q = core_points(a, pa, b, pb);
  const S reach = std::max({q.a.cwiseAbs().maxCoeff(), q.b.cwiseAbs().maxCoeff(), core_length(a), core_length(b)});
  const S noise = S(64) * std::numeric_limits<S>::epsilon() * reach;
  const bool meet = (q.b - q.a).squaredNorm() <= noise * noise;
  return balls_contact(q.a, round_radius(a), meet ? q.a : q.b, round_radius(b), core_fallback_normal(a, pa, b, pb));
}

/// Does the sphere (world centre c, radius r) touch or overlap the box? (The boolean of
/// sphere_box_contact, without its contact.)
template <class S>
inline bool sphere_box_overlap(const Vec3<S>& c, S r, const Box<S>& box, const RigidTransform<S>& pb) {
  const Vec3<S> lc = pb.R.transpose() * (c - pb.t);
  return (lc - lc.cwiseMax(-box.half).cwiseMin(box.half)).squaredNorm() <= r * r;
}

/// Sphere (world centre c, radius r) against a box: closest point of the box, or (centre inside)
/// the nearest face. Normal from the sphere towards the box.
template <class S>
inline ConvexContact<S> sphere_box_contact(const Vec3<S>& c, S r, const Box<S>& box, const RigidTransform<S>& pb) {
  ConvexContact<S> out;
  const Vec3<S> lc = pb.R.transpose() * (c - pb.t);
  const Vec3<S> q = lc.cwiseMax(-box.half).cwiseMin(box.half);
  const Vec3<S> d = lc - q;
  const S d2 = d.squaredNorm();
  if (d2 > r * r) return out;
  out.intersecting = true;
  if (d2 > S(0)) {
    const S dist = std::sqrt(d2);
    out.normal = pb.rotate(Vec3<S>(-d / dist));
    out.depth = r - dist;
    // deepest points: c + r n (sphere), the box's closest point q (box)
    out.point = (c + r * out.normal + pb.apply(q)) / S(2);
  } else {
    const Vec3<S> gap = box.half - lc.cwiseAbs();
    int k;
    gap.minCoeff(&k);
    Vec3<S> n = Vec3<S>::Zero();
    n[k] = lc[k] >= S(0) ? S(-1) : S(1);
    out.normal = pb.rotate(n);
    out.depth = r + gap[k];
    Vec3<S> face = lc;
    face[k] = lc[k] >= S(0) ? box.half[k] : -box.half[k];
    out.point = (c + r * out.normal + pb.apply(face)) / S(2);
  }
  return out;
}

template <class S>
inline ConvexDistance<S> sphere_box_distance(const Vec3<S>& c, S r, const Box<S>& box, const RigidTransform<S>& pb) {
  ConvexDistance<S> out;
  const Vec3<S> lc = pb.R.transpose() * (c - pb.t);
  const Vec3<S> q = lc.cwiseMax(-box.half).cwiseMin(box.half);
  const S dist = (lc - q).norm();
  out.intersecting = dist <= r;
  out.distance = std::max(dist - r, S(0));
  out.point_b = pb.apply(q);
  out.point_a = dist > S(0) ? Vec3<S>(c + (out.point_b - c) * (r / dist)) : c;
  return out;
}

/// A point q against a solid cylinder (radius R, half length h), in the cylinder's frame. The
/// cylinder is a disc times an interval, so the squared distance splits into a radial part
/// dr = max(rho - R, 0) (rho = |q_xy|) and an axial part dz = max(|z| - h, 0): the closest point
/// clamps each on its own, and the direction from it to q is (dr radial + dz up) / distance, taken
/// from dr and dz (differences of the inputs) rather than from q minus the closest point, so it
/// stays accurate for q within rounding of the surface.
template <class S>
struct CylinderPoint {
  S rho, side, cap;  ///< |q_xy|; R - rho and h - |z| (both >= 0: inside or on the boundary)
  Vec3<S> radial;    ///< q_xy / rho, or +x on the axis
  Vec3<S> up;        ///< +z or -z, the side of z
  S distance;        ///< from q to the cylinder (0 inside)
  Vec3<S> outward;   ///< outside: unit, from the closest point towards q
  Vec3<S> closest;   ///< the closest point of the cylinder (q itself inside)
  /// Inside or on the boundary: how far q is from leaving, and the way out (through the nearer of
  /// the side and the caps, the caps on a tie: a centre on the rim leaves through the cap).
  S exit_gap() const { return std::min(side, cap); }
  Vec3<S> exit_direction() const { return cap <= side ? up : radial; }
};
template <class S>
inline CylinderPoint<S> cylinder_point(const Cylinder<S>& cyl, const Vec3<S>& q) {
  CylinderPoint<S> c;
  c.rho = std::sqrt(q.x() * q.x() + q.y() * q.y());
  c.side = cyl.radius - c.rho;
  c.cap = cyl.half_length - std::abs(q.z());
  c.radial = c.rho > S(0) ? Vec3<S>(q.x() / c.rho, q.y() / c.rho, S(0)) : Vec3<S>(Vec3<S>::UnitX());
  c.up = Vec3<S>(S(0), S(0), q.z() >= S(0) ? S(1) : S(-1));
  const S dr = std::max(-c.side, S(0)), dz = std::max(-c.cap, S(0));
  c.distance = std::sqrt(dr * dr + dz * dz);
  c.outward = c.distance > S(0) ? Vec3<S>((dr / c.distance) * c.radial + (dz / c.distance) * c.up) : Vec3<S>(c.radial);
  c.closest = q - c.distance * c.outward;
  return c;
}

/// Does the sphere (world centre c, radius r) touch or overlap the cylinder? (The boolean of
/// sphere_cylinder_contact, without a square root unless the centre is beyond the side.)
template <class S>
inline bool sphere_cylinder_overlap(const Vec3<S>& c, S r, const Cylinder<S>& cyl, const RigidTransform<S>& pb) {
  const Vec3<S> q = pb.R.transpose() * (c - pb.t);
  const S rho2 = q.x() * q.x() + q.y() * q.y();
  const S dz = std::max(std::abs(q.z()) - cyl.half_length, S(0));
  const S dr = rho2 > cyl.radius * cyl.radius ? std::sqrt(rho2) - cyl.radius : S(0);
  return dr * dr + dz * dz <= r * r;
}

/// Sphere (world centre c, radius r) against a solid B given by the record `p` of the centre in
/// B's frame (CylinderPoint, ConePoint: distance, outward, closest, and exit_gap() /
/// exit_direction() inside). Centre outside: normal from the centre towards its closest point of
/// B, depth r - distance. Centre inside or on the boundary: it leaves the way the record names,
/// depth r + that gap. Normal from the sphere towards B; the point midway between the deepest
/// points.
template <class S, class Point>
inline ConvexContact<S> sphere_solid_contact(const Vec3<S>& c, S r, const Point& p, const RigidTransform<S>& pb) {
  ConvexContact<S> out;
  if (p.distance > r) return out;
  out.intersecting = true;
  if (p.distance > S(0)) {  // outside
    out.normal = pb.rotate(Vec3<S>(-p.outward));
    out.depth = r - p.distance;
    out.point = (c + r * out.normal + pb.apply(p.closest)) / S(2);
    return out;
  }
  const S gap = p.exit_gap();
  const Vec3<S> exit_dir = pb.rotate(p.exit_direction());
  out.normal = -exit_dir;  // b moves against the exit direction
  out.depth = r + gap;
  // deepest points: c + r n (of the sphere), c + gap * exit (the face the centre leaves by)
  out.point = c + (gap - r) / S(2) * exit_dir;
  return out;
}

/// The distance and witness points of the sphere and the solid of sphere_solid_contact.
template <class S, class Point>
inline ConvexDistance<S> sphere_solid_distance(const Vec3<S>& c, S r, const Point& p, const RigidTransform<S>& pb) {
  ConvexDistance<S> out;
  out.intersecting = p.distance <= r;
  out.distance = std::max(p.distance - r, S(0));
  out.point_b = pb.apply(p.closest);
  out.point_a = c - r * pb.rotate(p.outward);
  return out;
}

/// Sphere (world centre c, radius r) against a cylinder (cylinder_point), as
/// sphere_solid_contact: a centre inside leaves through the nearer of the side and the
/// caps (the caps on a tie, so a centre on the rim goes through the cap; a centre on the axis
/// nearer the side goes along +x of the cylinder's frame).
template <class S>
inline ConvexContact<S> sphere_cylinder_contact(const Vec3<S>& c, S r, const Cylinder<S>& cyl, const RigidTransform<S>& pb) {
  return sphere_solid_contact(c, r, cylinder_point(cyl, Vec3<S>(pb.R.transpose() * (c - pb.t))), pb);
}

template <class S>
inline ConvexDistance<S> sphere_cylinder_distance(const Vec3<S>& c, S r, const Cylinder<S>& cyl, const RigidTransform<S>& pb) {
  return sphere_solid_distance(c, r, cylinder_point(cyl, Vec3<S>(pb.R.transpose() * (c - pb.t))), pb);
}

/// A point q (in a cone's frame) against the solid cone, worked in q's meridian half-plane (rho =
/// q's distance to the axis, z), where the cone is the triangle apex A = (0, h), rim B = (R, -h),
/// base centre (0, -h). Inside: the nearer of the side line and the base plane. Outside: the
/// region of the nearest feature (the side's interior, the base's interior, the apex, the rim;
/// the axis edge of the triangle is not the cone's boundary and never nearest from rho >= 0). On
/// a face the outward direction is the face's normal, not the difference of nearly equal points
/// (which rounding turns into any direction for a point within rounding of the face: fuzzing-like
/// tests found normals along which the overlap was the whole cone's length); at the apex and the
/// rim it is the line from the vertex, which the region test keeps in the vertex's normal cone.
template <class S>
struct ConePoint {
  S distance = S(0);  ///< from q to the cone (0 inside or on it)
  S side = S(0);      ///< inside: distance to the side (the cone's lateral surface)
  S base = S(0);      ///< inside: distance to the base plane
  Vec3<S> radial;     ///< unit, from the axis towards q (+x of the frame when q is on the axis)
  Vec3<S> outward;    ///< unit: outside, from the closest point towards q; inside, the exit direction
  Vec3<S> closest;    ///< the closest point of the cone (q itself inside)
  /// Inside or on the boundary: how far q is from leaving, and the way out (`outward`).
  S exit_gap() const { return std::min(side, base); }
  Vec3<S> exit_direction() const { return outward; }
};

template <class S>
inline ConePoint<S> cone_point(const Cone<S>& cone, const Vec3<S>& q) {
  ConePoint<S> c;
  const S R = cone.radius, h = cone.half_length;
  const S rho = std::sqrt(q.x() * q.x() + q.y() * q.y());
  c.radial = rho > S(0) ? Vec3<S>(q.x() / rho, q.y() / rho, S(0)) : Vec3<S>(Vec3<S>::UnitX());
  const Vec3<S> down(S(0), S(0), S(-1));
  // the side line through A and B: unit direction d = (R, -2h) / len, outward normal m = (2h, R) / len
  const S len = std::sqrt(R * R + S(4) * h * h);
  const S mr = S(2) * h / len, mz = R / len;
  const Vec3<S> side_out = mr * c.radial + Vec3<S>(S(0), S(0), mz);
  const S dz = q.z() - h;                         // q - A in meridian coordinates: (rho, dz)
  const S s = mr * rho + mz * dz;                 // signed distance to the side line (> 0 outside)
  const S b = -(q.z() + h);                       // signed distance to the base plane (> 0 below)
  const S t = (R * rho - S(2) * h * dz) / len;    // q's projection on the side, from A towards B
  // Nearest to a vertex (vr, vz) of the meridian triangle, e = q - vertex. The direction is e
  // written as alpha m + beta g (m the side's normal, g = (0, gz) the other face's normal at the
  // vertex: the base's (0, -1) at the rim, the axis (0, 1) at the apex) with both coefficients
  // clamped at 0: the vertex's normal cone. Rounding can put e, when it is as small as rounding,
  // outside that cone, and along such a direction the cone's support is another vertex.
  const auto vertex = [&](S er, S ez, S vr, S vz, S gz) {
    c.distance = std::sqrt(er * er + ez * ez);
    const S alpha = std::max(er / mr, S(0));
    const S beta = std::max((ez - alpha * mz) * gz, S(0));
    const S nr = alpha * mr, nz = alpha * mz + beta * gz;
    const S n = std::sqrt(nr * nr + nz * nz);
    c.outward = n > S(0) ? Vec3<S>((nr / n) * c.radial + Vec3<S>(S(0), S(0), nz / n)) : down;
    c.closest = vr * c.radial + Vec3<S>(S(0), S(0), vz);
  };
  if (s <= S(0) && b <= S(0)) {  // inside or on the boundary: leave by the nearer face (the base on a tie)
    c.side = -s;
    c.base = -b;
    c.outward = c.side < c.base ? side_out : down;
    c.closest = q;
  } else if (b > S(0) && rho <= R) {  // below the base
    c.distance = b;
    c.outward = down;
    c.closest = Vec3<S>(q.x(), q.y(), -h);
  } else if (s > S(0) && t <= S(0)) {  // beyond the apex
    vertex(rho, dz, S(0), h, S(1));
  } else if (s > S(0) && t < len) {  // beside the side
    c.distance = s;
    c.outward = side_out;
    c.closest = q - s * side_out;
  } else {  // beyond the rim
    vertex(rho - R, q.z() + h, R, -h, S(-1));
  }
  return c;
}

/// Does the sphere (world centre c, radius r) touch or overlap the cone?
template <class S>
inline bool sphere_cone_overlap(const Vec3<S>& c, S r, const Cone<S>& cone, const RigidTransform<S>& pb) {
  return cone_point(cone, Vec3<S>(pb.R.transpose() * (c - pb.t))).distance <= r;
}

/// Sphere (world centre c, radius r) against a cone (cone_point), as
/// sphere_solid_contact: a centre inside leaves through the nearer of the side and the
/// base (the base on a tie; a centre on the axis leaves the side along +x of the cone's frame:
/// every direction round the axis is as near).
template <class S>
inline ConvexContact<S> sphere_cone_contact(const Vec3<S>& c, S r, const Cone<S>& cone, const RigidTransform<S>& pb) {
  return sphere_solid_contact(c, r, cone_point(cone, Vec3<S>(pb.R.transpose() * (c - pb.t))), pb);
}

template <class S>
inline ConvexDistance<S> sphere_cone_distance(const Vec3<S>& c, S r, const Cone<S>& cone, const RigidTransform<S>& pb) {
  return sphere_solid_distance(c, r, cone_point(cone, Vec3<S>(pb.R.transpose() * (c - pb.t))), pb);
}

/// Box–box by the 15 separating axes: not intersecting when one separates them, else the axis of
/// least overlap gives the normal and depth (exact for polytopes: the least overlap over these axes
/// is the penetration depth); the contact point is the midpoint of the deepest features' centres.
template <class S>
ConvexContact<S> box_box_contact(const Box<S>& a, const RigidTransform<S>& pa, const Box<S>& b, const RigidTransform<S>& pb,
                                 bool want_contact) {
  ConvexContact<S> out;
  const Vec3<S> t = pb.t - pa.t;
  const Mat3<S> C = pa.R.transpose() * pb.R;  // b's axes in a's frame
  const Mat3<S> absC = C.cwiseAbs();
  const Vec3<S> ta = pa.R.transpose() * t;
  const Vec3<S>& ha = a.half;
  const Vec3<S>& hb = b.half;
  S best = std::numeric_limits<S>::infinity();
  Vec3<S> best_axis = Vec3<S>::UnitZ();  // in a's frame, unit, oriented a -> b
  const auto consider = [&](const Vec3<S>& axis, S ra, S rb, S dist) {
    const S overlap = ra + rb - std::abs(dist);
    if (overlap < best) {
      best = overlap;
      best_axis = dist >= S(0) ? axis : Vec3<S>(-axis);
    }
    return overlap >= S(0);
  };
  for (int i = 0; i < 3; ++i)
    if (!consider(Vec3<S>::Unit(i), ha[i], absC.row(i).dot(hb), ta[i])) return out;
  for (int j = 0; j < 3; ++j)
    if (!consider(Vec3<S>(C.col(j)), absC.col(j).dot(ha), hb[j], C.col(j).dot(ta))) return out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Vec3<S> axis = Vec3<S>::Unit(i).cross(Vec3<S>(C.col(j)));
      const S len = axis.norm();
      if (len < S(1e-6)) continue;
      axis /= len;
      const S ra = axis.cwiseAbs().dot(ha);
      const S rb = (C.transpose() * axis).cwiseAbs().dot(hb);
      if (!consider(axis, ra, rb, axis.dot(ta))) return out;
    }
  out.intersecting = true;
  if (!want_contact) return out;
  out.depth = std::max(best, S(0));
  out.normal = pa.rotate(best_axis);
  // Deepest points along the normal: a's support towards b, b's support towards a, each taken as
  // the centre of the supporting feature (vertex, edge or face) so that face contacts are centred.
  const auto feature_centre = [](const Vec3<S>& h, const Vec3<S>& dir_local) {
    Vec3<S> p;
    for (int k = 0; k < 3; ++k) p[k] = std::abs(dir_local[k]) < S(1e-9) ? S(0) : (dir_local[k] > S(0) ? h[k] : -h[k]);
    return p;
  };
  const Vec3<S> sa = pa.apply(feature_centre(ha, best_axis));
  const Vec3<S> sb = pb.apply(feature_centre(hb, Vec3<S>(-(C.transpose() * best_axis))));
  // Project both on the contact plane through their midpoint along the normal.
  out.point = (sa + sb) / S(2);
  return out;
}

}  // namespace detail
}  // namespace impact
