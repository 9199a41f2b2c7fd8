// SPDX-License-Identifier: MIT
/// \file
/// First-hit ray (or segment) casts through a WideBvh (bvh/wide_bvh.hpp): nearest-first, the
/// four children of a node tested at once (AVX when compiled with it, else SSE2, else a scalar
/// loop; all three compute the same IEEE operations in the same order, so they give the same
/// answers bit for bit), the nearest entered child descended at once and the others kept on a
/// stack with their entry parameter.
///
/// Numerical contract: that of query/ray_mesh.hpp. Every crossing is decided by the same
/// watertight narrow-phase rule on the mesh's own coordinates (detail::ray_mesh_triangle_hit: a
/// ray through a shared edge or vertex of a closed mesh hits a triangle around it, never none;
/// the t = 0 tie rule). The node tests are conservative: the slab test runs in S on the float
/// boxes (rounded outward, exact in S), and the exit parameter is padded (PBRT's robust slab
/// test), so no triangle the ray crosses is pruned by rounding. Ties as in ray_mesh_first_hit:
/// after a hit, nodes entered at exactly its t are pruned; a triangle's t is never below the
/// entry into its own box (detail::ray_mesh_triangle_hit), which the float boxes hold, and the
/// slab test is monotone in the box, so that pruning is exact: the t returned is the smallest of a
/// loop over every triangle.
#pragma once

#include "impact/bvh/traversal_stack.hpp"
#include "impact/bvh/wide_bvh.hpp"
#include "impact/query/ray_mesh.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace impact {

namespace detail {

/// The slab test of a ray against the four children of a WideBvhNode, for a ray whose inverse
/// direction is finite on every axis: the near and far planes are picked once per ray by the
/// signs of the axes. Set up once per ray.
template <class S> class WideSlab {
 public:
  WideSlab(const Vec3<S>& o, const Vec3<S>& inv) {
    for (int i = 0; i < 3; ++i) {
      near_[i] = 2 * i + (inv[i] < S(0) ? 1 : 0);
      far_[i] = 2 * i + (inv[i] < S(0) ? 0 : 1);
      o_[i] = o[i];
      inv_[i] = inv[i];
    }
  }
  /// keys[c]: the entry parameter into child c's box, or NaN when the ray misses it or enters
  /// it after t_max. Empty slots give NaN, or +infinity for an infinite float ray (their planes
  /// overflow): the caller skips them by their count. `use_simd` false forces the scalar loop.
  void keys(const WideBvhNode& n, S t_max, S (&keys)[4], bool use_simd = true) const {
    constexpr S pad = S(4) * std::numeric_limits<S>::epsilon();  // robust slab test (PBRT 3.9.2)
    constexpr S nan = std::numeric_limits<S>::quiet_NaN();
    if constexpr (std::is_same_v<S, double>) {
      if (use_simd) {
#if defined(__AVX__)
        const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
        const __m256d vpad = _mm256_set1_pd(pad);
        __m256d t0 = _mm256_setzero_pd(), t1 = _mm256_set1_pd(t_max);
        for (int i = 0; i < 3; ++i) {
          const __m256d o = _mm256_set1_pd(o_[i]), inv = _mm256_set1_pd(inv_[i]);
          const __m256d a = _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(_mm_load_ps(n.bounds[near_[i]])), o), inv);
          __m256d b = _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(_mm_load_ps(n.bounds[far_[i]])), o), inv);
          b = _mm256_add_pd(b, _mm256_mul_pd(_mm256_and_pd(b, abs_mask), vpad));
          t0 = _mm256_max_pd(a, t0);
          t1 = _mm256_min_pd(b, t1);
        }
        const __m256d hit = _mm256_cmp_pd(t0, t1, _CMP_LE_OQ);
        _mm256_storeu_pd(keys, _mm256_blendv_pd(_mm256_set1_pd(nan), t0, hit));
        return;
#elif defined(__SSE2__)
        const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
        const __m128d vpad = _mm_set1_pd(pad);
        for (int h = 0; h < 2; ++h) {  // children 2h and 2h + 1
          __m128d t0 = _mm_setzero_pd(), t1 = _mm_set1_pd(t_max);
          for (int i = 0; i < 3; ++i) {
            const __m128d o = _mm_set1_pd(o_[i]), inv = _mm_set1_pd(inv_[i]);
            const __m128d a = _mm_mul_pd(_mm_sub_pd(load2(n.bounds[near_[i]] + 2 * h), o), inv);
            __m128d b = _mm_mul_pd(_mm_sub_pd(load2(n.bounds[far_[i]] + 2 * h), o), inv);
            b = _mm_add_pd(b, _mm_mul_pd(_mm_and_pd(b, abs_mask), vpad));
            t0 = _mm_max_pd(a, t0);
            t1 = _mm_min_pd(b, t1);
          }
          const __m128d hit = _mm_cmple_pd(t0, t1);
          _mm_storeu_pd(keys + 2 * h, _mm_or_pd(_mm_and_pd(hit, t0), _mm_andnot_pd(hit, _mm_set1_pd(nan))));
        }
        return;
#endif
      }
    }
    S t0[4] = {S(0), S(0), S(0), S(0)}, t1[4] = {t_max, t_max, t_max, t_max};
    for (int i = 0; i < 3; ++i)
      for (int c = 0; c < 4; ++c) {
        const S a = (S(n.bounds[near_[i]][c]) - o_[i]) * inv_[i];
        S b = (S(n.bounds[far_[i]][c]) - o_[i]) * inv_[i];
        b += std::abs(b) * pad;
        t0[c] = a > t0[c] ? a : t0[c];  // maxpd / minpd: the second operand unless the first wins
        t1[c] = b < t1[c] ? b : t1[c];
      }
    for (int c = 0; c < 4; ++c) keys[c] = t0[c] <= t1[c] ? t0[c] : nan;
  }

 private:
