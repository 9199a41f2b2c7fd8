// SPDX-License-Identifier: MIT
/// \file
/// Ray (or segment) against a triangle mesh held in a MeshBvh, placed in the world by a rigid
/// transform: first hit (nearest-first traversal, the entry parameter of the ray into each node's
/// BV as the key) and any hit (depth-first, stops at the first triangle hit).
///
/// Numerical contract. Triangles are tested with the narrow phase's watertight ray-triangle test
/// (narrow/ray_triangle.hpp; Woop, Benthin and Wald, JCGT 2013, with exact signs of its edge
/// functions: whether the ray's line meets the closed triangle is decided exactly, t is
/// approximate): the ray is prepared once, and a ray through a shared edge or vertex of a closed
/// mesh hits at least one of the triangles around it (never none). A hit on the boundary of a
/// triangle counts (closed triangles). Rays parallel to a triangle's plane miss it. A triangle counts as hit only when the ray also enters its
/// bounding box by the node tests' slab test, and its t is never below that entry (see
/// detail::ray_mesh_triangle_hit). The node tests are conservative (their exit parameter is
/// padded, PBRT's robust slab test) and monotone (a box inside another is entered no earlier), so
/// no hit is lost to rounding in the traversal of a box tree or a CompactBvh: their first hit's t
/// is exactly the smallest t of a loop over every triangle. Oriented-box trees key on the same
/// slab entry into each box's axis-aligned hull and reject nodes whose box the ray's line misses
/// (detail::ray_bv_entry for Obb): the same exact answer, since the watertight test hits only
/// triangles its ray's line meets (exact signs) within its approximate t range. Sphere trees use the sphere's padded
/// entry, a lower bound up to the rounding of the entry itself. One tie rule keeps particles out of surfaces: a hit at
/// exactly t = 0 counts only when the ray enters the triangle's front (d . n < 0, n the wound
/// normal), so a point exactly on a surface is on its front side: moving into the surface it
/// hits, moving away it does not.
///
/// Cost limit: k coincident copies of a triangle cost O(k) triangle tests a cast unless their
/// box is entered exactly at the hit (copies flat across the ray's axis, box trees): every node
/// holding a copy is entered before the hit and no node test can tell its copies add nothing.
#pragma once

#include "impact/bvh/compact_bvh.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/core/next_float.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/narrow/ray_triangle.hpp"

#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <type_traits>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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

/// Entry parameter of the ray into a box, padded so that rounding never loses a hit; nullopt when
/// the ray misses the box or enters it after t_max. Monotone in the box: for boxes A inside B,
/// the computed entry into B is <= the computed entry into A, and B is missed only when A is
/// (every plane difference and product is rounded monotonically); the first hit relies on that.
template <class S>
inline std::optional<S> ray_box_entry(const Vec3<S>& o, const Vec3<S>& inv_d, const Aabb<S>& box, S t_max);

/// The two rules below on a watertight hit at t (front: the ray enters the triangle's front): t
/// raised to the entry into the triangle's box (none when the ray misses the box before t_max),
/// and none at exactly t = 0 from behind. Shared by ray_mesh_triangle_hit and the wide cast's
/// SIMD lanes (query/ray_wide_bvh.hpp), which must decide alike.
template <class S>
inline std::optional<S> mesh_hit_t(const Vec3<S>& o, const Vec3<S>& inv, const Triangle<S>& tri, S t, bool front, S t_max) {
  const Aabb<S> box(tri.a.cwiseMin(tri.b).cwiseMin(tri.c), tri.a.cwiseMax(tri.b).cwiseMax(tri.c));
  const std::optional<S> entry = ray_box_entry(o, inv, box, t_max);
  if (!entry) return std::nullopt;
  if (t < *entry) t = *entry;
  if (t == S(0) && !front) return std::nullopt;
  return t;
}

