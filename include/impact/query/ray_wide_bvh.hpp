// SPDX-License-Identifier: MIT
/// \file
/// First-hit ray (or segment) casts through a WideBvh (bvh/wide_bvh.hpp): nearest-first, the
/// four children of a node tested at once (SSE when compiled with it, else a scalar loop of the
/// same IEEE operations in the same order: the same answers bit for bit), the nearest entered
/// child descended at once and the others kept on a stack with their entry parameter. The node
/// test runs in float (WideFloatSlab: the boxes are floats; its entry is lowered and its exit
/// raised by a bound on its rounding, so it enters every box the double slab test WideSlab enters,
/// never later), or in S through WideSlab for rays it cannot take (magnitudes beyond 2^60, a zero
/// direction component). The triangles of a leaf stored as floats go four at a time through a
/// certified float filter (LeafFilter) that skips only triangles the watertight test is certain
/// to reject; the others, and every triangle of a tree stored in S, go to the test itself.
///
/// Numerical contract: that of query/ray_mesh.hpp. Every crossing is decided by the same
/// watertight narrow-phase rule on the mesh's own coordinates (detail::ray_mesh_triangle_hit: a
/// ray through a shared edge or vertex of a closed mesh hits a triangle around it, never none;
/// the t = 0 tie rule). The node tests are conservative: the double slab test runs in S on the
/// float boxes (rounded outward, exact in S) with its exit parameter padded (PBRT's robust slab
/// test), and the float one widens that, so no triangle the ray crosses is pruned by rounding.
/// Ties as in ray_mesh_first_hit: after a hit, nodes entered at or after its t are pruned; a
/// triangle's t is never below the entry into its own box (detail::ray_mesh_triangle_hit), which
/// the float boxes hold, the slab test is monotone in the box and the float key is never above
/// it, so that pruning is exact: the t returned is the smallest of a loop over every triangle
/// (which triangle among equal ones depends on the visiting order).
#pragma once

#include "impact/bvh/traversal_stack.hpp"
#include "impact/bvh/wide_bvh.hpp"
#include "impact/query/ray_mesh.hpp"

#include <algorithm>
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

/// The smallest float >= x (x not NaN; +infinity above the float range), without libm.
inline float float_round_up(double x) {
  const float f = static_cast<float>(x);
  if (!(double(f) < x)) return f;
  // the next float up: one more unit in the last place of |f| (f >= 0) or one less (f < 0)
  if (f == 0.0f) return std::numeric_limits<float>::denorm_min();
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  b = f > 0.0f ? b + 1 : b - 1;
  float g;
  std::memcpy(&g, &b, sizeof g);
  return g;
}
/// The largest float <= x (x not NaN; -infinity below the float range), without libm.
inline float float_round_down(double x) { return -float_round_up(-x); }

