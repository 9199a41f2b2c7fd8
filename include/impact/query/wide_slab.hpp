// SPDX-License-Identifier: MIT
/// \file
/// The node tests of a cast through a WideBvh (bvh/wide_bvh.hpp): the slab test of one ray
/// against the four (or eight) boxes of a node, in S (WideSlab, on the float boxes, exact in S with its exit
/// padded as in PBRT's robust slab test) and in float (WideFloatSlab, a quarter of the work, its
/// entry lowered and its exit raised by a bound on its rounding so that it enters every box
/// WideSlab enters, never later), and the order in which the entered children are visited
/// (order_children, shared by both so that a cast visits the same nodes whichever test ran).
/// Each runs with SSE when compiled with it, else as a scalar loop of the same IEEE operations in
/// the same order: the same keys and masks bit for bit. (The 8-wide AVX cast has a node test of its
/// own, one multiply-add a plane: query/wide_fused_slab.hpp.) Used by query/ray_wide_bvh.hpp.
#pragma once

#include "impact/bvh/wide_bvh.hpp"
#include "impact/core/next_float.hpp"
#include "impact/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__AVX__)
#include <immintrin.h>
#endif
// the 8-wide AVX code (the cast's node loop, query/wide_fused_slab.hpp, and its leaf test): compiled
// for AVX whatever the target (a target attribute), called when the CPU has it (wide_avx_available)
#if defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define IMPACT_WIDE_AVX 1
#define IMPACT_WIDE_AVX_TARGET __attribute__((target("avx")))
#endif

namespace impact {
namespace detail {

/// True when the 8-wide cast's AVX code may run: compiled in (GCC or Clang on x86) and the CPU has
/// it (checked once).
inline bool wide_avx_available() {
#if defined(IMPACT_WIDE_AVX)
  static const bool avx = __builtin_cpu_supports("avx");
  return avx;
#else
  return false;
#endif
}

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
  template <int W> void keys(const WideBvhNodeN<W>& n, S t_max, S (&keys)[W], bool use_simd = true) const {
    constexpr S pad = S(4) * std::numeric_limits<S>::epsilon();  // robust slab test (PBRT 3.9.2)
    constexpr S nan = std::numeric_limits<S>::quiet_NaN();
    if constexpr (std::is_same_v<S, double>) {
      if (use_simd) {
#if defined(__AVX__)
        const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
        const __m256d vpad = _mm256_set1_pd(pad);
        for (int g = 0; g < W; g += 4) {  // children g .. g + 3
          __m256d t0 = _mm256_setzero_pd(), t1 = _mm256_set1_pd(t_max);
          for (int i = 0; i < 3; ++i) {
            const __m256d o = _mm256_set1_pd(o_[i]), inv = _mm256_set1_pd(inv_[i]);
            const __m256d a = _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(_mm_load_ps(n.bounds[near_[i]] + g)), o), inv);
            __m256d b = _mm256_mul_pd(_mm256_sub_pd(_mm256_cvtps_pd(_mm_load_ps(n.bounds[far_[i]] + g)), o), inv);
            b = _mm256_add_pd(b, _mm256_mul_pd(_mm256_and_pd(b, abs_mask), vpad));
            t0 = _mm256_max_pd(a, t0);
            t1 = _mm256_min_pd(b, t1);
          }
          const __m256d hit = _mm256_cmp_pd(t0, t1, _CMP_LE_OQ);
          _mm256_storeu_pd(keys + g, _mm256_blendv_pd(_mm256_set1_pd(nan), t0, hit));
        }
        return;
#elif defined(__SSE2__)
        const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
        const __m128d vpad = _mm_set1_pd(pad);
        for (int h = 0; h < W / 2; ++h) {  // children 2h and 2h + 1
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
    S t0[W], t1[W];
    for (int c = 0; c < W; ++c) t0[c] = S(0), t1[c] = t_max;
    for (int i = 0; i < 3; ++i)
      for (int c = 0; c < W; ++c) {
        const S a = (S(n.bounds[near_[i]][c]) - o_[i]) * inv_[i];
        S b = (S(n.bounds[far_[i]][c]) - o_[i]) * inv_[i];
        b += std::abs(b) * pad;
        t0[c] = a > t0[c] ? a : t0[c];  // maxpd / minpd: the second operand unless the first wins
        t1[c] = b < t1[c] ? b : t1[c];
      }
    for (int c = 0; c < W; ++c) keys[c] = t0[c] <= t1[c] ? t0[c] : nan;
  }

 private:
#if defined(__SSE2__)
  static __m128d load2(const float* f) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f)))); }
#endif
  int near_[3], far_[3];
  S o_[3], inv_[3];
};