#if defined(__SSE2__)
  static __m128d load2(const float* f) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f)))); }
#endif
  int near_[3], far_[3];
  S o_[3], inv_[3];
};

/// ray_mesh_first_hit through a WideBvh without the argument checks; `pose` null for the mesh's
/// own frame. `use_simd` false forces the scalar node test (for the tests that compare the two).
template <class S>
std::optional<RayMeshHit<S>> ray_wide_first_hit_unchecked(const WideBvh<S>& wide, const Ray<S>& ray, const RigidTransform<S>* pose,
                                                          RayMeshStats* stats, bool use_simd = true) {
  if (wide.empty()) return std::nullopt;
  const Vec3<S> o = pose ? Vec3<S>(pose->R.transpose() * (ray.origin - pose->t)) : ray.origin;
  const Vec3<S> d = pose ? Vec3<S>(pose->R.transpose() * ray.direction) : ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return std::nullopt;
  const Vec3<S> inv = safe_inverse(d);
  PreparedRay<S> pr(Ray<S>(o, d, ray.t_max));
  S best = ray.t_max;
  std::int32_t best_k = -1;
  Vec3<S> best_bary = Vec3<S>::Zero();
  // after a hit only a strictly earlier one replaces it, so nodes entered at best are pruned
  S limit = best;
  auto bound = [&]() { return limit; };
  const bool finite = std::isfinite(inv[0]) && std::isfinite(inv[1]) && std::isfinite(inv[2]);
  const WideSlab<S> slab(o, inv);
  auto keys_of = [&](const WideBvhNode& n, S (&keys)[4]) {
    if (finite) {
      slab.keys(n, best, keys, use_simd);
      return;
    }
    for (int c = 0; c < 4; ++c) {  // a zero direction component: the box test that handles it
      const Aabb<S> box(Vec3<S>(S(n.bounds[0][c]), S(n.bounds[2][c]), S(n.bounds[4][c])),
                        Vec3<S>(S(n.bounds[1][c]), S(n.bounds[3][c]), S(n.bounds[5][c])));
      const auto t = n.count[c] < 0 ? std::nullopt : ray_box_entry(o, inv, box, best);
      keys[c] = t ? *t : std::numeric_limits<S>::quiet_NaN();
    }
  };
  struct Entry {
    S key;
    std::int32_t first, count;
  };
  TraversalStack<Entry, 128> stack;
  const WideBvhNode* nodes = wide.nodes().data();
  std::int32_t first = 0, count = 0;  // the root: an inner node
  std::size_t node_tests = 0, triangle_tests = 0;
  for (;;) {
    if (count > 0) {
      for (std::int32_t k = first; k < first + count; ++k) {
        if (wide.repeats_previous(k)) continue;  // the triangle just tested, again (coincident copies)
        ++triangle_tests;
        pr.ray.t_max = best;
        const auto h = ray_mesh_triangle_hit(pr, inv, wide.triangle(k));
        if (h && (best_k < 0 || h->t < best)) {
          best = h->t;
          best_k = k;
          best_bary = Vec3<S>(h->u, h->v, h->w);
          limit = std::nextafter(best, -std::numeric_limits<S>::infinity());
        }
      }
    } else {
      const WideBvhNode& n = nodes[first];
      S keys[4];
      keys_of(n, keys);
      node_tests += 4;
      const S b = bound();
      // the entered children, nearest first (insertion sort of at most four)
      int order[4], m = 0;
      for (int c = 0; c < 4; ++c) {
        if (!(keys[c] <= b) || n.count[c] < 0) continue;
        int j = m++;
        while (j > 0 && keys[order[j - 1]] > keys[c]) {
          order[j] = order[j - 1];
          --j;
        }
        order[j] = c;
      }
      if (m > 0) {
        for (int j = m - 1; j > 0; --j) stack.push({keys[order[j]], n.first[order[j]], n.count[order[j]]});
        first = n.first[order[0]];
        count = n.count[order[0]];
        continue;
      }
    }
    // the nearest pending child still below the bound
    bool found = false;
    while (!stack.empty()) {
      const Entry e = stack.pop();
      if (e.key <= bound()) {
        first = e.first;
        count = e.count;
        found = true;
        break;
      }
    }
    if (!found) break;
  }
  if (stats) {
    stats->node_tests += node_tests;
    stats->triangle_tests += triangle_tests;
  }
  if (best_k < 0) return std::nullopt;
  RayMeshHit<S> hit;
  hit.t = best;
  hit.leaf_index = best_k;
  hit.triangle = wide.triangle_id(best_k);
  hit.barycentric = best_bary;
  hit.point = ray.origin + best * ray.direction;
  const Vec3<S> nrm = wide.triangle(best_k).normal();
  hit.normal = pose ? Vec3<S>(pose->R * nrm) : nrm;
  hit.front_face = d.dot(nrm) < S(0);
  return hit;
}

}  // namespace detail