/// The slab test of a ray against the four children of a WideBvhNode in float: a conservative
/// version of WideSlab's keys (in S on the same float boxes) at a quarter of the work, for a ray
/// whose inverse direction is in [2^-60, 2^60] in magnitude, whose origin and the tree's
/// coordinates are at most 2^60 and whose origin is within 2^40 / |1 / d| of a float on every
/// axis (`usable`; no float overflow, no underflow to zero, no NaN).
///
/// The origin and the inverse direction are rounded to float once per ray; the boxes are floats.
/// A plane's parameter (b - o) / d computed so differs from WideSlab's by at most 4 u |t| + E
/// (u = 2^-24: the float subtraction, the rounding of 1 / d and the product, and WideSlab's own
/// rounding and exit padding; E = max over the axes of |o - float(o)| |1 / d|, zero when the
/// origin is a float, and 2^-100 for underflow). The entry t0 = max(0, near planes) is therefore
/// lowered to lo = t0 (1 - 2^-19) - e and the exit t1 = min(float t_max rounded up, far planes)
/// raised to hi = t1 (1 + 2^-19) + e, with e = E (1 + 2^-16) + 2^-100 rounded up, each a product
/// and a sum in float. Then (see the proof in the tests' comment, FloatSlabIsConservative):
///  - lo <= WideSlab's entry (32 u of slack against 4 u, after the float roundings of the two
///    operations), so pruning a child whose lo exceeds the best t stays exact;
///  - when WideSlab enters a box (its entry <= its exit, the entry >= 0), lo <= hi: for t1 >= 0
///    hi is above WideSlab's exit; for t1 < 0 (WideSlab's exit can still be >= 0 only when
///    |t1| <= E (1 + 8 u)), lo <= t0 - e (1 - u) and hi >= e (1 - u) - |t1| (1 + 34 u), and the
///    margin 2^-16 of e covers the rest.
/// Empty slots (lower plane FLT_MAX, upper -FLT_MAX) give lo >= 2^67 (1 - 2^-19) - 2^41 > 0 > hi
/// on every axis and are never entered (no count check). SSE when compiled with it, else a
/// scalar loop of the same IEEE operations in the same order (the same keys and mask bit for bit).
template <class S> class WideFloatSlab {
 public:
  WideFloatSlab(const Vec3<S>& o, const Vec3<S>& inv, S coordinate_bound) {
#if defined(__SSE2__)
    if constexpr (std::is_same_v<S, double>) {
      // two axes a register: the checks, the rounding to float and its error, the plane offsets
      const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
      const __m128d big = _mm_set1_pd(0x1p60), small = _mm_set1_pd(0x1p-60);
      const __m128d o01 = _mm_loadu_pd(o.data()), o22 = _mm_set1_pd(o[2]);
      const __m128d i01 = _mm_loadu_pd(inv.data()), i22 = _mm_set1_pd(inv[2]);
      const __m128d ai01 = _mm_and_pd(i01, abs_mask), ai22 = _mm_and_pd(i22, abs_mask);
      const __m128d in01 = _mm_and_pd(_mm_and_pd(_mm_cmple_pd(_mm_and_pd(o01, abs_mask), big), _mm_cmple_pd(ai01, big)), _mm_cmpge_pd(ai01, small));
      const __m128d in22 = _mm_and_pd(_mm_and_pd(_mm_cmple_pd(_mm_and_pd(o22, abs_mask), big), _mm_cmple_pd(ai22, big)), _mm_cmpge_pd(ai22, small));
      const __m128 of01 = _mm_cvtpd_ps(o01), of22 = _mm_cvtpd_ps(o22), if01 = _mm_cvtpd_ps(i01), if22 = _mm_cvtpd_ps(i22);
      const __m128d e01 = _mm_mul_pd(_mm_and_pd(_mm_sub_pd(o01, _mm_cvtps_pd(of01)), abs_mask), ai01);
      const __m128d e22 = _mm_mul_pd(_mm_and_pd(_mm_sub_pd(o22, _mm_cvtps_pd(of22)), abs_mask), ai22);
      const __m128d e2 = _mm_max_pd(e01, e22);
      const double e = _mm_cvtsd_f64(_mm_max_sd(e2, _mm_unpackhi_pd(e2, e2)));  // (NaN only when a check fails)
      const int sign = _mm_movemask_pd(i01) | (_mm_movemask_pd(i22) & 1) << 2;
      usable_ = (_mm_movemask_pd(_mm_and_pd(in01, in22)) == 3) & (coordinate_bound <= S(0x1p60)) & (e <= 0x1p40);
      for (int i = 0; i < 3; ++i) {
        near_[i] = static_cast<int>(sizeof(float[4])) * (2 * i + ((sign >> i) & 1));  // byte offsets of the planes
        far_[i] = near_[i] ^ static_cast<int>(sizeof(float[4]));
      }
      vo_[0] = _mm_shuffle_ps(of01, of01, 0x00), vo_[1] = _mm_shuffle_ps(of01, of01, 0x55), vo_[2] = _mm_shuffle_ps(of22, of22, 0x00);
      vinv_[0] = _mm_shuffle_ps(if01, if01, 0x00), vinv_[1] = _mm_shuffle_ps(if01, if01, 0x55), vinv_[2] = _mm_shuffle_ps(if22, if22, 0x00);
      e_ = usable_ ? float_round_up(e * (1.0 + 0x1p-16) + 0x1p-100) : 0.0f;
      ve_ = _mm_set1_ps(e_);
      return;
    }
#endif
    bool ok = coordinate_bound <= S(0x1p60);
    double e = 0;
    for (int i = 0; i < 3; ++i) {
      const S a = std::abs(inv[i]);
      ok = ok & (std::abs(o[i]) <= S(0x1p60)) & (a <= S(0x1p60)) & (a >= S(0x1p-60));  // false for NaN
      const bool neg = inv[i] < S(0);
      near_[i] = static_cast<int>(sizeof(float[4])) * (2 * i + (neg ? 1 : 0));  // byte offsets of the planes
      far_[i] = near_[i] ^ static_cast<int>(sizeof(float[4]));
      const float of = static_cast<float>(o[i]), invf = static_cast<float>(inv[i]);
#if defined(__SSE2__)
      vo_[i] = _mm_set1_ps(of), vinv_[i] = _mm_set1_ps(invf);
#else
      o_[i] = of, inv_[i] = invf;
#endif
      e = std::max(e, std::abs(double(o[i]) - double(of)) * double(a));
    }
    usable_ = ok && e <= 0x1p40;
    e_ = usable_ ? float_round_up(e * (1.0 + 0x1p-16) + 0x1p-100) : 0.0f;
#if defined(__SSE2__)
    ve_ = _mm_set1_ps(e_);
#endif
  }
  /// False when some magnitude is out of range (see the class comment): use WideSlab.
  bool usable() const { return usable_; }
  /// e: the absolute part of the keys' lowering (the relative part is 2^-19).
  float absolute_error() const { return e_; }
  static constexpr float kLow = 1.0f - 0x1p-19f, kHigh = 1.0f + 0x1p-19f;

  /// The children entered before `bound` (a float <= the cast's bound): bit c set when lo[c] <=
  /// hi[c] and lo[c] <= bound; keys[c] = lo[c] (the others anything); `t_max_up` a float >= t_max.
  int entered(const WideBvhNode& n, float t_max_up, float bound, float (&keys)[4], bool use_simd = true) const {
#if defined(__SSE2__)
    if (use_simd) {
      __m128 lo;
      const int m = entered(n, _mm_set1_ps(t_max_up), _mm_set1_ps(bound), lo);
      _mm_storeu_ps(keys, lo);
      return m;
    }
#endif
    return entered_scalar(n, t_max_up, bound, keys);
  }

#if defined(__SSE2__)
  /// entered() with the bounds broadcast and the keys left in a register.
  int entered(const WideBvhNode& n, __m128 t_max_up, __m128 bound, __m128& keys) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    __m128 t0 = _mm_setzero_ps(), t1 = t_max_up;
    for (int i = 0; i < 3; ++i) {
      const __m128 a = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(p + near_[i])), vo_[i]), vinv_[i]);
      const __m128 b = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(p + far_[i])), vo_[i]), vinv_[i]);
      t0 = _mm_max_ps(a, t0);
      t1 = _mm_min_ps(b, t1);
    }
    const __m128 lo = _mm_sub_ps(_mm_mul_ps(t0, _mm_set1_ps(kLow)), ve_);
    const __m128 hi = _mm_add_ps(_mm_mul_ps(t1, _mm_set1_ps(kHigh)), ve_);
    keys = lo;
    return _mm_movemask_ps(_mm_and_ps(_mm_cmple_ps(lo, hi), _mm_cmple_ps(lo, bound)));
  }