/// The smallest float >= x (x not NaN; +infinity above the float range), without libm or
/// branches: f = float(x) and, when f < x, the next float up, one more unit in the last place of
/// |f| for a sign bit 0 (+0 becomes the smallest subnormal) or one less for a sign bit 1 (f = -0
/// is never below x: it is the rounding of x in [-2^-150, 0]).
inline float float_round_up(double x) {
  const float f = static_cast<float>(x);
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  const std::uint32_t below = double(f) < x ? 1u : 0u;
  b += below - ((below & (b >> 31)) << 1);  // +1, -1 or 0
  float g;
  std::memcpy(&g, &b, sizeof g);
  return g;
}
/// The largest float <= x (x not NaN; -infinity below the float range), without libm.
inline float float_round_down(double x) { return -float_round_up(-x); }
/// float_round_down(x) and float_round_up(x) from one rounding of x (x not NaN): f = float(x)
/// is one of them, and the other is its neighbour when f != x.
inline void float_bounds(double x, float& down, float& up) {
  const float f = static_cast<float>(x);
  const double fd = double(f);
  if (fd == x) {  // x is a float (a cast's t_max of 1 or infinity): both bounds
    down = up = f;
    return;
  }
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  const std::uint32_t below = fd < x ? 1u : 0u, above = fd > x ? 1u : 0u;
  const std::uint32_t neg = b >> 31;
  // the neighbour up of f below x (+1 on the bits for a sign bit 0, -1 for 1: +0 becomes the
  // smallest subnormal) or down of f above x (-1 for a sign bit 0, +1 for 1: -0, the rounding of
  // x in [-2^-150, 0), becomes the smallest negative subnormal; +0 is never above x)
  const std::uint32_t ub = b + below - ((below & neg) << 1);
  const std::uint32_t db = b - above + ((above & neg) << 1);
  float u, d;
  std::memcpy(&u, &ub, sizeof u);
  std::memcpy(&d, &db, sizeof d);
  up = u;
  down = d;
}

/// The float bounds of a cast after a hit at t = x (x >= 0 or -0, not NaN): `up` the smallest
/// float >= x (the node test's exit bound) and `below` the largest float < x
/// (float_round_down(next_down(x)): the entry bound, so a child entered at or after the hit is
/// pruned), from one rounding of x: f = float(x) is one of them and the other its neighbour (for f
/// below x, f and the float up; else the float down, -denorm_min for f = +-0, and f).
inline void float_hit_bounds(double x, float& up, float& below) {
  const float f = static_cast<float>(x);
  std::uint32_t b;
  std::memcpy(&b, &f, sizeof b);
  // without jumps (whether f is below x is a coin toss): f >= +-0 and its bits are b
  const std::uint32_t lower = double(f) < x ? 1u : 0u;
  const std::uint32_t ub = b + lower;  // (below x: the next float up, +infinity above FLT_MAX)
  const std::uint32_t db0 = b - 1u + lower;  // (else the float below f, but for f = +-0: a NaN)
  const std::uint32_t db = (db0 << 1) == 0xfffffffeu ? 0x80000001u : db0;  // (-denorm_min)
  std::memcpy(&up, &ub, sizeof up);
  std::memcpy(&below, &db, sizeof below);
}
/// A float at most x - 4 (x 2^-19 + e) for every x > `below` (float_hit_bounds' bound of a hit at
/// x >= 0) and e >= 2^-100: the cast's tie bound (docs/rays-history.md), in two float operations (or one
/// multiply-add where the compiler contracts them). With k = 1 - 2^-16, P = below k rounded is at
/// most x k (1 + 2^-24) <= x (1 - 2^-17) - x 2^-24 (P <= 0 for below < 0), c = 5 e rounded is at
/// least 4.99 e, and P - c rounded is at most (P - c)(1 + 2^-24) <= P (1 + 2^-24) - c when P - c >= 0,
/// at most P - c (1 - 2^-24) below zero: both <= x (1 - 2^-17) - 4 e; an underflow's 2^-150 is far
/// below the 0.98 e to spare.
inline float float_tie_bound(float below, float e) { return below * (1.0f - 0x1p-16f) - 5.0f * e; }