/// First hit of the ray origin + t * direction, t in [0, ray.t_max], against the mesh of `wide`
/// placed in the world by `pose`: the contract of ray_mesh_first_hit (query/ray_mesh.hpp), the
/// same t, through the 4-wide tree. RayMeshHit::leaf_index is the leaf-order position in `wide`
/// (WideBvh::triangle). Throws InvalidInput for a non-finite origin or direction, a zero
/// direction, t_max NaN or negative (validate_ray), or a pose that is not rigid (validate_pose).
template <class S>
std::optional<RayMeshHit<S>> ray_mesh_first_hit(const WideBvh<S>& wide, const Ray<S>& ray, const RigidTransform<S>& pose,
                                                RayMeshStats* stats = nullptr) {
  validate_ray(ray, "ray_mesh_first_hit");
  validate_pose(pose, "ray_mesh_first_hit");
  return detail::ray_wide_first_hit_unchecked(wide, ray, &pose, stats);
}

/// The same first hit with the ray in the mesh's own frame (no pose to check or apply).
template <class S> std::optional<RayMeshHit<S>> ray_mesh_first_hit(const WideBvh<S>& wide, const Ray<S>& ray) {
  validate_ray(ray, "ray_mesh_first_hit");
  return detail::ray_wide_first_hit_unchecked(wide, ray, static_cast<const RigidTransform<S>*>(nullptr), nullptr);
}

}  // namespace impact