#endif

  /// entered() by a scalar loop of the same IEEE operations in the same order.
  int entered_scalar(const WideBvhNode& n, float t_max_up, float bound, float (&keys)[4]) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    float t0[4] = {0.0f, 0.0f, 0.0f, 0.0f}, t1[4] = {t_max_up, t_max_up, t_max_up, t_max_up};
    for (int i = 0; i < 3; ++i) {
      const float* near = reinterpret_cast<const float*>(p + near_[i]);
      const float* far = reinterpret_cast<const float*>(p + far_[i]);
      for (int c = 0; c < 4; ++c) {
        const float a = (near[c] - origin(i)) * inverse(i);
        const float b = (far[c] - origin(i)) * inverse(i);
        t0[c] = a > t0[c] ? a : t0[c];  // maxps / minps: the second operand unless the first wins
        t1[c] = b < t1[c] ? b : t1[c];
      }
    }
    int m = 0;
    for (int c = 0; c < 4; ++c) {
      const float lo = t0[c] * kLow - e_, hi = t1[c] * kHigh + e_;
      keys[c] = lo;
      m |= (lo <= hi && lo <= bound ? 1 : 0) << c;
    }
    return m;
  }
  /// The smallest float >= x (x >= 0, not NaN; +infinity above the float range).
  static float round_up(double x) { return float_round_up(x); }
  /// The largest float <= x (not NaN; -infinity below the float range).
  static float round_down(double x) { return float_round_down(x); }

 private:
#if defined(__SSE2__)
  float origin(int i) const { return _mm_cvtss_f32(vo_[i]); }
  float inverse(int i) const { return _mm_cvtss_f32(vinv_[i]); }
#else
  float origin(int i) const { return o_[i]; }
  float inverse(int i) const { return inv_[i]; }
#endif
  bool usable_ = false;
  int near_[3], far_[3];  // byte offsets of the near and far planes of each axis in a node
  float e_ = 0.0f;
#if defined(__SSE2__)
  __m128 vo_[3], vinv_[3], ve_;  // origin and inverse direction rounded to float, e, broadcast
#else
  float o_[3], inv_[3];
#endif
};

