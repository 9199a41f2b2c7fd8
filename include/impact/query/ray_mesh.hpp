// SPDX-License-Identifier: MIT
/// \file
/// Ray (or segment) against a triangle mesh held in a MeshBvh, placed in the world by a rigid
/// transform: first hit (nearest-first traversal, the entry parameter of the ray into each node's
/// BV as the key) and any hit (depth-first, stops at the first triangle hit).
///
/// Numerical contract. Triangles are tested with a watertight ray-triangle test (Woop, Benthin and
/// Wald, "Watertight Ray/Triangle Intersection", JCGT 2013): the ray is sheared into its own frame
/// once, and each edge function depends only on the edge's two vertices, so a ray through a shared
/// edge or vertex of a closed mesh hits at least one of the triangles around it (never none). Edge
/// functions that come out exactly zero in float are recomputed in double. A hit on the boundary
/// of a triangle counts (closed triangles). Rays parallel to a triangle's plane miss it. The node
/// tests are conservative (their exit parameter is padded, PBRT's robust slab test), so no hit is
/// lost to rounding in the traversal. One tie rule keeps particles out of surfaces: a hit at
/// exactly t = 0 counts only when the ray enters the triangle's front (d . n < 0, n the wound
/// normal), so a point exactly on a surface is on its front side: moving into the surface it
/// hits, moving away it does not.
#pragma once

#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/transform.hpp"

#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>

