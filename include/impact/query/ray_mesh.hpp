// SPDX-License-Identifier: MIT
/// \file
/// Ray (or segment) against a triangle mesh held in a MeshBvh, placed in the world by a rigid
/// transform: first hit (nearest-first traversal, the entry parameter of the ray into each node's
/// BV as the key) and any hit (depth-first, stops at the first triangle hit).
///
/// Numerical contract. Triangles are tested with the narrow phase's watertight ray-triangle test
/// (narrow/ray_triangle.hpp; Woop, Benthin and Wald, JCGT 2013): the ray is prepared once, and a
/// ray through a shared edge or vertex of a closed mesh hits at least one of the triangles around
/// it (never none). A hit on the boundary of a triangle counts (closed triangles). Rays parallel
/// to a triangle's plane miss it. The node
/// tests are conservative (their exit parameter is padded, PBRT's robust slab test), so no hit is
/// lost to rounding in the traversal. One tie rule keeps particles out of surfaces: a hit at
/// exactly t = 0 counts only when the ray enters the triangle's front (d . n < 0, n the wound
/// normal), so a point exactly on a surface is on its front side: moving into the surface it
/// hits, moving away it does not.
#pragma once

#include "impact/bvh/compact_bvh.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/narrow/ray_triangle.hpp"

#include <cassert>
#include <cmath>
#include <cstdint>
#include <optional>
#include <type_traits>
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

/// The narrow-phase watertight test with the library's tie rule at t = 0: a hit exactly at the
/// ray's origin counts only when the ray enters the triangle's front (see the file comment).
/// `pr.ray.t_max` is the current bound.
template <class S> inline std::optional<RayTriangleHit<S>> ray_mesh_triangle_hit(const PreparedRay<S>& pr, const Triangle<S>& tri) {
  auto h = intersect_ray_triangle(pr, tri);
  if (h && h->t == S(0) && !h->front) return std::nullopt;
  return h;
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
    f += std::abs(f) * S(4) * std::numeric_limits<S>::epsilon();  // robust slab test (PBRT 3.9.2)
    t0 = n > t0 ? n : t0;
    t1 = f < t1 ? f : t1;
    if (t0 > t1) return std::nullopt;
  }
  return t0;
}