#if defined(__SSE2__)
/// A certified float filter of the watertight test over four leaf-order triangles at once (SSE),
/// for a WideBvh whose triangles are floats. The test (intersect_ray_triangle, in S, on the
/// triangle's own coordinates) rejects a triangle when two of its edge functions have opposite
/// strict signs, or when its hit parameter lies outside [0, t_max]. The filter computes the same
/// shear and edge functions in float (origin and shear rounded to float) together with a forward
/// bound on their distance to the values the test computes:
///  - a sheared coordinate p (x or y) of a vertex P - o: |p_float - p_test| <= 2 e_o + 8 u L + tiny,
///    where e_o bounds the origin's rounding to float, u = 2^-24, L = max |P - o| (componentwise,
///    in float) and tiny = 2^-120 covers underflow; the shear factors are in [-1, 1];
///  - an edge function e = x_c y_b - y_c x_b: |e_float - e_test| <= 2.1 (X_c d_b + X_b d_c + d_b d_c)
///    + 5 u X_b X_c + tiny, with X the larger |sheared coordinate| of a vertex and d its bound
///    (the test's own rounding, in double or in float, is within the slack of the constants);
///  - a sheared depth z = s_z (P_z - o_z): |z_float - z_test| <= |s_z| (e_o + 6 u max|P_z|) + tiny.
/// A triangle is skipped only when the test is certain to reject it: two edge functions beyond
/// their bounds with opposite signs, or (S = double) all three beyond twice their bounds with one
/// sign (the hit parameter is then a convex combination of the depths) and every depth beyond its
/// bound below 0 or above t_max (1 + 2^-20) (the test's rounding of its parameter and of t_max
/// times the determinant is within 2^-20; in float, products of tiny values could underflow, so
/// the float test's depths are left to the test). Every other triangle goes to the test itself, so the answers are
/// the test's, bit for bit; infinities and NaNs (overflow in float) compare false and keep the
/// triangle. Set up once per ray.
template <class S> class LeafFilter {
 public:
  LeafFilter() = default;  // set() before candidates()
  explicit LeafFilter(const PreparedRay<S>& pr) { set(pr); }
  void set(const PreparedRay<S>& pr) {
    k_[0] = pr.kx, k_[1] = pr.ky, k_[2] = pr.kz;
    float eo = 0.0f;
    for (int i = 0; i < 3; ++i) {
      const float f = static_cast<float>(pr.ray.origin[i]);
      o_[i] = _mm_set1_ps(f);
      eo = std::max(eo, round_up(std::abs(double(pr.ray.origin[i]) - double(f))));
    }
    sx_ = _mm_set1_ps(static_cast<float>(pr.sx));
    sy_ = _mm_set1_ps(static_cast<float>(pr.sy));
    const float sz = static_cast<float>(pr.sz);
    sz_ = _mm_set1_ps(sz);
    constexpr float u = 0x1p-24f, tiny = 0x1p-120f;
    d0_ = _mm_set1_ps(round_up(2.0 * double(eo) + double(tiny)));
    d1_ = _mm_set1_ps(8 * u);
    e0_ = _mm_set1_ps(2.1f);
    e1_ = _mm_set1_ps(5 * u);
    tiny_ = _mm_set1_ps(tiny);
    z0_ = _mm_set1_ps(round_up(double(std::abs(sz)) * double(eo) + double(tiny)));
    z1_ = _mm_set1_ps(std::abs(sz) * (6 * u));
  }

  /// Bit c set when the triangle at leaf-order position c of `p` (9 floats a triangle, readable
  /// 37 floats from p) may be hit by the ray with t_max = `t_max`: the test must decide it. Bits
  /// at and above `count` (<= 4) are clear.
  int candidates(const float* p, int count, S t_max) const {
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    __m128 px[3], py[3], pz[3], x[3], d[3];  // by vertex: sheared coordinates, their size, bound
    __m128 lz = _mm_setzero_ps();
    for (int v = 0; v < 3; ++v) {
      // rows (x, y, z, next) of vertex v of the four triangles, transposed to x, y, z by triangle
      const __m128 r0 = _mm_loadu_ps(p + 3 * v), r1 = _mm_loadu_ps(p + 9 + 3 * v);
      const __m128 r2 = _mm_loadu_ps(p + 18 + 3 * v), r3 = _mm_loadu_ps(p + 27 + 3 * v);
      const __m128 lo01 = _mm_unpacklo_ps(r0, r1), lo23 = _mm_unpacklo_ps(r2, r3);  // x0 x1 y0 y1, x2 x3 y2 y3
      const __m128 hi01 = _mm_unpackhi_ps(r0, r1), hi23 = _mm_unpackhi_ps(r2, r3);  // z0 z1 . ., z2 z3 . .
      __m128 c[3];
      c[0] = _mm_movelh_ps(lo01, lo23);
      c[1] = _mm_movehl_ps(lo23, lo01);
      c[2] = _mm_movelh_ps(hi01, hi23);
      const __m128 qx = _mm_sub_ps(c[k_[0]], o_[k_[0]]), qy = _mm_sub_ps(c[k_[1]], o_[k_[1]]), qz = _mm_sub_ps(c[k_[2]], o_[k_[2]]);
      px[v] = _mm_sub_ps(qx, _mm_mul_ps(sx_, qz));
      py[v] = _mm_sub_ps(qy, _mm_mul_ps(sy_, qz));
      pz[v] = _mm_mul_ps(sz_, qz);
      const __m128 aqz = _mm_and_ps(qz, abs_mask);
      const __m128 l = _mm_max_ps(_mm_max_ps(_mm_and_ps(qx, abs_mask), _mm_and_ps(qy, abs_mask)), aqz);
      d[v] = _mm_add_ps(d0_, _mm_mul_ps(d1_, l));
      x[v] = _mm_max_ps(_mm_and_ps(px[v], abs_mask), _mm_and_ps(py[v], abs_mask));
      lz = _mm_max_ps(lz, aqz);
    }
    // edge functions (the test's order: e_u of b and c, e_v of c and a, e_w of a and b)
    const __m128 eu = _mm_sub_ps(_mm_mul_ps(px[2], py[1]), _mm_mul_ps(py[2], px[1]));
    const __m128 ev = _mm_sub_ps(_mm_mul_ps(px[0], py[2]), _mm_mul_ps(py[0], px[2]));
    const __m128 ew = _mm_sub_ps(_mm_mul_ps(px[1], py[0]), _mm_mul_ps(py[1], px[0]));
    const __m128 bu = bound(x[1], d[1], x[2], d[2]), bv = bound(x[2], d[2], x[0], d[0]), bw = bound(x[0], d[0], x[1], d[1]);
    const __m128 pu = _mm_cmpgt_ps(eu, bu), pv = _mm_cmpgt_ps(ev, bv), pw = _mm_cmpgt_ps(ew, bw);
    const __m128 nu = _mm_cmplt_ps(_mm_add_ps(eu, bu), _mm_setzero_ps()), nv = _mm_cmplt_ps(_mm_add_ps(ev, bv), _mm_setzero_ps()),
                 nw = _mm_cmplt_ps(_mm_add_ps(ew, bw), _mm_setzero_ps());
    const __m128 miss = _mm_and_ps(_mm_or_ps(_mm_or_ps(pu, pv), pw), _mm_or_ps(_mm_or_ps(nu, nv), nw));
    __m128 skip = miss;
    if constexpr (std::is_same_v<S, double>) {
      // all three edge functions beyond twice their bounds with one sign (the test's are then
      // beyond the bound, 2^-120, so its products with the depths are normal doubles), and every
      // depth below 0 or above t_max
      const __m128 zero = _mm_setzero_ps();
      const __m128 su = _mm_add_ps(bu, bu), sv = _mm_add_ps(bv, bv), sw = _mm_add_ps(bw, bw);
      const __m128 all_pos = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(eu, su), _mm_cmpgt_ps(ev, sv)), _mm_cmpgt_ps(ew, sw));
      const __m128 all_neg = _mm_and_ps(_mm_and_ps(_mm_cmplt_ps(_mm_add_ps(eu, su), zero), _mm_cmplt_ps(_mm_add_ps(ev, sv), zero)),
                                        _mm_cmplt_ps(_mm_add_ps(ew, sw), zero));
      const __m128 ez = _mm_add_ps(z0_, _mm_mul_ps(z1_, lz));
      const __m128 zmin = _mm_min_ps(_mm_min_ps(pz[0], pz[1]), pz[2]), zmax = _mm_max_ps(_mm_max_ps(pz[0], pz[1]), pz[2]);
      const __m128 tf = _mm_set1_ps(round_up(double(t_max) * (1.0 + 0x1p-19)));
      const __m128 out = _mm_or_ps(_mm_cmpgt_ps(_mm_sub_ps(zmin, ez), tf), _mm_cmplt_ps(_mm_add_ps(zmax, ez), zero));
      skip = _mm_or_ps(skip, _mm_and_ps(_mm_or_ps(all_pos, all_neg), out));
    } else {
      (void)t_max;
      (void)lz;
    }
    return ~_mm_movemask_ps(skip) & ((1 << count) - 1);
  }

 private:
  /// The smallest float >= x (x >= 0, not NaN; +infinity above the float range).
  static float round_up(double x) {
    float f = static_cast<float>(x);
    if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
  }
  __m128 bound(__m128 xb, __m128 db, __m128 xc, __m128 dc) const {
    const __m128 cross = _mm_add_ps(_mm_add_ps(_mm_mul_ps(xc, db), _mm_mul_ps(xb, dc)), _mm_mul_ps(db, dc));
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(e0_, cross), _mm_mul_ps(e1_, _mm_mul_ps(xb, xc))), tiny_);
  }
  int k_[3];
  __m128 o_[3], sx_, sy_, sz_, d0_, d1_, e0_, e1_, tiny_, z0_, z1_;
};
#endif