/// The slab test of a ray against the W children of a WideBvhNodeN<W> in float: a conservative
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
/// scalar loop of the same IEEE operations in the same order (the same keys and mask bit for bit);
/// for W = 8 SSE tests the two halves of four.
template <class S, int W = 4> class WideFloatSlab {
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
      std::memcpy(sse_.planes, kPlaneOffsets.at[sign], sizeof sse_.planes);
      sse_.o[0] = _mm_shuffle_ps(of01, of01, 0x00), sse_.o[1] = _mm_shuffle_ps(of01, of01, 0x55), sse_.o[2] = _mm_shuffle_ps(of22, of22, 0x00);
      sse_.inv[0] = _mm_shuffle_ps(if01, if01, 0x00), sse_.inv[1] = _mm_shuffle_ps(if01, if01, 0x55), sse_.inv[2] = _mm_shuffle_ps(if22, if22, 0x00);
      e_ = usable_ ? float_round_up(e * (1.0 + 0x1p-16) + 0x1p-100) : 0.0f;
      sse_.e = _mm_set1_ps(e_);
      return;
    }
#endif
    bool ok = coordinate_bound <= S(0x1p60);
    double e = 0;
    for (int i = 0; i < 3; ++i) {
      const S a = std::abs(inv[i]);
      ok = ok & (std::abs(o[i]) <= S(0x1p60)) & (a <= S(0x1p60)) & (a >= S(0x1p-60));  // false for NaN
      const bool neg = inv[i] < S(0);
      planes()[i] = static_cast<int>(sizeof(float[W])) * (2 * i + (neg ? 1 : 0));  // byte offsets of the planes
      planes()[3 + i] = planes()[i] ^ static_cast<int>(sizeof(float[W]));
      const float of = static_cast<float>(o[i]), invf = static_cast<float>(inv[i]);
#if defined(__SSE2__)
      sse_.o[i] = _mm_set1_ps(of), sse_.inv[i] = _mm_set1_ps(invf);
#else
      o_[i] = of, inv_[i] = invf;
#endif
      e = std::max(e, std::abs(double(o[i]) - double(of)) * double(a));
    }
    usable_ = ok && e <= 0x1p40;
    e_ = usable_ ? float_round_up(e * (1.0 + 0x1p-16) + 0x1p-100) : 0.0f;
#if defined(__SSE2__)
    sse_.e = _mm_set1_ps(e_);
#endif
  }
  /// False when some magnitude is out of range (see the class comment): use WideSlab.
  bool usable() const { return usable_; }
  /// e: the absolute part of the keys' lowering (the relative part is 2^-19).
  float absolute_error() const { return e_; }
  static constexpr float kLow = 1.0f - 0x1p-19f, kHigh = 1.0f + 0x1p-19f;

  /// The children entered before `bound` (a float <= the cast's bound): bit c set when lo[c] <=
  /// hi[c] and lo[c] <= bound; keys[c] = lo[c] (the others anything); `t_max_up` a float >= t_max.
  int entered(const WideBvhNodeN<W>& n, float t_max_up, float bound, float (&keys)[W], bool use_simd = true) const {
#if defined(__SSE2__)
    if (use_simd) {
      __m128 lo[W / 4];
      const int m = sse_.entered(n, _mm_set1_ps(t_max_up), _mm_set1_ps(bound), lo);
      for (int g = 0; g < W / 4; ++g) _mm_storeu_ps(keys + 4 * g, lo[g]);
      return m;
    }
#else
    (void)use_simd;
#endif
    return entered_scalar(n, t_max_up, bound, keys);
  }

#if defined(__SSE2__)
  /// The per-ray state of the SSE test, by value (a cast copies it into registers).
  struct Sse {
    __m128 o[3], inv[3], e;  // origin and inverse direction rounded to float, e, broadcast
    int planes[6];           // byte offsets in a node of the near planes of x, y, z, then of the far ones
    /// entered() of a 4-wide node with the bounds broadcast and the keys left in a register.
    int entered(const WideBvhNodeN<W>& n, __m128 t_max_up, __m128 bound, __m128& keys) const {
      static_assert(W == 4, "one register of keys: a 4-wide node");
      return lanes(reinterpret_cast<const char*>(n.bounds), t_max_up, bound, keys);
    }
    /// The same for any width, keys[h] holding children 4h .. 4h + 3 (an 8-wide node: two halves of
    /// four).
    int entered(const WideBvhNodeN<W>& n, __m128 t_max_up, __m128 bound, __m128 (&keys)[W / 4]) const {
      const char* p = reinterpret_cast<const char*>(n.bounds);
      int m = lanes(p, t_max_up, bound, keys[0]);
      if constexpr (W == 8) m |= lanes(p + 16, t_max_up, bound, keys[1]) << 4;
      return m;
    }
    /// The test of four children whose planes are at the byte offsets `planes` from p.
    int lanes(const char* p, __m128 t_max_up, __m128 bound, __m128& keys) const {
      __m128 t0 = _mm_setzero_ps(), t1 = t_max_up;
      for (int i = 0; i < 3; ++i) {
        const __m128 a = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(p + planes[i])), o[i]), inv[i]);
        const __m128 b = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(p + planes[3 + i])), o[i]), inv[i]);
        t0 = _mm_max_ps(a, t0);
        t1 = _mm_min_ps(b, t1);
      }
      const __m128 lo = _mm_sub_ps(_mm_mul_ps(t0, _mm_set1_ps(kLow)), e);
      const __m128 hi = _mm_add_ps(_mm_mul_ps(t1, _mm_set1_ps(kHigh)), e);
      keys = lo;
      return _mm_movemask_ps(_mm_and_ps(_mm_cmple_ps(lo, hi), _mm_cmple_ps(lo, bound)));
    }
  };
  const Sse& sse() const { return sse_; }
  /// entered() with the bounds broadcast and the keys left in a register.
  int entered(const WideBvhNodeN<W>& n, __m128 t_max_up, __m128 bound, __m128& keys) const { return sse_.entered(n, t_max_up, bound, keys); }