namespace impact {

/// A ray-mesh hit, in the world frame.
template <class S> struct RayMeshHit {
  S t = S(0);                          ///< ray parameter: the hit point is origin + t * direction
  std::int32_t triangle = -1;          ///< row of the mesh's F
  std::int32_t leaf_index = -1;        ///< leaf position (MeshBvh::triangle(leaf_index))
  Vec3<S> point = Vec3<S>::Zero();     ///< hit point, origin + t * direction
  Vec3<S> normal = Vec3<S>::Zero();    ///< unit normal of the triangle as wound (world frame)
  Vec3<S> barycentric = Vec3<S>::Zero();  ///< weights of the triangle's vertices a, b, c at the hit
  bool front_face = true;              ///< direction . normal < 0 (the ray came from the front side)
};

/// Counters of one query, for benchmarks.
struct RayMeshStats {
  std::size_t node_tests = 0, triangle_tests = 0;
};

namespace detail {

/// A ray prepared for the watertight test: shear constants and the permutation of axes that
/// makes the dominant direction component the z axis.
template <class S> struct WatertightRay {
  Vec3<S> o, d;
  int kx = 0, ky = 1, kz = 2;
  S sx = 0, sy = 0, sz = 1;
  explicit WatertightRay(const Vec3<S>& origin, const Vec3<S>& dir) : o(origin), d(dir) {
    const Vec3<S> a = dir.cwiseAbs();
    kz = a[0] >= a[1] ? (a[0] >= a[2] ? 0 : 2) : (a[1] >= a[2] ? 1 : 2);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    if (dir[kz] < S(0)) std::swap(kx, ky);  // keep the winding
    sx = dir[kx] / dir[kz];
    sy = dir[ky] / dir[kz];
    sz = S(1) / dir[kz];
  }
};

/// Watertight ray-triangle test. Returns the (t, barycentric) of a hit with t in [0, t_max] (t = 0
/// only when entering the front), or nothing. The direction must be nonzero.
template <class S>
inline std::optional<std::pair<S, Vec3<S>>> watertight_hit(const WatertightRay<S>& r, const Triangle<S>& tri, S t_max) {
  const Vec3<S> A = tri.a - r.o, B = tri.b - r.o, C = tri.c - r.o;
  const S ax = A[r.kx] - r.sx * A[r.kz], ay = A[r.ky] - r.sy * A[r.kz];
  const S bx = B[r.kx] - r.sx * B[r.kz], by = B[r.ky] - r.sy * B[r.kz];
  const S cx = C[r.kx] - r.sx * C[r.kz], cy = C[r.ky] - r.sy * C[r.kz];
  S u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
  if constexpr (std::is_same_v<S, float>) {
    if (u == S(0) || v == S(0) || w == S(0)) {
      u = static_cast<S>(double(cx) * double(by) - double(cy) * double(bx));
      v = static_cast<S>(double(ax) * double(cy) - double(ay) * double(cx));
      w = static_cast<S>(double(bx) * double(ay) - double(by) * double(ax));
    }
  }
  if ((u < S(0) || v < S(0) || w < S(0)) && (u > S(0) || v > S(0) || w > S(0))) return std::nullopt;
  const S det = u + v + w;
  if (det == S(0)) return std::nullopt;  // parallel to the plane, or degenerate triangle
  const S az = r.sz * A[r.kz], bz = r.sz * B[r.kz], cz = r.sz * C[r.kz];
  const S T = u * az + v * bz + w * cz;
  // t = T / det must lie in [0, t_max]; compare without dividing, sign-aware.
  if (det > S(0) ? (T < S(0) || T > t_max * det) : (T > S(0) || T < t_max * det)) return std::nullopt;
  const S inv = S(1) / det;
  const S t = T * inv;
  if (T == S(0) && r.d.dot(tri.scaled_normal()) >= S(0)) return std::nullopt;  // on the surface, leaving or parallel
  return std::make_pair(t, Vec3<S>(u * inv, v * inv, w * inv));
}

/// Entry parameter of the ray into a box, padded so that rounding never loses a hit; nullopt when
/// the ray misses the box or enters it after t_max.
template <class S>
inline std::optional<S> ray_box_entry(const Vec3<S>& o, const Vec3<S>& inv_d, const Aabb<S>& box, S t_max) {
  S t0 = S(0), t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    S n = (box.min[i] - o[i]) * inv_d[i], f = (box.max[i] - o[i]) * inv_d[i];
    if (n != n || f != f) {  // 0 * inf: direction component zero and origin on a slab plane
      if (o[i] < box.min[i] || o[i] > box.max[i]) return std::nullopt;
      continue;
    }
    if (n > f) std::swap(n, f);
    f *= S(1) + S(4) * std::numeric_limits<S>::epsilon();  // robust slab test (PBRT 3.9.2)
    t0 = n > t0 ? n : t0;
    t1 = f < t1 ? f : t1;
    if (t0 > t1) return std::nullopt;
  }
  return t0;
}

/// Entry parameter of the ray into a sphere (padded), nullopt on a miss or entry after t_max.
template <class S> inline std::optional<S> ray_sphere_entry(const Vec3<S>& o, const Vec3<S>& d, const Sphere<S>& s, S t_max) {
  const Vec3<S> m = o - s.center;
  const S r = s.radius * (S(1) + S(8) * std::numeric_limits<S>::epsilon());
  const S c = m.squaredNorm() - r * r;
  if (c <= S(0)) return S(0);  // origin inside
  const S a = d.squaredNorm(), b = m.dot(d);
  if (b >= S(0) || a == S(0)) return std::nullopt;
  const S disc = b * b - a * c;
  if (disc < S(0)) return std::nullopt;
  const S t = (-b - std::sqrt(disc)) / a;
  if (t > t_max) return std::nullopt;
  return t > S(0) ? t : S(0);
}

/// Entry of a ray into a BV inflated by `margin` (0 for a plain ray; a sphere's radius for a swept
/// sphere). `inv_d` is the componentwise inverse of d.
template <class S>
inline std::optional<S> ray_bv_entry(const Vec3<S>& o, const Vec3<S>& d, const Vec3<S>& inv_d, const Aabb<S>& box, S t_max,
                                     S margin = S(0)) {
  (void)d;
  if (margin > S(0)) return ray_box_entry(o, inv_d, Aabb<S>(box.min.array() - margin, box.max.array() + margin), t_max);
  return ray_box_entry(o, inv_d, box, t_max);
}
template <class S>
inline std::optional<S> ray_bv_entry(const Vec3<S>& o, const Vec3<S>& d, const Vec3<S>&, const Sphere<S>& s, S t_max,
                                     S margin = S(0)) {
  return ray_sphere_entry(o, d, Sphere<S>(s.center, s.radius + margin), t_max);
}

/// Conservative box-versus-BV prefilter (false only when they are certainly disjoint).
template <class S> inline bool may_overlap(const Aabb<S>& seg, const Aabb<S>& b) {
  return (seg.min.array() <= b.max.array()).all() && (b.min.array() <= seg.max.array()).all();
}
template <class S> inline bool may_overlap(const Aabb<S>& seg, const Sphere<S>& s) {
  const Vec3<S> q = s.center.cwiseMax(seg.min).cwiseMin(seg.max);
  return (q - s.center).squaredNorm() <= s.radius * s.radius * (S(1) + S(8) * std::numeric_limits<S>::epsilon());
}

template <class S> inline Vec3<S> safe_inverse(const Vec3<S>& d) {
  return Vec3<S>(S(1) / d[0], S(1) / d[1], S(1) / d[2]);  // +-inf for zero components
}

}  // namespace detail

