// SPDX-License-Identifier: MIT
/// \file
/// First hit of a sphere of radius r moving along a segment against a triangle mesh (a MeshBvh
/// under a rigid transform): the first t at which the sphere touches a triangle's face, edge or
/// vertex. Equivalently a ray against the mesh grown by r (each triangle becomes a slab capped by
/// cylinders and spheres), traversed nearest first with every BV inflated by r.
///
/// Contract. The leaf test is the narrow phase's sweep_sphere_triangle (narrow/sphere_triangle.hpp:
/// faces by the offset plane, edges by ray-cylinder, vertices by ray-sphere, approximate to
/// rounding); the capsule around a shared edge belongs to both triangles, so seams are closed.
/// A sphere that already touches or overlaps a triangle at t = 0 hits it at t = 0 when it moves
/// towards the triangle (velocity . normal < 0, normal from the triangle to the centre), and does
/// not hit it when it moves away: starting in contact neither sticks nor tunnels.
///
/// A sphere whose r * r is not a normal number (r below 2^-511 in double, 2^-63 in float) is cast
/// as a point: the first hit is the watertight ray cast's (query/ray_mesh.hpp), as for r = 0. The
/// sweep's squared distances lose such a radius (r * r rounds to a subnormal or zero): the tube
/// around an edge and the ball around a vertex vanish, and a sphere aimed exactly at a shared edge
/// or vertex of a closed mesh went through it (104 of 1,122 paths from the centre of a unit
/// icosphere through its vertices and edge midpoints, r = 2^-520). The point's first hit misses
/// only the contacts within r of its path.
///
/// A sphere whose r * r is normal but whose r is below the sweep's resolution (r < 2^-20 L in
/// double, 2^-12 L in float, L the largest coordinate involved: the mesh's coordinate_bound, the
/// path's start and end) is swept and also cast as a point, and the earlier hit is returned. The
/// sweep compares squared distances whose rounding grows like eps L^2, so it can lose such a
/// radius at an edge or a vertex (r = 1e-18 at coordinates near 1: 104 of the 1,122 icosphere
/// paths went through, 16 for r = 1e-16, 88 in float for r = 1e-8); the cutoffs are above
/// sqrt(eps) L, where r^2 is at least the rounding of L^2. The sphere touches the surface no later
/// than its centre crosses it, and the point cast is watertight, so the result is never a miss
/// where the centre crosses; the point's hit is returned only when the sweep missed or hit later,
/// and is then at most about r / |direction| later than the true contact. Above the cutoff only the
/// sweep runs.
#pragma once

#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/narrow/sphere_triangle.hpp"

#include <algorithm>
#include <optional>
#include <type_traits>

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

/// Swept sphere (centre o + t d, t in [0, t_max], radius r > 0) against one triangle: the narrow
/// phase's sweep_sphere_triangle with the library's contact rule on top. A sphere already
/// touching the triangle at t = 0 hits only when it moves towards it (d . n < 0 beyond the
/// rounding of the normal); touching and sliding along or moving away is no hit.
template <class S>
inline std::optional<SweptSphereHit<S>> swept_sphere_triangle(const Vec3<S>& o, const Vec3<S>& d, S r, const Triangle<S>& tri,
                                                              S t_max) {
  const auto h = sweep_sphere_triangle(o, Vec3<S>(o + t_max * d), r, tri);
  if (!h) return std::nullopt;
  if (h->time == S(0)) {
    const S dist = (o - h->point).norm();
    const S slack = dist > S(0) ? S(64) * std::numeric_limits<S>::epsilon() * (o.cwiseAbs().maxCoeff() + h->point.cwiseAbs().maxCoeff()) / dist
                                : S(0);
    if (!(d.dot(h->normal) < -slack * d.norm())) return std::nullopt;
  } else if (!(d.dot(h->normal) < S(0))) {
    return std::nullopt;  // tangential grazing: the motion does not approach
  }
  SweptSphereHit<S> out;
  out.t = h->time * t_max;
  out.point = h->point;
  out.normal = h->normal;
  out.feature = h->feature;
  return out;
}

}  // namespace detail