#endif

  /// entered() by a scalar loop of the same IEEE operations in the same order.
  int entered_scalar(const WideBvhNodeN<W>& n, float t_max_up, float bound, float (&keys)[W]) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    float t0[W], t1[W];
    for (int c = 0; c < W; ++c) t0[c] = 0.0f, t1[c] = t_max_up;
    for (int i = 0; i < 3; ++i) {
      const float* near = reinterpret_cast<const float*>(p + planes()[i]);
      const float* far = reinterpret_cast<const float*>(p + planes()[3 + i]);
      for (int c = 0; c < W; ++c) {
        const float a = (near[c] - origin(i)) * inverse(i);
        const float b = (far[c] - origin(i)) * inverse(i);
        t0[c] = a > t0[c] ? a : t0[c];  // maxps / minps: the second operand unless the first wins
        t1[c] = b < t1[c] ? b : t1[c];
      }
    }
    int m = 0;
    for (int c = 0; c < W; ++c) {
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
  int* planes() { return sse_.planes; }
  const int* planes() const { return sse_.planes; }
  float origin(int i) const { return _mm_cvtss_f32(sse_.o[i]); }
  float inverse(int i) const { return _mm_cvtss_f32(sse_.inv[i]); }
#else
  int* planes() { return planes_; }
  const int* planes() const { return planes_; }
  float origin(int i) const { return o_[i]; }
  float inverse(int i) const { return inv_[i]; }
#endif
  /// kPlanes[sign]: the byte offsets in a 4-wide node of the near planes of x, y, z then the far
  /// ones, for the direction's sign bits (bit i: component i negative); twice them in an 8-wide one.
  static constexpr int kPlanes[8][6] = {{0, 32, 64, 16, 48, 80}, {16, 32, 64, 0, 48, 80}, {0, 48, 64, 16, 32, 80},
                                        {16, 48, 64, 0, 32, 80}, {0, 32, 80, 16, 48, 64}, {16, 32, 80, 0, 48, 64},
                                        {0, 48, 80, 16, 32, 64}, {16, 48, 80, 0, 32, 64}};
  /// kPlanes scaled to the node's width (the offsets of a W-wide node), made at compile time.
  struct PlaneOffsets {
    int at[8][6];
  };
  static constexpr PlaneOffsets plane_offsets() {
    PlaneOffsets p{};
    for (int sign = 0; sign < 8; ++sign)
      for (int j = 0; j < 6; ++j) p.at[sign][j] = kPlanes[sign][j] * (W / 4);
    return p;
  }
  static constexpr PlaneOffsets kPlaneOffsets = plane_offsets();
  bool usable_ = false;
  float e_ = 0.0f;
#if defined(__SSE2__)
  Sse sse_;
#else
  int planes_[6];  // byte offsets in a node of the near planes of x, y, z, then of the far ones
  float o_[3], inv_[3];
#endif
};

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

/// The children entered at a node, nearest first: writes the entered slots of `mask` ordered by
/// key (ties: the lower slot first), returns how many. Shared by every node test, so that a cast
/// visits the same nodes in the same order whichever computed the keys.
template <class K, int N> inline int order_children(int mask, const K (&keys)[N], int (&order)[N]) {
  int m = 0;
  if constexpr (N <= 4) {  // the slots in order without branches
    for (int c = 0; c < N; ++c) {
      order[m] = c;
      m += (mask >> c) & 1;
    }
  } else {  // a few of eight: one step a set bit
    for (unsigned bits = static_cast<unsigned>(mask); bits; bits &= bits - 1) order[m++] = lowest_bit(static_cast<int>(bits));
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

}  // namespace detail
}  // namespace impact
