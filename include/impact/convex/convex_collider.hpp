// SPDX-License-Identifier: MIT
/// \file
/// ConvexCollider<S, Shape>: a capsule, cylinder, cone or convex hull of the convex layer as a
/// particle collider (response/collider.hpp, particle_step.hpp), a solid that particles stay
/// outside of, with the contract of the core's colliders: first hit of a moving point or ball
/// (backtracking), penetration with the closest surface point, normal and target (projection), a
/// clearance for the free-ball cache, restitution and friction from its Material, its own
/// Strategy, and a rigid motion. It joins a ColliderSet as one of its trailing collider types:
///
///   impact::ColliderSet<double, impact::Aabb<double>, impact::ConvexCollider<double, impact::Capsule<double>>,
///                       impact::ConvexCollider<double, impact::ConvexHull<double>>> set;
///   set.extra_of<impact::ConvexCollider<double, impact::Capsule<double>>>().push_back({impact::Capsule<double>(0.2, 0.5)});
///   impact::step_particles(particles, set, dt, options);
///
/// The core's ColliderSet loops over its trailing types at compile time (no virtual call), and
/// this header needs Eigen only: the convex layer's shapes without libccd.
///
/// How (local frame, per shape; every answer closed form or a loop over the hull's faces):
///   point query   the shape's closest boundary point to q, the outward unit normal there and the
///                 signed distance (negative inside): capsule by the closest point of its segment;
///                 cylinder by the radial and axial clamps (inside: the nearer of side and caps);
///                 cone in its (radius, height) half plane by the closest point of its triangle
///                 (inside: the nearer of base and lateral line); hull by its triangles' closest
///                 points (outside) and its faces' planes (inside)
///   first hit     the centre's path o + t d against the shape grown by the particle's radius r:
///                 f(t) = distance(o + t d) - r is convex in t (the distance to a convex set along a
///                 line), so Newton's step from the left, t += f / (-f'), f' = d . normal, never
///                 passes the first root; it stops when f <= the rounding tolerance (a hit), when
///                 the path turns away (f' >= 0 with f > 0: convexity, no later root: a miss) or
///                 past t_max; after 64 steps (kinks of a hull's distance, grazing paths) it reports
///                 the hit where it stands: early, never late, so a particle is never let in
///   projection    a centre within r of the shape (or inside) goes to point + (r + offset) normal
///
/// Numerical contract: CONSERVATIVE for backtracking (a hit is reported at the first time the
/// centre comes within the tolerance 16 ulps of (|o| + |d| t_max + the shape's scale) of the grown
/// surface, or earlier, never after it); closest points and normals are exact up to rounding.
/// Shapes with a normal everywhere except on edges and apexes, where the normal is that of the
/// nearest face or the direction from the closest point (the subgradient the distance takes).
///
/// Validation: ColliderSet::validate (called by the step) checks the common fields as for every
/// collider and the shape (validate_shape: finite, positive radii and lengths; a built hull).
/// Thread safety: const queries only read the collider.
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/core/error.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/response/collider.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace impact {

/// The closest boundary point of a shape to a point, in the shape's frame.
template <class S>
struct ShapePointQuery {
  S distance = S(0);                  ///< signed: > 0 outside, < 0 inside
  Vec3<S> point = Vec3<S>::Zero();    ///< closest point of the boundary
  Vec3<S> normal = Vec3<S>::UnitZ();  ///< outward unit normal (the direction from point to an outside q)
};

namespace detail {
/// The unit vector of (x, y) in the plane, or (1, 0) for the origin (a point on the axis).
template <class S>
inline Vec3<S> radial_unit(const Vec3<S>& q, S& rho) {
  rho = std::sqrt(q.x() * q.x() + q.y() * q.y());
  return rho > S(0) ? Vec3<S>(q.x() / rho, q.y() / rho, S(0)) : Vec3<S>(Vec3<S>::UnitX());
}
/// From q and its closest point p of a solid (q outside or on it), with a fallback normal.
template <class S>
inline ShapePointQuery<S> outside_query(const Vec3<S>& q, const Vec3<S>& p, const Vec3<S>& fallback) {
  ShapePointQuery<S> r;
  const Vec3<S> v = q - p;
  const S len = v.norm();
  r.distance = len;
  r.point = p;
  r.normal = len > S(0) ? Vec3<S>(v / len) : fallback;
  return r;
}
}  // namespace detail

template <class S>
ShapePointQuery<S> point_query(const Capsule<S>& c, const Vec3<S>& q) {
  const Vec3<S> axis(S(0), S(0), std::clamp(q.z(), -c.half_length, c.half_length));
  const Vec3<S> v = q - axis;
  const S len = v.norm();
  ShapePointQuery<S> r;
  r.normal = len > S(0) ? Vec3<S>(v / len) : Vec3<S>(Vec3<S>::UnitX());
  r.distance = len - c.radius;
  r.point = axis + c.radius * r.normal;
  return r;
}

template <class S>
ShapePointQuery<S> point_query(const Cylinder<S>& c, const Vec3<S>& q) {
  S rho;
  const Vec3<S> u = detail::radial_unit(q, rho);
  const S R = c.radius, h = c.half_length;
  const S side = R - rho, cap = h - std::abs(q.z());
  const Vec3<S> up(S(0), S(0), q.z() >= S(0) ? S(1) : S(-1));
  if (side >= S(0) && cap >= S(0)) {  // inside or on the boundary: the nearer of side and caps
    ShapePointQuery<S> r;
    if (cap <= side) {
      r.distance = -cap;
      r.normal = up;
      r.point = Vec3<S>(q.x(), q.y(), up.z() * h);
    } else {
      r.distance = -side;
      r.normal = u;
      r.point = Vec3<S>(R * u.x(), R * u.y(), q.z());
    }
    return r;
  }
  const S pr = std::min(rho, R), pz = std::clamp(q.z(), -h, h);
  return detail::outside_query(q, Vec3<S>(pr * u.x(), pr * u.y(), pz), side < S(0) ? u : up);
}

template <class S>
ShapePointQuery<S> point_query(const Cone<S>& c, const Vec3<S>& q) {
  S rho;
  const Vec3<S> u = detail::radial_unit(q, rho);
  const S R = c.radius, h = c.half_length;
  // the half plane (rho, z): the triangle (0, -h), (R, -h), (0, h); lateral outward normal m
  const S ml = std::sqrt(S(4) * h * h + R * R);
  const S m_rho = S(2) * h / ml, m_z = R / ml;
  const S lateral = m_rho * rho + m_z * (q.z() - h);  // signed distance to the lateral line (> 0 outside)
  const S base = -h - q.z();                           // signed distance to the base plane (> 0 outside)
  ShapePointQuery<S> r;
  if (lateral <= S(0) && base <= S(0)) {  // inside or on the boundary
    if (base >= lateral) {
      r.distance = base;
      r.normal = -Vec3<S>::UnitZ();
      r.point = Vec3<S>(q.x(), q.y(), -h);
    } else {
      r.distance = lateral;
      r.normal = Vec3<S>(m_rho * u.x(), m_rho * u.y(), m_z);
      r.point = q - lateral * r.normal;
    }
    return r;
  }
  // outside: the closest point of the filled triangle in the half plane
  const Triangle<S> t(Vec3<S>(S(0), -h, S(0)), Vec3<S>(R, -h, S(0)), Vec3<S>(S(0), h, S(0)));
  const Vec3<S> p2 = closest_point_on_triangle(Vec3<S>(rho, q.z(), S(0)), t).point;
  const Vec3<S> fb = base > lateral ? Vec3<S>(-Vec3<S>::UnitZ()) : Vec3<S>(m_rho * u.x(), m_rho * u.y(), m_z);
  return detail::outside_query(q, Vec3<S>(p2.x() * u.x(), p2.x() * u.y(), p2.y()), fb);
}

template <class S>
ShapePointQuery<S> point_query(const ConvexHull<S>& hull, const Vec3<S>& q) {
  // the face plane q is farthest beyond (inside: the nearest face)
  S worst = -std::numeric_limits<S>::infinity();
  std::size_t face = 0;
  for (std::size_t f = 0; f < hull.faces.size(); ++f) {
    const S s = hull.faces[f].normal.dot(q) - hull.faces[f].offset;
    if (s > worst) worst = s, face = f;
  }
  const Vec3<S> fn = hull.faces[face].normal;
  if (worst <= S(0)) {
    ShapePointQuery<S> r;
    r.distance = worst;
    r.normal = fn;
    r.point = q - worst * fn;
    return r;
  }
  Vec3<S> best = Vec3<S>::Zero();
  S best_d2 = std::numeric_limits<S>::infinity();
  for (Eigen::Index t = 0; t < hull.triangles.rows(); ++t) {
    const Triangle<S> tri(hull.vertices.row(hull.triangles(t, 0)).transpose(), hull.vertices.row(hull.triangles(t, 1)).transpose(),
                          hull.vertices.row(hull.triangles(t, 2)).transpose());
    const auto c = closest_point_on_triangle(q, tri);
    if (c.squared_distance < best_d2) best_d2 = c.squared_distance, best = c.point;
  }
  return detail::outside_query(q, best, fn);
}

/// A convex shape (Capsule, Cylinder, Cone or ConvexHull, in its own frame; the pose in `motion`
/// places it) that particles stay outside of. See the file comment.
template <class S, class Shape>
struct ConvexCollider {
  Shape shape;
  ColliderMotion<S> motion;
  Material<S> material;
  Strategy strategy = Strategy::Inherit;
  static constexpr const char* kind = "convex";

  explicit ConvexCollider(const Shape& s, const Material<S>& m = {}) : shape(s), material(m) {}

  /// The shape's extent about its frame's origin (for the step's scale-aware offsets).
  S scale() const { return shape_size(shape) + interior_point(shape).cwiseAbs().maxCoeff(); }
  /// Distance from the local point q to the shape (0 inside).
  S clearance(const Vec3<S>& q) const { return std::max(point_query(shape, q).distance, S(0)); }

  std::optional<LocalHit<S>> local_first_hit(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    return detail::first_hit_any_leg(o, d, t_max, [&](const Vec3<S>& lo, const Vec3<S>& ld, S lt) { return first_hit_in_range(lo, ld, r, lt); });
  }

  std::optional<LocalPenetration<S>> local_penetration(const Vec3<S>& q, const Vec3<S>&, S r, S offset) const {
    const ShapePointQuery<S> pq = point_query(shape, q);
    if (pq.distance >= r) return std::nullopt;
    return LocalPenetration<S>{pq.point, pq.normal, pq.point + (r + offset) * pq.normal};
  }

  /// Throws InvalidInput for an invalid shape (ColliderSet::validate calls it with the collider's name).
  /// The message naming the collider is built only on failure: a valid shape costs the checks alone.
  void validate(const char* where, const std::string& name) const {
    try {
      validate_shape(shape, where);
    } catch (const InvalidInput&) {
      validate_shape(shape, (std::string(where) + ": " + name).c_str());  // the same checks: throw again, with the name
      throw;
    }
  }

 private:
  std::optional<LocalHit<S>> first_hit_in_range(const Vec3<S>& o, const Vec3<S>& d, S r, S t_max) const {
    if (!(d.squaredNorm() > S(0))) return std::nullopt;
    const S tol = S(16) * std::numeric_limits<S>::epsilon() *
                  (o.cwiseAbs().maxCoeff() + d.cwiseAbs().maxCoeff() * t_max + scale() + r);
    S t = S(0);
    ShapePointQuery<S> pq;
    for (int it = 0; it < 64; ++it) {
      pq = point_query(shape, Vec3<S>(o + t * d));
      const S f = pq.distance - r;
      const S dn = d.dot(pq.normal);
      if (f <= tol) {
        if (it == 0 && !(dn < S(0))) return std::nullopt;  // on or inside at the start, moving out
        return LocalHit<S>{t, pq.point, pq.normal};
      }
      if (!(dn < S(0))) return std::nullopt;  // moving away: f is convex, no later root
      t += f / (-dn);
      if (t > t_max) return std::nullopt;
    }
    pq = point_query(shape, Vec3<S>(o + t * d));
    return LocalHit<S>{t, pq.point, pq.normal};  // early, never late
  }
};

}  // namespace impact
