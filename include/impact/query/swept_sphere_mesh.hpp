// SPDX-License-Identifier: MIT
/// \file
/// First hit of a sphere of radius r moving along a segment against a triangle mesh (a MeshBvh
/// under a rigid transform): the first t at which the sphere touches a triangle's face, edge or
/// vertex. Equivalently a ray against the mesh grown by r (each triangle becomes a slab capped by
/// cylinders and spheres), traversed nearest first with every BV inflated by r.
///
/// Contract. Exact up to rounding for faces (offset plane), edges (ray-cylinder) and vertices
/// (ray-sphere); the capsule around a shared edge belongs to both triangles, so seams are closed.
/// A sphere that already touches or overlaps a triangle at t = 0 hits it at t = 0 when it moves
/// towards the triangle (velocity . normal < 0, normal from the triangle to the centre), and does
/// not hit it when it moves away: starting in contact neither sticks nor tunnels.
#pragma once

#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"

namespace impact {

/// A swept-sphere hit, in the world frame.
template <class S> struct SweptSphereHit {
  S t = S(0);                        ///< centre at the hit: origin + t * direction
  std::int32_t triangle = -1;        ///< row of the mesh's F
  std::int32_t leaf_index = -1;      ///< leaf position
  Vec3<S> point = Vec3<S>::Zero();   ///< contact point on the triangle
  Vec3<S> normal = Vec3<S>::Zero();  ///< unit, from the contact point towards the centre
  TriangleFeature feature = TriangleFeature::Face;
};

namespace detail {

/// Smallest root in [0, t_max] of a t^2 + 2 b t + c = 0 entering the region c(t) <= 0, for a > 0.
/// Tangential grazing (a double root, up to rounding) is not a hit: the motion does not approach.
template <class S> inline std::optional<S> entering_root(S a, S b, S c, S t_max) {
  if (!(a > S(0))) return std::nullopt;
  const S disc = b * b - a * c;
  if (!(disc > S(64) * std::numeric_limits<S>::epsilon() * (b * b + std::abs(a * c)))) return std::nullopt;
  const S t = (-b - std::sqrt(disc)) / a;
  if (t < S(0) || t > t_max) return std::nullopt;
  return t;
}

/// Swept sphere (centre o + t d, radius r > 0) against one triangle. See the file comment.
template <class S>
inline std::optional<SweptSphereHit<S>> swept_sphere_triangle(const Vec3<S>& o, const Vec3<S>& d, S r, const Triangle<S>& tri,
                                                              S t_max) {
  SweptSphereHit<S> h;
  const TrianglePoint<S> cp = closest_on_triangle(o, tri);
  const Vec3<S> diff = o - cp.point;
  const S dist2 = diff.squaredNorm();
  if (dist2 <= r * r) {
    Vec3<S> n;
    S slack = S(0);  // rounding of the closest point tilts n; sliding along the surface is no hit
    if (dist2 > S(0)) {
      const S dist = std::sqrt(dist2);
      n = diff / dist;
      slack = S(64) * std::numeric_limits<S>::epsilon() * (o.cwiseAbs().maxCoeff() + cp.point.cwiseAbs().maxCoeff()) / dist;
    } else {
      n = tri.normal();
      if (n.dot(d) > S(0)) n = -n;
    }
    if (!(d.dot(n) < -slack * d.norm())) return std::nullopt;
    h.t = S(0);
    h.point = cp.point;
    h.normal = n;
    h.feature = cp.feature;
    return h;
  }
  S best = t_max;
  bool found = false;
  // Face: the plane moved by r towards the origin's side.
  const Vec3<S> n = tri.normal();
  if (n.squaredNorm() > S(0)) {
    const S sd = (o - tri.a).dot(n);
    const Vec3<S> ns = sd >= S(0) ? n : Vec3<S>(-n);
    const S dn = d.dot(ns);
    if (dn < S(0)) {
      const S t = (std::abs(sd) - r) / (-dn);
      if (t >= S(0) && t <= best) {
        const Vec3<S> p = o + t * d - r * ns;
        // inside the triangle: same-sign edge tests against the wound normal
        const bool in = n.dot((tri.b - tri.a).cross(p - tri.a)) >= S(0) && n.dot((tri.c - tri.b).cross(p - tri.b)) >= S(0) &&
                        n.dot((tri.a - tri.c).cross(p - tri.c)) >= S(0);
        if (in) {
          h.t = t;
          h.point = p;
          h.normal = ns;
          h.feature = TriangleFeature::Face;
          return h;  // the face is the outermost part of the grown triangle: nothing is hit before it
        }
      }
    }
  }
  const S dd = d.squaredNorm();
  // Edges: cylinders of radius r around each edge, within the edge's length.
  for (int k = 0; k < 3; ++k) {
    const Vec3<S>& p = tri[k];
    const Vec3<S> e = tri[(k + 1) % 3] - p;
    const S ee = e.squaredNorm();
    if (!(ee > S(0))) continue;
    const Vec3<S> m = o - p;
    const S md = m.dot(d), me = m.dot(e), de = d.dot(e);
    // |(m + t d) x e|^2 / ee = r^2  ->  quadratic in t
    const S a = dd * ee - de * de;
    const S b = md * ee - me * de;
    const S c = m.squaredNorm() * ee - me * me - r * r * ee;
    const auto t = entering_root(a, b, c, best);
    if (!t) continue;
    const S s = (me + *t * de) / ee;
    if (s < S(0) || s > S(1)) continue;
    best = *t;
    found = true;
    h.t = *t;
    h.point = p + s * e;
    h.feature = static_cast<TriangleFeature>(static_cast<int>(TriangleFeature::EdgeAB) + k);
  }
  // Vertices: spheres of radius r.
  for (int k = 0; k < 3; ++k) {
    const Vec3<S> m = o - tri[k];
    const auto t = entering_root(dd, m.dot(d), m.squaredNorm() - r * r, best);
    if (!t) continue;
    best = *t;
    found = true;
    h.t = *t;
    h.point = tri[k];
    h.feature = static_cast<TriangleFeature>(static_cast<int>(TriangleFeature::VertexA) + k);
  }
  if (!found) return std::nullopt;
  const Vec3<S> c = o + h.t * d - h.point;
  const S cn = c.norm();
  h.normal = cn > S(0) ? Vec3<S>(c / cn) : Vec3<S>(-d.normalized());
  return h;
}

}  // namespace detail

/// First hit of the sphere with centre ray.origin + t * ray.direction, t in [0, ray.t_max], and
/// radius `radius` (>= 0; 0 falls back to the ray query) against the mesh placed by `pose`.
template <class BV>
std::optional<SweptSphereHit<typename BvTraits<BV>::Scalar>> swept_sphere_mesh_first_hit(
    const MeshBvh<BV>& mesh, const Ray<typename BvTraits<BV>::Scalar>& ray, typename BvTraits<BV>::Scalar radius,
    const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {}) {
  using S = typename BvTraits<BV>::Scalar;
  if (!(radius > S(0))) {
    const auto h = ray_mesh_first_hit(mesh, ray, pose);
    if (!h) return std::nullopt;
    SweptSphereHit<S> s;
    s.t = h->t;
    s.triangle = h->triangle;
    s.leaf_index = h->leaf_index;
    s.point = h->point;
    s.normal = h->front_face ? h->normal : Vec3<S>(-h->normal);
    s.feature = TriangleFeature::Face;
    return s;
  }
  const Vec3<S> o = pose.R.transpose() * (ray.origin - pose.t);
  const Vec3<S> d = pose.R.transpose() * ray.direction;
  const Vec3<S> inv = detail::safe_inverse(d);
  S best = ray.t_max;
  std::optional<SweptSphereHit<S>> out;
  traverse_nearest(
      mesh.tree(), [&](const BV& bv) { return detail::ray_bv_entry(o, d, inv, bv, best, radius); }, [&]() { return best; },
      [&](std::int32_t k) {
        auto h = detail::swept_sphere_triangle(o, d, radius, mesh.triangle(k), best);
        if (h && (!out || h->t < best)) {
          best = h->t;
          h->leaf_index = k;
          out = h;
        }
        return true;
      });
  if (!out) return std::nullopt;
  out->triangle = mesh.triangle_id(out->leaf_index);
  out->point = pose.apply(out->point);
  out->normal = pose.R * out->normal;
  return out;
}

}  // namespace impact