/// The children entered at a node, nearest first: writes the entered slots of `mask` ordered by
/// key (ties: the lower slot first), returns how many. Shared by every node test, so that a cast
/// visits the same nodes in the same order whichever computed the keys.
template <class K> inline int order_children(int mask, const K (&keys)[4], int (&order)[4]) {
  int m = 0;
  for (int c = 0; c < 4; ++c) {
    order[m] = c;
    m += (mask >> c) & 1;
  }
  for (int i = 1; i < m; ++i) {
    const int c = order[i];
    int j = i;
    while (j > 0 && keys[order[j - 1]] > keys[c]) {
      order[j] = order[j - 1];
      --j;
    }
    order[j] = c;
  }
  return m;
}

/// The index of the lowest set bit of m (m != 0).
inline int lowest_bit(int m) {
#if defined(__GNUC__) || defined(__clang__)
  return __builtin_ctz(static_cast<unsigned>(m));
#else
  int c = 0;
  while (!(m & 1)) m >>= 1, ++c;
  return c;
#endif
}

/// True when the ray passes validate_ray's checks (finite origin and direction within
/// CoordinateRange, the direction's largest component at least min_scale, t_max >= 0 or +inf):
/// the same rule in a few comparisons (NaN fails them all); validate_ray throws for the others.
template <class S> inline bool ray_in_range(const Ray<S>& ray) {
  constexpr S hi = CoordinateRange<S>::max;
  bool ok = ray.t_max >= S(0);
  S dmax = S(0);
  for (int i = 0; i < 3; ++i) {
    const S ad = std::abs(ray.direction[i]);
    ok = ok & (std::abs(ray.origin[i]) <= hi) & (ad <= hi);
    dmax = ad > dmax ? ad : dmax;
  }
  return ok && dmax >= CoordinateRange<S>::min_scale;
}