/// ray_box_entry for a CompactBvh node's float box, for a direction whose inverse `inv` is finite
/// on every axis, with the axes' signs (`neg`: inv < 0) precomputed: the near and far planes are
/// picked by sign instead of swapped, which gives exactly ray_box_entry's values.
template <class S>
inline std::optional<S> ray_node_entry(const Vec3<S>& o, const Vec3<S>& inv, const bool (&neg)[3], const CompactBvhNode& n, S t_max) {
  S t0 = S(0), t1 = t_max;
  for (int i = 0; i < 3; ++i) {
    const S lo = S(n.lo[i]), hi = S(n.hi[i]);
    const S a = ((neg[i] ? hi : lo) - o[i]) * inv[i];
    S b = ((neg[i] ? lo : hi) - o[i]) * inv[i];
    b += std::abs(b) * S(4) * std::numeric_limits<S>::epsilon();  // robust slab test (PBRT 3.9.2)
    t0 = a > t0 ? a : t0;
    t1 = b < t1 ? b : t1;
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

namespace detail {

/// The first-hit cast shared by both tree layouts: `walk(key, bound, visit)` runs a nearest-first
/// traversal whose key receives a node's BV (the mesh's own, or a CompactBvh's float box).
template <class BV, class Walk>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit_with(const MeshBvh<BV>& mesh, Walk&& walk,
                                                                                 const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                                 const RigidTransform<typename BvTraits<BV>::Scalar>& pose,
                                                                                 RayMeshStats* stats) {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> o = pose.R.transpose() * (ray.origin - pose.t);
  const Vec3<S> d = pose.R.transpose() * ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return std::nullopt;
  PreparedRay<S> pr(Ray<S>(o, d, ray.t_max));
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
  // the compact walk's slab test picks each axis' near plane by the direction's sign, which gives
  // ray_box_entry's values whenever 1 / d is finite on every axis
  const bool slab_ok = std::isfinite(inv[0]) && std::isfinite(inv[1]) && std::isfinite(inv[2]);
  const bool neg[3] = {inv[0] < S(0), inv[1] < S(0), inv[2] < S(0)};
  walk(
      [&](const auto& bv) -> std::optional<S> {
        if (stats) ++stats->node_tests;
        if constexpr (std::is_same_v<std::decay_t<decltype(bv)>, CompactBvhNode>) {
          if (finite)
            for (int i = 0; i < 3; ++i)
              if (seg.max[i] < S(bv.lo[i]) || S(bv.hi[i]) < seg.min[i]) return std::nullopt;
          if (slab_ok) return detail::ray_node_entry(o, inv, neg, bv, best);
          return detail::ray_box_entry(o, inv, Aabb<S>(bv.box().template cast<S>()), best);  // exact: float -> S
        } else {
          if (finite && !detail::may_overlap(seg, bv)) return std::nullopt;
          return detail::ray_bv_entry(o, d, inv, bv, best);
        }
      },
      [&]() { return best; },
      [&](std::int32_t k) {
        if (stats) ++stats->triangle_tests;
        pr.ray.t_max = best;
        const auto h = detail::ray_mesh_triangle_hit(pr, mesh.triangle(k));
        if (h && (best_leaf < 0 || h->t < best)) {
          best = h->t;
          best_leaf = k;
          best_bary = Vec3<S>(h->u, h->v, h->w);
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

}  // namespace detail

/// First hit of the ray origin + t * direction, t in [0, ray.t_max], against the mesh placed in
/// the world by `pose`. A segment p -> q is the ray (p, q - p, 1). Returns nothing when the ray
/// misses or the direction is zero. Ties between triangles at the same t (a shared edge) return
/// one of them. Cost O(log n) for rays that pass near few triangles.
///
/// `start_node` (the root by default) restricts the search to one subtree of mesh.tree(): the
/// caller guarantees that every triangle the ray can hit lies in it (e.g. DistanceGrid::start_node).
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit(const MeshBvh<BV>& mesh,
                                                                            const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                            const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {},
                                                                            RayMeshStats* stats = nullptr, std::int32_t start_node = 0) {
  return detail::ray_mesh_first_hit_with(
      mesh,
      [&](auto&& key, auto&& bound, auto&& visit) {
        traverse_nearest(mesh.tree(), [&](const BV& bv) { return key(bv); }, bound, visit, start_node);
      },
      ray, pose, stats);
}

/// The same first hit, walking `fast`, a CompactBvh of mesh.tree() (bvh/compact_bvh.hpp), from
/// the node standing for `start_node` (a node of mesh.tree(), with the same guarantee): the same
/// t (the triangle may differ only among triangles hit at exactly the same t), faster when the
/// mesh's tree does not fit in cache. `fast` must be built from mesh.tree() after its last change.
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit(const MeshBvh<BV>& mesh, const CompactBvh& fast,
                                                                            const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                            const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {},
                                                                            RayMeshStats* stats = nullptr, std::int32_t start_node = 0) {
  assert(fast.num_primitives() == static_cast<std::size_t>(mesh.num_triangles()));
  return detail::ray_mesh_first_hit_with(
      mesh,
      [&](auto&& key, auto&& bound, auto&& visit) {
        traverse_nearest(fast, [&](const CompactBvhNode& n) { return key(n); }, bound, visit, fast.from_source(start_node));
      },
      ray, pose, stats);
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
  const PreparedRay<S> pr(Ray<S>(o, d, ray.t_max));
  const Vec3<S> inv = detail::safe_inverse(d);
  bool found = false;
  traverse(
      mesh.tree(), [&](const BV& bv) { return detail::ray_bv_entry(o, d, inv, bv, ray.t_max).has_value(); },
      [&](std::int32_t k) {
        found = detail::ray_mesh_triangle_hit(pr, mesh.triangle(k)).has_value();
        return !found;
      });
  return found;
}

}  // namespace impact