/// The narrow-phase watertight test with the library's rules. `pr.ray.t_max` is the current bound,
/// `inv` the componentwise inverse of the ray's direction (safe_inverse).
///  - The ray must enter the triangle's bounding box by the node tests' own slab test
///    (ray_box_entry), and the hit's t is raised to that entry when it is below it. The narrow
///    phase's t is a rounded convex combination of the vertices' depths along the ray, which can
///    fall an ulp or more below the entry into the triangle's box (a ray through a vertex that is a
///    corner of the box), or anywhere in the triangle's depth range for a ray in the triangle's
///    plane (the edge functions are then rounding noise). Raised to the entry it is never below the
///    computed entry into any box holding the triangle (ray_box_entry is monotone), so a node whose
///    computed entry is >= the best t found cannot hold a smaller one: the traversal's pruning is
///    exact, and the tree's first hit is the brute-force loop's minimum, bit for bit
///    (tests/fuzz/fuzz_mesh_bvh.cpp).
///  - A hit at exactly t = 0 counts only when the ray enters the triangle's front (see the file
///    comment).
template <class S>
inline std::optional<RayTriangleHit<S>> ray_mesh_triangle_hit(const PreparedRay<S>& pr, const Vec3<S>& inv, const Triangle<S>& tri) {
  auto h = intersect_ray_triangle(pr, tri);
  if (!h) return h;
  const std::optional<S> t = mesh_hit_t(pr.ray.origin, inv, tri, h->t, h->front, pr.ray.t_max);
  if (!t) return std::nullopt;
  h->t = *t;
  return h;
}

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

/// ray_box_entry for both boxes of a CompactBvh pair at once, for a ray whose inverse direction
/// `inv` is finite on every axis: the near and far planes are picked by the axes' signs instead of
/// swapped, which gives exactly ray_box_entry's values (with SSE2, two siblings per instruction:
/// maxpd and minpd pick a > b ? a : b as the scalar code does). Set up once per ray.
template <class S>
class PairSlab {
 public:
  PairSlab(const Vec3<S>& o, const Vec3<S>& inv) {
    for (int i = 0; i < 3; ++i) {
      // byte offsets of this axis' near and far planes (both siblings) in a CompactBvhPair
      const bool neg = inv[i] < S(0);
      const std::size_t lo = offsetof(CompactBvhPair, lo) + sizeof(float[2]) * std::size_t(i);
      const std::size_t hi = offsetof(CompactBvhPair, hi) + sizeof(float[2]) * std::size_t(i);
      near_[i] = neg ? hi : lo;
      far_[i] = neg ? lo : hi;
#if defined(__SSE2__)
      if constexpr (std::is_same_v<S, double>) {
        o2_[i] = _mm_set1_pd(o[i]);
        inv2_[i] = _mm_set1_pd(inv[i]);
      }
#endif
      o_[i] = o[i];
      inv_[i] = inv[i];
    }
  }
  /// keys[side]: the entry parameter into that sibling's box, or NaN when the ray misses it or
  /// enters it after t_max.
  void keys(const CompactBvhPair& p, S t_max, S (&keys)[2]) const {
    const char* base = reinterpret_cast<const char*>(&p);
#if defined(__SSE2__)
    if constexpr (std::is_same_v<S, double>) {
      const __m128d pad = _mm_set1_pd(4 * std::numeric_limits<double>::epsilon());
      const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
      __m128d t0 = _mm_setzero_pd(), t1 = _mm_set1_pd(t_max);
      for (int i = 0; i < 3; ++i) {
        const __m128d a = _mm_mul_pd(_mm_sub_pd(load2(base + near_[i]), o2_[i]), inv2_[i]);
        __m128d b = _mm_mul_pd(_mm_sub_pd(load2(base + far_[i]), o2_[i]), inv2_[i]);
        b = _mm_add_pd(b, _mm_mul_pd(_mm_and_pd(b, abs_mask), pad));  // robust slab test (PBRT 3.9.2)
        t0 = _mm_max_pd(a, t0);
        t1 = _mm_min_pd(b, t1);
      }
      const __m128d hit = _mm_cmple_pd(t0, t1);
      _mm_storeu_pd(keys,
                    _mm_or_pd(_mm_and_pd(hit, t0), _mm_andnot_pd(hit, _mm_set1_pd(std::numeric_limits<double>::quiet_NaN()))));
      return;
    }
#endif
    S t0[2] = {S(0), S(0)}, t1[2] = {t_max, t_max};
    for (int i = 0; i < 3; ++i) {
      float near_plane[2], far_plane[2];
      std::memcpy(near_plane, base + near_[i], sizeof near_plane);
      std::memcpy(far_plane, base + far_[i], sizeof far_plane);
      for (int c = 0; c < 2; ++c) {
        const S a = (S(near_plane[c]) - o_[i]) * inv_[i];
        S b = (S(far_plane[c]) - o_[i]) * inv_[i];
        b += std::abs(b) * S(4) * std::numeric_limits<S>::epsilon();  // robust slab test (PBRT 3.9.2)
        t0[c] = a > t0[c] ? a : t0[c];
        t1[c] = b < t1[c] ? b : t1[c];
      }
    }
    for (int c = 0; c < 2; ++c) keys[c] = t0[c] <= t1[c] ? t0[c] : std::numeric_limits<S>::quiet_NaN();
  }