/// A pending child of a wide cast: a lower bound of its entry in S (its float key, or the key in S
/// rounded down) and its reference.
struct WideEntry {
  float key;
  std::int32_t first, count;
};

/// The state of one cast through a WideBvh (ray_wide_first_hit_unchecked), shared by its node
/// loop and its leaves: the best hit so far and the bounds derived from it, the ray prepared for
/// the triangle test (at the first leaf: most short casts reach none).
template <class S> struct WideCast {
  const WideBvh<S>& wide;
  const Vec3<S>& o;  // the ray in the mesh's frame (the caller's: it outlives the cast)
  const Vec3<S>& d;
  const Vec3<S> inv;
  const S t_max;
  const bool use_simd;
  const WideFloatSlab<S> float_slab;
  S best, limit;  // after a hit only a strictly earlier one replaces it: nodes entered at best are pruned
  std::int32_t best_k = -1;
  Vec3<S> best_bary = Vec3<S>::Zero();
  float exit_f, bound_f;  // the float node test's exit bound (a float >= best) and entry bound (<= limit)
  // after a hit: float keys at or above tie_f may be within rounding of the hit (redecide)
  float tie_f = std::numeric_limits<float>::infinity();
  PreparedRay<S> pr;
  bool leaf_seen = false;
  std::optional<WideSlab<S>> slab;  // in S: set up when first needed
#if defined(__SSE2__)
  LeafFilter<S> filter;  // set up at the first leaf
#endif
  std::size_t node_tests = 0, triangle_tests = 0;

  /// `o_` and `d_` must outlive the cast.
  WideCast(const WideBvh<S>& w, const Vec3<S>& o_, const Vec3<S>& d_, S t_max_, bool simd)
      : wide(w), o(o_), d(d_), inv(safe_inverse(d_)), t_max(t_max_), use_simd(simd), float_slab(o_, inv, w.coordinate_bound()),
        best(t_max_), limit(t_max_), exit_f(float_round_up(double(t_max_))), bound_f(float_round_down(double(t_max_))) {}

  /// The keys in S of a node's children (WideSlab, or the box test for a zero direction component).
  void double_keys(const WideBvhNode& n, S (&keys)[4]) {
    if (!slab) slab.emplace(o, inv);
    if (std::isfinite(inv[0]) && std::isfinite(inv[1]) && std::isfinite(inv[2])) {
      slab->keys(n, best, keys, use_simd);
      return;
    }
    for (int c = 0; c < 4; ++c) {
      const Aabb<S> box(Vec3<S>(S(n.bounds[0][c]), S(n.bounds[2][c]), S(n.bounds[4][c])),
                        Vec3<S>(S(n.bounds[1][c]), S(n.bounds[3][c]), S(n.bounds[5][c])));
      const auto t = n.count[c] < 0 ? std::nullopt : ray_box_entry(o, inv, box, best);
      keys[c] = t ? *t : std::numeric_limits<S>::quiet_NaN();
    }
  }
  /// The children entered by the test in S (before limit), with their keys rounded down to float.
  int double_mask(const WideBvhNode& n, float (&fk)[4]) {
    S keys[4];
    double_keys(n, keys);
    int mask = 0;
    for (int c = 0; c < 4; ++c) {
      const bool in = keys[c] <= limit && n.count[c] >= 0;
      mask |= (in ? 1 : 0) << c;
      fk[c] = in ? float_round_down(double(keys[c])) : 0.0f;
    }
    return mask;
  }
  /// The triangle at leaf-order position k by the narrow-phase rule; a strictly earlier hit
  /// replaces the best one.
  void test(std::int32_t k) {
    pr.ray.t_max = best;
    const auto h = ray_mesh_triangle_hit(pr, inv, wide.triangle(k));
    if (h && (best_k < 0 || h->t < best)) {
      best = h->t;
      best_k = k;
      best_bary = Vec3<S>(h->u, h->v, h->w);
      limit = std::nextafter(best, -std::numeric_limits<S>::infinity());
      exit_f = float_round_up(double(best));
      bound_f = float_round_down(double(limit));
      const double slack = 4.0 * (std::abs(double(best)) * 0x1p-19 + double(float_slab.absolute_error()));
      tie_f = float_round_down(double(best) - slack);
    }
  }
  /// The triangles of a leaf: four at a time through the certified float filter when they are
  /// stored as floats (SSE), else each by the test.
  IMPACT_NOINLINE void leaf(std::int32_t first, std::int32_t count) {
    if (!leaf_seen) {
      pr = PreparedRay<S>(Ray<S>(o, d, t_max));
#if defined(__SSE2__)
      if (use_simd && wide.packed()) filter.set(pr);
#endif
      leaf_seen = true;
    }
    const bool repeats = wide.has_repeats();
#if defined(__SSE2__)
    if (use_simd && wide.packed()) {
      const float* packed = wide.packed_data();
      for (std::int32_t g = first; g < first + count; g += 4) {
        const int lanes = static_cast<int>(std::min<std::int32_t>(4, first + count - g));
        int todo = filter.candidates(packed + 9 * static_cast<std::size_t>(g), lanes, best);
        if (repeats) {
          for (int c = 0; c < lanes; ++c) {
            if (wide.repeats_previous(g + c)) todo &= ~(1 << c);  // the triangle just tested, again
            else ++triangle_tests;
          }
        } else {
          triangle_tests += static_cast<std::size_t>(lanes);
        }
        while (todo) {
          const int c = lowest_bit(todo);
          todo &= todo - 1;
          test(g + c);
        }
      }
      return;
    }
#endif
    for (std::int32_t k = first; k < first + count; ++k) {
      if (repeats && wide.repeats_previous(k)) continue;  // the triangle just tested, again (coincident copies)
      ++triangle_tests;
      test(k);
    }
  }
  /// After a hit, at a node whose float keys of entered children are within rounding of it: the
  /// keys in S decide (exact ties with the hit are pruned, as WideSlab prunes them: a ray through
  /// a vertex would otherwise open every leaf around it).
  IMPACT_NOINLINE int redecide(const WideBvhNode& n, float (&fk)[4]) { return double_mask(n, fk); }

  /// Descends to the nearest entered child of `mask` (keys fk), pushing the others farthest first.
  template <class Stack> void descend(const WideBvhNode& n, int mask, const float (&fk)[4], Stack& stack, std::int32_t& first, std::int32_t& count) {
    const int c0 = lowest_bit(mask);
    const int rest = mask & (mask - 1);
    if (!rest) {  // one child (the common case)
      first = n.first[c0];
      count = n.count[c0];
      return;
    }
    const int c1 = lowest_bit(rest);
    if (!(rest & (rest - 1))) {  // two: the nearer first (ties: the lower slot)
      const bool swap = fk[c0] > fk[c1];
      const int near = swap ? c1 : c0, far = swap ? c0 : c1;
      stack.push({fk[far], n.first[far], n.count[far]});
      first = n.first[near];
      count = n.count[near];
      return;
    }
    int order[4];
    const int m = order_children(mask, fk, order);
    for (int j = m - 1; j > 0; --j) stack.push({fk[order[j]], n.first[order[j]], n.count[order[j]]});
    first = n.first[order[0]];
    count = n.count[order[0]];
  }

  /// The traversal: nearest child first, the others on the stack with their keys.
  void run() {
    TraversalStack<WideEntry, 128> stack;
    const WideBvhNode* nodes = wide.nodes().data();
    std::int32_t first = 0, count = 0;  // the root: an inner node
    const bool in_float = float_slab.usable();  // (false for an infinite 1 / d)
    auto pop = [&](float bound) {  // the nearest pending child still below the bound
      while (!stack.empty()) {
        const WideEntry e = stack.pop();
        if (e.key <= bound) {
          first = e.first;
          count = e.count;
          return true;
        }
      }
      return false;
    };
#if defined(__SSE2__)
    if (in_float && use_simd) {
      for (;;) {
        // the bounds as of the last leaf, in registers for the node loop
        const __m128 exit_v = _mm_set1_ps(exit_f), bound_v = _mm_set1_ps(bound_f), tie_v = _mm_set1_ps(tie_f);
        const float bound = bound_f;
        while (count == 0) {
          const WideBvhNode& n = nodes[first];
          ++node_tests;
          __m128 lo;
          int mask = float_slab.entered(n, exit_v, bound_v, lo);
          if (mask) {
            float fk[4];
            _mm_storeu_ps(fk, lo);
            if (IMPACT_UNLIKELY(_mm_movemask_ps(_mm_cmpge_ps(lo, tie_v)) & mask)) {
              mask = redecide(n, fk);
              if (!mask) {
                if (!pop(bound)) return;
                continue;
              }
            }
            descend(n, mask, fk, stack, first, count);
            continue;
          }
          if (!pop(bound)) return;
        }
        leaf(first, count);
        if (!pop(bound_f)) return;
      }
    }
#endif
    for (;;) {
      if (count > 0) {
        leaf(first, count);
      } else {
        const WideBvhNode& n = nodes[first];
        ++node_tests;
        float fk[4];
        int mask;
        if (in_float) {
          mask = float_slab.entered_scalar(n, exit_f, bound_f, fk);
          if (IMPACT_UNLIKELY((mask & ((fk[0] >= tie_f) | (fk[1] >= tie_f) << 1 | (fk[2] >= tie_f) << 2 | (fk[3] >= tie_f) << 3))))
            mask = redecide(n, fk);
        } else {
          mask = double_mask(n, fk);
        }
        if (mask) {
          descend(n, mask, fk, stack, first, count);
          continue;
        }
      }
      if (!pop(bound_f)) return;
    }
  }
};

