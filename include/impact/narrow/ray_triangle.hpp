// SPDX-License-Identifier: MIT
/// \file
/// Watertight ray–triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
/// Intersection", JCGT 2013).
///
/// Numerical contract: WATERTIGHT, hit parameters APPROXIMATE. The ray is mapped to a ray space
/// where it runs along +z from the origin (permutation making the dominant direction component z,
/// then a shear); the triangle is hit when its three 2D edge functions at the origin do not have
/// opposite strict signs. An edge function depends only on its edge's two vertices and is computed
/// identically (up to its sign) for both triangles sharing that edge, and zero counts as inside, so a
/// ray through a shared edge or vertex of a closed mesh hits at least one adjacent triangle: no
/// leaks through seams (a ray may report both). In float, an edge function that evaluates to zero is
/// recomputed in double (the products of floats are then exact), so its sign is that of the sheared
/// float coordinates. Rays lying in the triangle's plane, and degenerate triangles, report no hit.
/// Assumes no -ffast-math, and no FMA contraction of the edge functions (it would break the
/// symmetry the watertightness argument relies on): the CMake target impact::impact passes
/// -ffp-contract=off to g++ and clang; a build that includes the headers without it must too when
/// it targets a processor with FMA (-march=native, -mfma).
#pragma once

#include "impact/geometry/ray.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <type_traits>
#include <utility>

namespace impact {

/// A ray–triangle hit. point = ray.at(t) = u a + v b + w c (approximately).
template <class S> struct RayTriangleHit {
  S t = S(0);                   ///< ray parameter in [0, ray.t_max]
  S u = S(0), v = S(0), w = S(0);  ///< barycentric weights of the triangle's a, b, c (each in [0, 1], sum 1)
  bool front = true;            ///< true when the ray meets the side the normal (b - a) x (c - a) points to
};

/// A ray prepared for many triangles: the axis permutation and the shear to ray space.
template <class S> struct PreparedRay {
  Ray<S> ray;
  int kx = 0, ky = 1, kz = 2;
  S sx = S(0), sy = S(0), sz = S(1);
  bool valid = false;  ///< false for a zero direction (it hits nothing)

  PreparedRay() = default;
  explicit PreparedRay(const Ray<S>& r) : ray(r) {
    const Vec3<S> ad = r.direction.cwiseAbs();
    kz = ad.x() >= ad.y() ? (ad.x() >= ad.z() ? 0 : 2) : (ad.y() >= ad.z() ? 1 : 2);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    const S dz = r.direction[kz];
    valid = dz != S(0);
    if (!valid) return;
    if (dz < S(0)) std::swap(kx, ky);  // keep the frame right-handed
    sx = r.direction[kx] / dz;
    sy = r.direction[ky] / dz;
    sz = S(1) / dz;
  }
};

namespace detail {

template <class S, class W>
inline std::optional<RayTriangleHit<S>> finish_ray_hit(W eu, W ev, W ew, S az, S bz, S cz, S t_max) {
  if ((eu < W(0) || ev < W(0) || ew < W(0)) && (eu > W(0) || ev > W(0) || ew > W(0))) return std::nullopt;
  const W det = eu + ev + ew;
  if (det == W(0)) return std::nullopt;
  const W tt = eu * W(az) + ev * W(bz) + ew * W(cz);
  if (det > W(0)) {
    if (tt < W(0) || tt > W(t_max) * det) return std::nullopt;
  } else {
    if (tt > W(0) || tt < W(t_max) * det) return std::nullopt;
  }
  const W inv = W(1) / det;
  RayTriangleHit<S> h;
  h.t = std::min(S(tt * inv), t_max);
  h.u = S(eu * inv), h.v = S(ev * inv), h.w = S(ew * inv);
  h.front = det > W(0);
  return h;
}

}  // namespace detail

/// Watertight intersection of a prepared ray with the closed triangle tri (see the file comment).
template <class S> inline std::optional<RayTriangleHit<S>> intersect_ray_triangle(const PreparedRay<S>& pr, const Triangle<S>& tri) {
  static_assert(is_supported_scalar_v<S>, "intersect_ray_triangle: float or double");
  if (!pr.valid) return std::nullopt;
  const Vec3<S> A = tri.a - pr.ray.origin, B = tri.b - pr.ray.origin, C = tri.c - pr.ray.origin;
  const int kx = pr.kx, ky = pr.ky, kz = pr.kz;
  const S ax = A[kx] - pr.sx * A[kz], ay = A[ky] - pr.sy * A[kz];
  const S bx = B[kx] - pr.sx * B[kz], by = B[ky] - pr.sy * B[kz];
  const S cx = C[kx] - pr.sx * C[kz], cy = C[ky] - pr.sy * C[kz];
  const S cxby = cx * by, cybx = cy * bx, axcy = ax * cy, aycx = ay * cx, bxay = bx * ay, byax = by * ax;
  const S eu = cxby - cybx, ev = axcy - aycx, ew = bxay - byax;
  const S az = pr.sz * A[kz], bz = pr.sz * B[kz], cz = pr.sz * C[kz];
  if constexpr (std::is_same_v<S, float>) {
    if (eu == 0.0f || ev == 0.0f || ew == 0.0f) {
      const double du = double(cx) * double(by) - double(cy) * double(bx);
      const double dv = double(ax) * double(cy) - double(ay) * double(cx);
      const double dw = double(bx) * double(ay) - double(by) * double(ax);
      return detail::finish_ray_hit<S, double>(du, dv, dw, az, bz, cz, pr.ray.t_max);
    }
  }
  return detail::finish_ray_hit<S, S>(eu, ev, ew, az, bz, cz, pr.ray.t_max);
}

/// Watertight intersection of the ray (origin + s direction, s in [0, t_max]) with the closed
/// triangle: nullopt on a miss. Prepare the ray once (PreparedRay) when testing many triangles.
template <class S> inline std::optional<RayTriangleHit<S>> intersect_ray_triangle(const Ray<S>& ray, const Triangle<S>& tri) {
  return intersect_ray_triangle(PreparedRay<S>(ray), tri);
}

}  // namespace impact