/// First hit of the ray origin + t * direction, t in [0, ray.t_max], against the mesh placed in
/// the world by `pose`. A segment p -> q is the ray (p, q - p, 1). Returns nothing when the ray
/// misses or the direction is zero. Ties between triangles at the same t (a shared edge) return
/// one of them. Cost O(log n) for rays that pass near few triangles.
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit(const MeshBvh<BV>& mesh,
                                                                            const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                            const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {},
                                                                            RayMeshStats* stats = nullptr) {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> o = pose.R.transpose() * (ray.origin - pose.t);
  const Vec3<S> d = pose.R.transpose() * ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return std::nullopt;
  const detail::WatertightRay<S> wr(o, d);
  const Vec3<S> inv = detail::safe_inverse(d);
  S best = ray.t_max;
  std::int32_t best_leaf = -1;
  Vec3<S> best_bary;
  // a finite ray's own box rejects most nodes before the slab test
  const bool finite = ray.t_max < std::numeric_limits<S>::infinity();
  Aabb<S> seg;
  if (finite) {
    const Vec3<S> e = o + ray.t_max * d;
    const S pad = S(4) * std::numeric_limits<S>::epsilon() * (o.cwiseAbs().maxCoeff() + e.cwiseAbs().maxCoeff());
    seg = Aabb<S>(o.cwiseMin(e).array() - pad, o.cwiseMax(e).array() + pad);
  }
  traverse_nearest(
      mesh.tree(),
      [&](const BV& bv) -> std::optional<S> {
        if (stats) ++stats->node_tests;
        if (finite && !detail::may_overlap(seg, bv)) return std::nullopt;
        return detail::ray_bv_entry(o, d, inv, bv, best);
      },
      [&]() { return best; },
      [&](std::int32_t k) {
        if (stats) ++stats->triangle_tests;
        const auto h = detail::watertight_hit(wr, mesh.triangle(k), best);
        if (h && (best_leaf < 0 || h->first < best)) {
          best = h->first;
          best_leaf = k;
          best_bary = h->second;
        }
        return true;
      });
  if (best_leaf < 0) return std::nullopt;
  RayMeshHit<S> hit;
  hit.t = best;
  hit.leaf_index = best_leaf;
  hit.triangle = mesh.triangle_id(best_leaf);
  hit.barycentric = best_bary;
  hit.point = ray.origin + best * ray.direction;
  const Vec3<S> n = mesh.triangle(best_leaf).normal();
  hit.normal = pose.R * n;
  hit.front_face = d.dot(n) < S(0);
  return hit;
}

/// True when the ray hits any triangle for t in [0, ray.t_max] (same rules as the first hit).
/// Depth-first, stops at the first triangle found: cheaper than the first hit for visibility and
/// tunnelling checks.
template <class BV>
bool ray_mesh_any_hit(const MeshBvh<BV>& mesh, const Ray<typename BvTraits<BV>::Scalar>& ray,
                      const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {}) {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> o = pose.R.transpose() * (ray.origin - pose.t);
  const Vec3<S> d = pose.R.transpose() * ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return false;
  const detail::WatertightRay<S> wr(o, d);
  const Vec3<S> inv = detail::safe_inverse(d);
  bool found = false;
  traverse(
      mesh.tree(), [&](const BV& bv) { return detail::ray_bv_entry(o, d, inv, bv, ray.t_max).has_value(); },
      [&](std::int32_t k) {
        found = detail::watertight_hit(wr, mesh.triangle(k), ray.t_max).has_value();
        return !found;
      });
  return found;
}

}  // namespace impact