namespace detail {

/// The smallest radius a swept sphere is swept with (see the file comment): r * r is a normal
/// number from here up (2^-511 in double, 2^-63 in float); smaller ones are cast as points.
template <class S> constexpr S kMinSweptRadius = static_cast<S>(std::is_same_v<S, float> ? 0x1p-63 : 0x1p-511);

/// The sweep's resolution relative to the largest coordinate involved (see the file comment): a
/// radius below kSweptRadiusResolution * L is swept and also cast as a point. 2^-20 in double,
/// 2^-12 in float: above sqrt(eps) (2^-26, 2^-11.5), where r^2 stays above the rounding of L^2.
template <class S> constexpr S kSweptRadiusResolution = static_cast<S>(std::is_same_v<S, float> ? 0x1p-12 : 0x1p-20);

/// The watertight ray cast's first hit as a swept-sphere hit (a point, or a radius the sweep
/// cannot resolve): the ray's t and triangle, the normal turned towards the origin's side.
template <class BV>
std::optional<SweptSphereHit<typename BvTraits<BV>::Scalar>> point_cast_as_swept_sphere(const MeshBvh<BV>& mesh,
                                                                                        const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                                        const RigidTransform<typename BvTraits<BV>::Scalar>& pose) {
  using S = typename BvTraits<BV>::Scalar;
  const auto h = ray_mesh_first_hit_unchecked(mesh, ray, pose, nullptr, 0);
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

/// True when the sweep may lose `radius` to rounding (see the file comment): radius below
/// kSweptRadiusResolution times the largest of the mesh's coordinate_bound and the local path's
/// start and end coordinates (a path end that is not finite counts as unresolved).
template <class BV>
bool swept_radius_unresolved(const MeshBvh<BV>& mesh, const Vec3<typename BvTraits<BV>::Scalar>& o,
                             const Vec3<typename BvTraits<BV>::Scalar>& d, typename BvTraits<BV>::Scalar t_max,
                             typename BvTraits<BV>::Scalar radius) {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> end = o + t_max * d;
  const S extent = std::max({mesh.coordinate_bound(), o.cwiseAbs().maxCoeff(), end.cwiseAbs().maxCoeff()});
  return !(radius >= kSweptRadiusResolution<S> * extent);
}

/// swept_sphere_mesh_first_hit without the argument checks (callers that validated them once); the
/// direction as in ray_mesh_first_hit_unchecked (at least CoordinateRange::min_scale).
template <class BV>
std::optional<SweptSphereHit<typename BvTraits<BV>::Scalar>> swept_sphere_mesh_first_hit_unchecked(
    const MeshBvh<BV>& mesh, const Ray<typename BvTraits<BV>::Scalar>& ray, typename BvTraits<BV>::Scalar radius,
    const RigidTransform<typename BvTraits<BV>::Scalar>& pose) {
  using S = typename BvTraits<BV>::Scalar;
  if (!(radius >= kMinSweptRadius<S>)) return point_cast_as_swept_sphere(mesh, ray, pose);  // 0, or r * r not normal
  const Vec3<S> o = pose.R.transpose() * (ray.origin - pose.t);
  const Vec3<S> d = pose.R.transpose() * ray.direction;
  const Vec3<S> inv = detail::safe_inverse(d);
  S best = ray.t_max;
  std::optional<SweptSphereHit<S>> out;
  traverse_nearest(
      mesh.tree(), [&](const BV& bv) { return detail::ray_bv_entry(o, d, inv, bv, best, radius); }, [&]() { return best; },
      [&](std::int32_t k) {
        if (mesh.repeats_previous(k)) return true;  // the same answer as the triangle before it
        auto h = detail::swept_sphere_triangle(o, d, radius, mesh.triangle(k), best);
        if (h && (!out || h->t < best)) {
          best = h->t;
          h->leaf_index = k;
          out = h;
        }
        return true;
      });
  if (out) {
    out->triangle = mesh.triangle_id(out->leaf_index);
    out->point = pose.apply(out->point);
    out->normal = pose.R * out->normal;
  }
  if (swept_radius_unresolved(mesh, o, d, ray.t_max, radius)) {  // the sphere touches no later than its centre crosses
    auto p = point_cast_as_swept_sphere(mesh, ray, pose);
    if (p && (!out || p->t < out->t)) return p;
  }
  return out;
}

}  // namespace detail

/// First hit of the sphere with centre ray.origin + t * ray.direction, t in [0, ray.t_max], and
/// radius `radius` (>= 0; 0, and a radius whose square is not a normal number, fall back to the
/// ray query; a radius below the sweep's resolution takes the earlier of the sweep's and the ray
/// query's hits: see the file comment) against the mesh placed by `pose`.
/// Throws InvalidInput for a radius NaN, negative or beyond CoordinateRange, and on the checks of
/// ray_mesh_first_hit (ray and pose).
template <class BV>
std::optional<SweptSphereHit<typename BvTraits<BV>::Scalar>> swept_sphere_mesh_first_hit(
    const MeshBvh<BV>& mesh, const Ray<typename BvTraits<BV>::Scalar>& ray, typename BvTraits<BV>::Scalar radius,
    const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {}) {
  constexpr const char* where = "swept_sphere_mesh_first_hit";
  validate_length(radius, where, "radius");
  detail::validate_ray_cast(mesh, ray, pose, 0, where);
  return detail::swept_sphere_mesh_first_hit_unchecked(mesh, ray, radius, pose);
}

}  // namespace impact
