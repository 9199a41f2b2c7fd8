// SPDX-License-Identifier: MIT
/// \file
/// Sphere–triangle tests: static overlap, and the first contact of a sphere moving linearly against
/// a fixed triangle (particles with a radius).
///
/// Numerical contract: APPROXIMATE (floating point in S, closed-form roots). The static test
/// compares the closest-point distance with the radius. The swept test returns the smallest time in
/// [0, 1] over the candidate contact events of the triangle's features: the face plane offset by
/// the radius (only where the contact lies on the face), the three edge cylinders (only where the
/// contact lies between the edge's endpoints) and the three vertex spheres. Roots are computed in
/// the cancellation-free form. Degenerate triangles have no face event; zero-length edges have no
/// cylinder event; their vertices still count.
#pragma once

#include "impact/geometry/sphere.hpp"
#include "impact/geometry/triangle.hpp"
#include "impact/narrow/closest_point.hpp"

#include <cmath>
#include <optional>

namespace impact {

/// True when the closed ball and the closed triangle share a point (up to rounding).
template <class S> inline bool sphere_triangle_overlap(const Sphere<S>& sphere, const Triangle<S>& tri) {
  return closest_point_on_triangle(sphere.center, tri).squared_distance <= sphere.radius * sphere.radius;
}

/// First contact of a moving sphere with a triangle.
template <class S> struct SphereTriangleSweepHit {
  S time = S(0);     ///< in [0, 1]: the centre is then p0 + time (p1 - p0)
  Vec3<S> point;     ///< contact point on the triangle
  Vec3<S> normal;    ///< unit normal at the contact, from the triangle towards the sphere centre
  TriangleFeatureId feature = TriangleFeatureId::Face;  ///< feature of the triangle touched first
};

namespace detail {

/// Smallest root in [0, 1] of a t^2 + 2 hb t + c = 0 given c > 0 (outside at t = 0), or -1.
template <class S> inline S first_entry_root(S a, S hb, S c) {
  if (!(a > S(0)) || !(hb < S(0))) return S(-1);  // not approaching
  const S disc = hb * hb - a * c;
  if (disc < S(0)) return S(-1);
  const S t = c / (-hb + std::sqrt(disc));
  return t <= S(1) ? t : S(-1);
}

}  // namespace detail

/// First time in [0, 1] at which a sphere of radius r, its centre moving linearly from p0 to p1,
/// touches the closed triangle, with the contact point and normal; nullopt when it never does. If
/// the sphere already overlaps at p0 the time is 0. The normal points from the contact point
/// towards the centre (the face normal, oriented towards p0, when the centre is on the triangle).
template <class S>
inline std::optional<SphereTriangleSweepHit<S>> sweep_sphere_triangle(const Vec3<S>& p0, const Vec3<S>& p1, S r, const Triangle<S>& tri) {
  static_assert(is_supported_scalar_v<S>, "sweep_sphere_triangle: float or double");
  const S rr = r * r;
  const Vec3<S> n_unit = tri.normal();
  auto make = [&](S time, TriangleFeatureId hint) {
    SphereTriangleSweepHit<S> h;
    h.time = time;
    const Vec3<S> c = p0 + time * (p1 - p0);
    const auto cp = closest_point_on_triangle(c, tri);
    h.point = cp.point;
    h.feature = time > S(0) ? hint : cp.feature;
    const Vec3<S> dv = c - cp.point;
    const S len = dv.norm();
    if (len > S(0)) {
      h.normal = dv / len;
    } else {
      const S side = n_unit.dot(p0 - tri.a);
      h.normal = side < S(0) ? Vec3<S>(-n_unit) : n_unit;
    }
    return h;
  };
  const auto start = closest_point_on_triangle(p0, tri);
  if (start.squared_distance <= rr) return make(S(0), start.feature);

  const Vec3<S> d = p1 - p0;
  S best = S(2);
  TriangleFeatureId feature = TriangleFeatureId::Face;
  // face: the plane offset by r towards the side the centre starts on
  if (n_unit.squaredNorm() > S(0)) {
    const S dist0 = n_unit.dot(p0 - tri.a);
    const S side = dist0 >= S(0) ? S(1) : S(-1);
    const S speed = -side * n_unit.dot(d);  // approach speed towards the plane
    if (std::abs(dist0) > r && speed > S(0)) {
      const S t = (std::abs(dist0) - r) / speed;
      if (t <= S(1)) {
        const Vec3<S> q = p0 + t * d - side * r * n_unit;  // contact point on the plane
        const Vec3<S> ab = tri.b - tri.a, ac = tri.c - tri.a, aq = q - tri.a;
        const Vec3<S> n = tri.scaled_normal();
        const S nn = n.squaredNorm();
        const S wb = n.dot(aq.cross(ac)) / nn, wc = n.dot(ab.cross(aq)) / nn;
        if (wb >= S(0) && wc >= S(0) && wb + wc <= S(1) && t < best) best = t, feature = TriangleFeatureId::Face;
      }
    }
  }
  // edges: infinite cylinders of radius r, contact between the endpoints
  const TriangleFeatureId edge_feature[3] = {TriangleFeatureId::EdgeAB, TriangleFeatureId::EdgeBC, TriangleFeatureId::EdgeCA};
  for (int k = 0; k < 3; ++k) {
    const Vec3<S>& e0 = tri[k];
    const Vec3<S> e = tri[(k + 1) % 3] - e0;
    const S ee = e.squaredNorm();
    if (!(ee > S(0))) continue;
    const Vec3<S> m = p0 - e0;
    // |(m + t d) x e|^2 / |e|^2 = r^2, divided by |e|^2 so that every coefficient is a squared
    // length: the discriminant is then a fourth power of the lengths, not an eighth, and neither
    // over- nor underflows within the library's coordinate range (core/validate.hpp)
    const Vec3<S> A = d.cross(e), B = m.cross(e);
    const S inv_ee = S(1) / ee;
    const S c = B.squaredNorm() * inv_ee - rr;
    if (!(c > S(0))) continue;  // inside the infinite cylinder: an endpoint sphere comes first
    const S t = detail::first_entry_root(A.squaredNorm() * inv_ee, A.dot(B) * inv_ee, c);
    if (t < S(0) || t >= best) continue;
    const S s = (m + t * d).dot(e) / ee;
    if (s >= S(0) && s <= S(1)) best = t, feature = edge_feature[k];
  }
  // vertices: spheres of radius r
  const TriangleFeatureId vertex_feature[3] = {TriangleFeatureId::VertexA, TriangleFeatureId::VertexB, TriangleFeatureId::VertexC};
  for (int k = 0; k < 3; ++k) {
    const Vec3<S> m = p0 - tri[k];
    const S t = detail::first_entry_root(d.squaredNorm(), m.dot(d), m.squaredNorm() - rr);
    if (t >= S(0) && t < best) best = t, feature = vertex_feature[k];
  }
  if (best > S(1)) return std::nullopt;
  return make(best, feature);
}

}  // namespace impact