 private:
#if defined(__SSE2__)
  // two floats, widened to two doubles
  static __m128d load2(const char* f) {
    return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f))));
  }
  __m128d o2_[3], inv2_[3];
#endif
  S o_[3], inv_[3];
  std::size_t near_[3], far_[3];
};

/// Entry parameter of the ray into a sphere (padded), nullopt on a miss or entry after t_max.
/// The padding is at the scale of the coordinates, not only of the radius: the offset o - centre
/// is rounded at the scale of |o| and |centre|, so a tiny sphere far from the origin (a leaf
/// around a 1e-4 triangle seen from 2 units away) was missed by a ray through its triangle's
/// vertex (the entry rounded past t_max = the vertex's t, or the discriminant b^2 - a c lost to
/// cancellation in float). The discriminant is a (r^2 - |l|^2), l the offset of the centre from
/// the line (Haines et al., Ray Tracing Gems ch. 7), and the entry c / (-b + sqrt(disc)) (no
/// cancellation), lowered by the padding over |d|.
template <class S> inline std::optional<S> ray_sphere_entry(const Vec3<S>& o, const Vec3<S>& d, const Sphere<S>& s, S t_max) {
  constexpr S eps = std::numeric_limits<S>::epsilon();
  const Vec3<S> m = o - s.center;
  const S pad = S(16) * eps * (o.cwiseAbs().sum() + s.center.cwiseAbs().sum());
  const S r = s.radius * (S(1) + S(8) * eps) + pad;
  const S c = m.squaredNorm() - r * r;
  if (c <= S(0)) return S(0);  // origin inside
  const S a = d.squaredNorm(), b = m.dot(d);
  if (b >= S(0) || a == S(0)) return std::nullopt;
  const Vec3<S> l = m - (b / a) * d;
  const S h2 = r * r - l.squaredNorm();
  if (h2 < S(0)) return std::nullopt;
  const S t = c / (std::sqrt(a * h2) - b) * (S(1) - S(8) * eps) - pad / std::sqrt(a);
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

/// Entry of a ray into an oriented box (inflated by `margin`), for OBB trees. The key is the entry
/// into the box's axis-aligned hull (geometry/obb.hpp, bounding_aabb), by ray_box_entry: the hull
/// holds every triangle's box, so the key is never above the entry into any of them, and the
/// pruning is exact as in box trees (ray_mesh_triangle_hit). The oriented box itself only rejects:
/// the node is skipped when the ray's line misses it (line_meets_obb, conservative). Not the
/// segment: a triangle hit by a ray lying in its plane to rounding gets a t anywhere in the
/// triangle's depth range, maybe before the ray enters the box, while the line, which the
/// watertight test found crossing the triangle up to rounding, still meets the box.
template <class S>
inline std::optional<S> ray_bv_entry(const Vec3<S>& o, const Vec3<S>& d, const Vec3<S>& inv_d, const Obb<S>& b, S t_max,
                                     S margin = S(0)) {
  const std::optional<S> t = ray_bv_entry(o, d, inv_d, bounding_aabb(b), t_max, margin);
  if (!t || !line_meets_obb(o, d, b, margin)) return std::nullopt;
  return t;
}

/// Conservative box-versus-BV prefilter (false only when they are certainly disjoint).
template <class S> inline bool may_overlap(const Aabb<S>& seg, const Aabb<S>& b) {
  return (seg.min.array() <= b.max.array()).all() && (b.min.array() <= seg.max.array()).all();
}
template <class S> inline bool may_overlap(const Aabb<S>& seg, const Sphere<S>& s) {
  const Vec3<S> q = s.center.cwiseMax(seg.min).cwiseMin(seg.max);
  return (q - s.center).squaredNorm() <= s.radius * s.radius * (S(1) + S(8) * std::numeric_limits<S>::epsilon());
}
template <class S> inline bool may_overlap(const Aabb<S>& seg, const Obb<S>& b) { return may_overlap(seg, bounding_aabb(b)); }

template <class S> inline Vec3<S> safe_inverse(const Vec3<S>& d) {
  return Vec3<S>(S(1) / d[0], S(1) / d[1], S(1) / d[2]);  // +-inf for zero components
}

/// An axis-aligned box holding the sphere `s` (centre c, radius r), for a band bound
/// (bound_band_by_tree): each side moved out by e = (|c_i| + r) 2^-16, far more than the two
/// roundings of fl(fl(c_i - r) - e) (at most 3u (|c_i| + r), u <= 2^-24), so the computed corners
/// lie outside c -+ r. An empty sphere (a negative or NaN radius) gives an empty box.
template <class S> inline Aabb<S> sphere_band_box(const Sphere<S>& s) {
  if (!(s.radius >= S(0))) return Aabb<S>();
  const Vec3<S> e = (s.center.cwiseAbs().array() + s.radius) * S(0x1p-16);
  return Aabb<S>((s.center.array() - s.radius) - e.array(), (s.center.array() + s.radius) + e.array());
}

/// Sets pr's band bound (PreparedRay::band) for the triangles of `mesh` in its own frame (pr's ray
/// in that frame), from a box holding every triangle: a box tree's root box, a box around a sphere
/// tree's root sphere (sphere_band_box: the sphere holds its triangles' vertices). OBB trees (and
/// an empty tree) keep +infinity, each triangle's own band: their casts test few triangles, and
/// the bound's set-up cost more than it saved (docs/rays-history.md, thirty-first step).
template <class BV, class S> inline void bound_band_by_tree(PreparedRay<S>& pr, const MeshBvh<BV>& mesh) {
  if (mesh.tree().nodes.empty()) return;
  const BV& root = mesh.tree().nodes.front().bv;
  if constexpr (std::is_same_v<BV, Aabb<S>>) {
    pr.bound_band(root.min, root.max);
  } else if constexpr (std::is_same_v<BV, Sphere<S>>) {
    const Aabb<S> box = sphere_band_box(root);
    pr.bound_band(box.min, box.max);
  } else {
    (void)pr, (void)root;
  }
}

/// ray_mesh_triangle_hit for one triangle, the inverse direction computed here (brute-force loops).
template <class S> inline std::optional<RayTriangleHit<S>> ray_mesh_triangle_hit(const PreparedRay<S>& pr, const Triangle<S>& tri) {
  return ray_mesh_triangle_hit(pr, safe_inverse(pr.ray.direction), tri);
}

}  // namespace detail