/// ray_mesh_first_hit through a WideBvh without the argument checks; `pose` null for the mesh's
/// own frame. `use_simd` false forces the scalar node test and leaf loop (for the tests that
/// compare the two: the same answers, triangle included).
template <class S>
std::optional<RayMeshHit<S>> ray_wide_first_hit_unchecked(const WideBvh<S>& wide, const Ray<S>& ray, const RigidTransform<S>* pose,
                                                          RayMeshStats* stats, bool use_simd = true) {
  if (wide.empty()) return std::nullopt;
  const Vec3<S> o = pose ? Vec3<S>(pose->R.transpose() * (ray.origin - pose->t)) : ray.origin;
  const Vec3<S> d = pose ? Vec3<S>(pose->R.transpose() * ray.direction) : ray.direction;
  if (d.squaredNorm() == S(0) || !(ray.t_max >= S(0))) return std::nullopt;
  WideCast<S> cast(wide, o, d, ray.t_max, use_simd);
  cast.run();
  if (stats) {
    stats->node_tests += 4 * cast.node_tests;
    stats->triangle_tests += cast.triangle_tests;
  }
  if (cast.best_k < 0) return std::nullopt;
  RayMeshHit<S> hit;
  hit.t = cast.best;
  hit.leaf_index = cast.best_k;
  hit.triangle = wide.triangle_id(cast.best_k);
  hit.barycentric = cast.best_bary;
  hit.point = ray.origin + cast.best * ray.direction;
  const Vec3<S> nrm = wide.triangle(cast.best_k).normal();
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
  if (!detail::ray_in_range(ray)) validate_ray(ray, "ray_mesh_first_hit");
  validate_pose(pose, "ray_mesh_first_hit");
  return detail::ray_wide_first_hit_unchecked(wide, ray, &pose, stats);
}

/// The same first hit with the ray in the mesh's own frame (no pose to check or apply).
template <class S> std::optional<RayMeshHit<S>> ray_mesh_first_hit(const WideBvh<S>& wide, const Ray<S>& ray) {
  if (!detail::ray_in_range(ray)) validate_ray(ray, "ray_mesh_first_hit");
  return detail::ray_wide_first_hit_unchecked(wide, ray, static_cast<const RigidTransform<S>*>(nullptr), nullptr);
}

}  // namespace impact