namespace detail {

/// The first-hit cast shared by both tree layouts: the ray in the mesh's frame, the best hit so
/// far, and the triangle visitor; the walks (the mesh's own tree, or a CompactBvh) add the node
/// tests.
template <class BV>
struct FirstHitCast {
  using S = typename BvTraits<BV>::Scalar;
  const MeshBvh<BV>& mesh;
  RayMeshStats* stats;
  Vec3<S> o, d, inv;
  PreparedRay<S> pr;
  S best;
  S limit;  ///< bound(), updated with best
  std::int32_t best_leaf = -1;
  Vec3<S> best_bary = Vec3<S>::Zero();
  bool finite = false;  ///< a finite ray whose own box `seg` was asked for (it rejects most nodes before the slab test)
  Aabb<S> seg;

  FirstHitCast(const MeshBvh<BV>& m, const Ray<S>& ray, const RigidTransform<S>& pose, RayMeshStats* st, bool segment_box)
      : mesh(m),
        stats(st),
        o(pose.R.transpose() * (ray.origin - pose.t)),
        d(pose.R.transpose() * ray.direction),
        best(ray.t_max),
        limit(ray.t_max) {
    inv = detail::safe_inverse(d);
    pr = PreparedRay<S>(Ray<S>(o, d, ray.t_max));
    bound_band_by_tree(pr, m);
    finite = segment_box && ray.t_max < std::numeric_limits<S>::infinity();
    if (finite) {
      const Vec3<S> e = o + ray.t_max * d;
      const S pad = S(4) * std::numeric_limits<S>::epsilon() * (o.cwiseAbs().maxCoeff() + e.cwiseAbs().maxCoeff());
      seg = Aabb<S>(o.cwiseMin(e).array() - pad, o.cwiseMax(e).array() + pad);
    }
  }
  /// False when nothing can be hit (zero direction, negative t_max).
  bool valid() const { return d.squaredNorm() != S(0) && best >= S(0); }
  /// The largest node entry still worth entering: best before a hit. Once a hit is found only a
  /// strictly earlier one replaces it. In a box tree a node's computed entry is a lower bound of
  /// its triangles' t (exact, not up to rounding: see ray_mesh_triangle_hit), so nodes entered at
  /// best itself are pruned too (else a mesh of coincident triangles, all hit at the same t, had
  /// every node and triangle visited). Likewise in an OBB tree, whose keys are its hulls' entries. A sphere's computed entry is a lower bound up to its own
  /// rounding only (a triangle's vertex can lie on the sphere), and the sphere is entered before
  /// its triangles anyway: sphere trees prune only nodes entered strictly after best.
  S bound() const { return limit; }
  bool visit(std::int32_t k) {
    if (mesh.repeats_previous(k)) return true;  // the triangle just tested, again: the same answer
    if (stats) ++stats->triangle_tests;
    pr.ray.t_max = best;
    const auto h = detail::ray_mesh_triangle_hit(pr, inv, mesh.triangle(k));
    if (h && (best_leaf < 0 || h->t < best)) {
      best = h->t;
      best_leaf = k;
      best_bary = Vec3<S>(h->u, h->v, h->w);
      if constexpr (exact_query_keys<BV>)
        limit = next_down(best);
      else
        limit = best;
    }
    return true;
  }
  std::optional<RayMeshHit<S>> result(const Ray<S>& ray, const RigidTransform<S>& pose) const {
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
};

}  // namespace detail

namespace detail {

/// The checks of the public ray casts: a valid ray (validate_ray), a rigid pose (validate_pose)
/// and a start node of the mesh's tree.
template <class BV>
void validate_ray_cast(const MeshBvh<BV>& mesh, const Ray<typename BvTraits<BV>::Scalar>& ray,
                       const RigidTransform<typename BvTraits<BV>::Scalar>& pose, std::int32_t start_node, const char* where) {
  validate_ray(ray, where);
  validate_pose(pose, where);
  validate_in_range<std::int64_t>(start_node, 0, static_cast<std::int64_t>(mesh.tree().nodes.size()) - 1, where, "start_node");
}

/// ray_mesh_first_hit without the argument checks (callers that validated them once); the
/// direction's largest component must be at least CoordinateRange::min_scale (callers with
/// unvalidated rays, a particle's leg, scale it first: detail::cast_short_ray, geometry/ray.hpp).
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit_unchecked(const MeshBvh<BV>& mesh,
                                                                                      const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                                      const RigidTransform<typename BvTraits<BV>::Scalar>& pose,
                                                                                      RayMeshStats* stats, std::int32_t start_node) {
  detail::FirstHitCast<BV> c(mesh, ray, pose, stats, true);
  if (!c.valid()) return std::nullopt;
  traverse_nearest(
      mesh.tree(),
      [&](const BV& bv) {
        if (stats) ++stats->node_tests;
        using R = std::optional<typename BvTraits<BV>::Scalar>;
        if (c.finite && !detail::may_overlap(c.seg, bv)) return R();
        return detail::ray_bv_entry(c.o, c.d, c.inv, bv, c.best);
      },
      [&]() { return c.bound(); }, [&](std::int32_t k) { return c.visit(k); }, start_node);
  return c.result(ray, pose);
}

/// ray_mesh_first_hit through a CompactBvh without the argument checks.
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit_unchecked(const MeshBvh<BV>& mesh, const CompactBvh& fast,
                                                                                      const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                                      const RigidTransform<typename BvTraits<BV>::Scalar>& pose,
                                                                                      RayMeshStats* stats, std::int32_t start_node) {
  using S = typename BvTraits<BV>::Scalar;
  assert(fast.num_primitives() == static_cast<std::size_t>(mesh.num_triangles()));
  detail::FirstHitCast<BV> c(mesh, ray, pose, stats, false);
  if (!c.valid()) return std::nullopt;
  // both siblings at once: by the axes' signs when 1 / d is finite on every axis, which gives
  // ray_box_entry's values; else one by one, on the exact float boxes (float -> S is exact)
  const detail::PairSlab<S> slab(c.o, c.inv);
  auto by_sign = [&](const CompactBvhPair& p, S(&keys)[2]) { slab.keys(p, c.best, keys); };
  auto one_by_one = [&](const CompactBvhPair& p, S(&keys)[2]) {
    for (int side = 0; side < 2; ++side) {
      const auto t = detail::ray_box_entry(c.o, c.inv, Aabb<S>(p.child(side).box().template cast<S>()), c.best);
      keys[side] = t ? *t : std::numeric_limits<S>::quiet_NaN();
    }
  };
  auto bound = [&]() { return c.bound(); };
  auto visit = [&](std::int32_t k) { return c.visit(k); };
  const std::int32_t start = fast.from_source(start_node);
  const std::size_t pairs = std::isfinite(c.inv[0]) && std::isfinite(c.inv[1]) && std::isfinite(c.inv[2])
                                ? traverse_nearest_pairs<S>(fast, by_sign, bound, visit, start)
                                : traverse_nearest_pairs<S>(fast, one_by_one, bound, visit, start);
  if (stats) stats->node_tests += 2 * pairs;
  return c.result(ray, pose);
}

}  // namespace detail

/// First hit of the ray origin + t * direction, t in [0, ray.t_max], against the mesh placed in
/// the world by `pose`. A segment p -> q is the ray (p, q - p, 1). Returns nothing when the ray
/// misses. Ties between triangles at the same t (a shared edge) return one of them. Cost
/// O(log n) for rays that pass near few triangles.
///
/// `start_node` (the root by default) restricts the search to one subtree of mesh.tree(): the
/// caller guarantees that every triangle the ray can hit lies in it (e.g. DistanceGrid::start_node).
///
/// Throws InvalidInput for a non-finite origin or direction, a zero direction, t_max NaN or
/// negative (validate_ray), a pose that is not rigid (validate_pose), or a start node outside
/// the tree.
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit(const MeshBvh<BV>& mesh,
                                                                            const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                            const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {},
                                                                            RayMeshStats* stats = nullptr, std::int32_t start_node = 0) {
  detail::validate_ray_cast(mesh, ray, pose, start_node, "ray_mesh_first_hit");
  return detail::ray_mesh_first_hit_unchecked(mesh, ray, pose, stats, start_node);
}

/// The same first hit, walking `fast`, a CompactBvh of mesh.tree() (bvh/compact_bvh.hpp), from
/// the node standing for `start_node` (a node of mesh.tree(), with the same guarantee): the same
/// t (the triangle may differ only among triangles hit at exactly the same t), faster when the
/// mesh's tree does not fit in cache. `fast` must be built from mesh.tree() after its last change
/// (InvalidInput when its primitive count differs from the mesh's); the other checks are those of
/// the first overload.
template <class BV>
std::optional<RayMeshHit<typename BvTraits<BV>::Scalar>> ray_mesh_first_hit(const MeshBvh<BV>& mesh, const CompactBvh& fast,
                                                                            const Ray<typename BvTraits<BV>::Scalar>& ray,
                                                                            const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {},
                                                                            RayMeshStats* stats = nullptr, std::int32_t start_node = 0) {
  detail::validate_ray_cast(mesh, ray, pose, start_node, "ray_mesh_first_hit");
  require(fast.num_primitives() == static_cast<std::size_t>(mesh.num_triangles()), "ray_mesh_first_hit",
          "the CompactBvh `fast` was not built from this mesh's tree (primitive counts differ)");
  return detail::ray_mesh_first_hit_unchecked(mesh, fast, ray, pose, stats, start_node);
}

/// True when the ray hits any triangle for t in [0, ray.t_max] (same rules and checks as the
/// first hit). Depth-first, stops at the first triangle found: cheaper than the first hit for
/// visibility and tunnelling checks.
template <class BV>
bool ray_mesh_any_hit(const MeshBvh<BV>& mesh, const Ray<typename BvTraits<BV>::Scalar>& ray,
                      const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {}) {
  using S = typename BvTraits<BV>::Scalar;
  detail::validate_ray_cast(mesh, ray, pose, 0, "ray_mesh_any_hit");
  const Vec3<S> o = pose.R.transpose() * (ray.origin - pose.t);
  const Vec3<S> d = pose.R.transpose() * ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return false;
  PreparedRay<S> pr(Ray<S>(o, d, ray.t_max));
  detail::bound_band_by_tree(pr, mesh);
  const Vec3<S> inv = detail::safe_inverse(d);
  bool found = false;
  traverse(
      mesh.tree(), [&](const BV& bv) { return detail::ray_bv_entry(o, d, inv, bv, ray.t_max).has_value(); },
      [&](std::int32_t k) {
        if (mesh.repeats_previous(k)) return true;  // missed like the triangle before it
        found = detail::ray_mesh_triangle_hit(pr, inv, mesh.triangle(k)).has_value();
        return !found;
      });
  return found;
}

}  // namespace impact
