// SPDX-License-Identifier: MIT
/// \file
/// The node test of the 8-wide AVX cast (query/ray_wide_bvh.hpp): the slab test of one ray
/// against the eight float boxes of a WideBvhNode8 with one fused multiply-add a plane,
/// b * (1 / d) - o * (1 / d), the near and far planes chosen once per ray by the direction's signs,
/// the origin's term of each plane moved by a per-ray margin (a near plane's value never above
/// its exact parameter, a far plane's never below it, over the parameters the ray can reach), so
/// that the test enters every box the double slab test (WideSlab, query/wide_slab.hpp) enters,
/// its key never above WideSlab's entry, with no correction after the reductions. WideFusedRay
/// holds the per-ray values (made in double, rounded once to float) and the proof;
/// entered_scalar is the test as a scalar loop of the same IEEE operations (std::fma), the AVX
/// test (compiled for AVX and FMA by a target attribute on GCC and Clang for x86, used when the
/// CPU has both: wide_fma_available) gives the same keys and mask bit for bit. Tested in
/// tests/query/test_ray_wide_bvh8.cpp; docs/rays-history.md (issue 14, the seventeenth and
/// twenty-third steps).
#pragma once

#include "impact/bvh/wide_bvh.hpp"
#include "impact/core/types.hpp"
#include "impact/query/wide_slab.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#if defined(IMPACT_WIDE_AVX)
#include <immintrin.h>
#define IMPACT_WIDE_FMA_TARGET __attribute__((target("avx,fma")))
#endif

namespace impact {
namespace detail {

/// True when the 8-wide AVX cast may run (its node test uses AVX and FMA): compiled in (GCC or
/// Clang on x86) and the CPU has both (checked once).
inline bool wide_fma_available() {
#if defined(IMPACT_WIDE_AVX)
  static const bool fma = __builtin_cpu_supports("avx") && __builtin_cpu_supports("fma");
  return fma;
#else
  return false;
#endif
}

/// The per-ray values of the fused node test of an 8-wide node, and the test as a scalar loop.
///
/// For a ray o + t d: inv[i] = float(1 / d_i) (1 / d_i as the cast computed it, in S, rounded to
/// float), and two offsets an axis in place of the origin's term: a near plane b's value is
/// fma(b, inv[i], -oi[i]), a far plane's fma(b, inv[i], -oi[3 + i]), oi[i] above o_i inv[i] and
/// oi[3 + i] below it by a margin that covers every rounding of the test over the parameters that
/// can matter (up to the ray's reach on that axis: t_max, or its exit from the tree's box if
/// sooner). So a near value is never above its plane's exact parameter and a far value never
/// below, with no correction after the reductions: lo = max(0, near values), and a child is
/// entered when lo <= min(far values, bound) (bound <= the float t_max rounded up, so t_max
/// needs no lane of its own). The maxima and minima are taken as trees, (a0 max a1) max (a2 max
/// 0), two deep on the node loop's dependent chain; no operand is NaN and lo is never -0 (a max
/// with +0 last), so any order gives the same keys and masks.
///
/// The offsets, in double, with the margin M = kMargin = 2^-19: x_i = M times the exit from the
/// tree's box through its slab on axis i (the larger of its two planes' (b - o_i)(M / d_i), 1 /
/// d_i as the cast computed it, in S), l_i = min(x_i, t_max M), H_i = max(l_i, 2^-126); oi[i] =
/// float(fma(o_i, inv[i] (1 + c), H_i)), oi[3 + i] = float(fma(o_i, inv[i] (1 - c), -H_i)), c =
/// 2^-23 with the sign of o_i inv[i] (the products inv[i] (1 +- c) of two floats are exact in
/// double); e = float(max_i (H_i (1 + 2^-20) + |o_i inv[i]| 2^-22) + 2^-99) bounds the margins
/// from above (the cast's tie bound uses it). Why the test enters every box WideSlab enters, its
/// key never above WideSlab's entry (u = 2^-24, v = u in float and 2^-53 in double; for a plane b
/// on axis i, p = (b - o_i) inv[i] and p_S = (b - o_i)(1 / d_i in S), exactly; q = o_i inv[i]):
/// - WideSlab<S> (query/wide_slab.hpp: the subtraction and the product rounded, its exit padded by
///   8 v) gives a near plane p_S (1 +- v)^2 and a far plane at most p_S (1 + v)^3 (1 + 8 v). So it
///   enters a box only if, over its near planes i and far planes j, p_S,j >= p_S,i (1 - 13.01 v)
///   and t_max >= p_S,i (1 - v)^2 (every p_S,j >= -2^-149: an underflow of its exit to -0), and
///   its entry is at least max(0, p_S,i (1 - v)^2).
/// - A float ray's inv[i] is its 1 / d_i in S, so p = p_S: the same rounded inverse in both tests
///   cancels. A double ray's inv[i] is its 1 / d_i rounded to float: p = p_S (1 + r), |r| <= u.
/// - Every child box lies in WideBvh::box: the box's far plane on axis i is a far plane j of the
///   box with x_i >= M p_S,j (1 - 2^-51), so for a box WideSlab enters, H_i >= M P (1 - 13.02 v)
///   on every axis, P = max_i p_S,i the largest near plane's (and H_i >= 2^-126).
/// - The margin eta = oi[i] - q (near) or q - oi[3 + i] (far): fma(...) is q +- (|q| 2^-23 + H_i)
///   rounded once in double, then to float (2^-24 |.| + 2^-150), which the 2^-23 |q| covers:
///   H_i (1 - 2^-22) <= eta <= H_i (1 + 2^-23) + 1.51 2^-23 |q| + 2^-150 <= e. So eta >= max(31.99 u
///   P, 2^-126 (1 - 2^-22)).
/// - The fused values: b inv[i] - oi[i] = p - eta exactly, rounded once by the fma (u relative,
///   2^-150 below the normal range, the sign kept): a near value is at most (p - eta)(1 + u) +
///   2^-150 when p > eta, else at most 0; a far value at least (p + eta)(1 - u) - 2^-150.
/// - Entry: a near value is at most p_S (1 - v)^2 <= WideSlab's entry, as eta (1 + u) >= 3.01 u p +
///   2^-149 (float) or >= 2.01 u p_S + 2^-149 (double): lo never exceeds WideSlab's entry (pruning
///   stays exact), and lo, a float at most the cast's limit, is at most its float bound.
/// - Exit: a near value i is at most a far value j when (p_i - eta_i)(1 + u) + 2^-150 <= (p_j +
///   eta_j)(1 - u) - 2^-150. In float p_j >= p_i (1 - 13.01 u), so it suffices that eta_i + eta_j
///   >= 15.02 u p_i + 2^-148 (the float slab's 8 u padding, its five roundings and the fused test's
///   two): they are >= 2 max(31.99 u P, 2^-126 (1 - 2^-22)), which is. In double it suffices that
///   eta_i + eta_j >= 4.02 u p_S,i + 2^-148 (the rounding of the inverse on two axes). Every far
///   value is > 0 (p_S,j >= -2^-149, eta_j >= 2^-126 (1 - 2^-22)). So lo <= min(far values,
///   bound): entered. (Rays that need the most: WideSlab<float> enters a miss of about 11 u whose
///   every rounding runs the same way; tests/query/test_ray_wide_bvh8.cpp has such rays, which a
///   margin of 5 u misses. A box the ray truly enters needs only eta_i + eta_j >= 4.02 u T.)
/// - Ties: WideSlab's entry - lo <= 5.2 u P + eta (1 + u) + 2^-150 <= 5.2 u P + 1.001 e, within the
///   slack 4 (t 2^-19 + e) of the cast's tie bound: a key below it is entered before the hit.
/// - Empty slots (lower plane FLT_MAX, upper -FLT_MAX): usable rays have |o|, tree coordinates
///   <= 2^60, |1 / d| in [2^-60, 2^60], |q| <= 2^63 and l_i <= 2^61 (so |oi| < 2^64): a near
///   value >= 2^67 - 2^64 > 0 > a far value, never entered. No NaN: a real plane's |b inv| <=
///   2^121, an empty slot's may overflow to the infinity of its sign, and the offsets are finite.
struct WideFusedRay {
  // M: a plane's margin per unit of the ray's reach (see above). The proof needs 7.51 u (u = 2^-24);
  // M = 2^-19 = 32 u keeps four times that, as slack against an error in the proof. 2^-21 = 8 u
  // would also be sound, with 6 % to spare; a smaller margin buys no speed (the same operations).
  static constexpr double kMargin = 0x1p-19;
  float inv[3];
  float oi[6];  // the near planes' offsets of x, y, z (above o inv), then the far planes' (below)
  float e = 0.0f;
  int planes[6];  // byte offsets in a WideBvhNode8 of the near planes of x, y, z, then of the far ones
  bool ok = false;

  /// The values of the ray (o, inv = 1 / d computed in S, t_max >= 0 or +infinity);
  /// `coordinate_bound` bounds the tree's coordinates (WideBvh::coordinate_bound), `box` is
  /// WideBvh::box (or any box holding every child box, in its layout).
  template <class S>
  WideFusedRay(const Vec3<S>& o, const Vec3<S>& inv_d, S coordinate_bound, const std::array<double, 8>& box, double t_max) {
    // each step as the AVX set-up takes it: maxpd / minpd (the second operand unless the first
    // wins), the products and sums in double in the same order
    bool in = double(coordinate_bound) <= 0x1p60;
    const double reach_max = t_max * kMargin;
    double bound = 0.0;  // the largest H (1 + 2^-20) + |p| 2^-22
    for (int i = 0; i < 3; ++i) {
      const double od = double(o[i]), id = double(inv_d[i]), ai = std::abs(id);
      inv[i] = static_cast<float>(id);
      const double fi = double(inv[i]), ap = std::abs(od * fi);
      const double x0 = (box[static_cast<std::size_t>(i)] - od) * (id * kMargin), x1 = (box[static_cast<std::size_t>(4 + i)] - od) * (id * kMargin);
      const double x = x0 > x1 ? x0 : x1;  // the exit from the box's slab (its far plane), times M
      const double l = x < reach_max ? x : reach_max;
      const double h = l > 0x1p-126 ? l : 0x1p-126;
      in = in & (std::abs(od) <= 0x1p60) & (ai <= 0x1p60) & (ai >= 0x1p-60) & (ap <= 0x1p63) & (l <= 0x1p61);  // false for NaN
      const double c = std::signbit(od) != std::signbit(id) ? -0x1p-23 : 0x1p-23;  // 2^-23 with the sign of p
      oi[i] = static_cast<float>(std::fma(od, fi * (1.0 + c), h));
      oi[3 + i] = static_cast<float>(std::fma(od, fi * (1.0 - c), -h));
      const double eb = h * 0x1.00001p0 + ap * 0x1p-22;
      bound = eb > bound ? eb : bound;
      planes[i] = static_cast<int>(sizeof(float[8])) * (2 * i + (std::signbit(id) ? 1 : 0));
      planes[3 + i] = planes[i] ^ static_cast<int>(sizeof(float[8]));
    }
    ok = in;
    e = ok ? static_cast<float>(bound + 0x1p-99) : 0.0f;
  }
  /// False when some magnitude is out of range (see above): the cast uses another node test.
  bool usable() const { return ok; }

  /// The children of `n` entered before `bound` (bit c; `bound` at most the float t_max rounded
  /// up), keys[c] = lo[c] (the others anything). The AVX test's operations one lane at a time.
  int entered_scalar(const WideBvhNode8& n, float bound, float (&keys)[8]) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    // maxps / minps: the second operand unless the first wins
    const auto maxps = [](float x, float y) { return x > y ? x : y; };
    const auto minps = [](float x, float y) { return x < y ? x : y; };
    int mask = 0;
    for (int c = 0; c < 8; ++c) {
      float a[3], b[3];
      for (int i = 0; i < 3; ++i) {
        a[i] = std::fma(reinterpret_cast<const float*>(p + planes[i])[c], inv[i], -oi[i]);
        b[i] = std::fma(reinterpret_cast<const float*>(p + planes[3 + i])[c], inv[i], -oi[3 + i]);
      }
      const float lo = maxps(maxps(a[0], a[1]), maxps(a[2], 0.0f)), hi = minps(minps(b[0], b[1]), minps(b[2], bound));
      keys[c] = lo;
      mask |= (lo <= hi ? 1 : 0) << c;
    }
    return mask;
  }
};

#if defined(IMPACT_WIDE_AVX)
/// The fused node test in 256-bit AVX with FMA (call only when wide_fma_available()).
struct WideFusedAvx {
  __m256 inv[3], oi[6];  // WideFusedRay's values broadcast
  int planes[6];

  /// The state of a ray in double, in one pass of 256-bit AVX over the three axes: WideFusedRay's
  /// checks and values bit for bit (tested). False when WideFusedRay would not be usable; `e` gets
  /// its e (0 when not usable). Its limits (2^60) are within CoordinateRange<double>: the public
  /// 8-wide cast relies on them as its argument check (query/ray_wide_bvh.hpp).
  IMPACT_WIDE_FMA_TARGET bool set(const Vec3<double>& o, const Vec3<double>& inv_d, double coordinate_bound, const std::array<double, 8>& box,
                                  double t_max, float& e_out) {
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
    // (x, y, z, 0) and (1/dx, 1/dy, 1/dz, 1): the fourth lane passes every check, adds nothing to e
    const __m256d vo = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(o.data())), _mm_load_sd(o.data() + 2), 1);
    const __m256d vi = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(inv_d.data())), _mm_set_pd(1.0, inv_d[2]), 1);
    const __m256d ai = _mm256_and_pd(vi, abs_mask);
    const __m128 invf = _mm256_cvtpd_ps(vi);
    const __m256d fi = _mm256_cvtps_pd(invf);
    const __m256d ap = _mm256_and_pd(_mm256_mul_pd(vo, fi), abs_mask);
    // the exit from the tree's box on each axis times M (the larger of its two planes'), at most t_max M
    const __m256d is = _mm256_mul_pd(vi, _mm256_set1_pd(WideFusedRay::kMargin));
    const __m256d x = _mm256_max_pd(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(box.data()), vo), is),
                                    _mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(box.data() + 4), vo), is));
    const __m256d l = _mm256_min_pd(x, _mm256_set1_pd(t_max * WideFusedRay::kMargin));
    const __m256d h = _mm256_max_pd(l, _mm256_set1_pd(0x1p-126));
    const __m256d big = _mm256_set1_pd(0x1p60);
    const __m256d in = _mm256_and_pd(
        _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(_mm256_and_pd(vo, abs_mask), big, _CMP_LE_OQ), _mm256_cmp_pd(ai, big, _CMP_LE_OQ)),
                      _mm256_cmp_pd(ai, _mm256_set1_pd(0x1p-60), _CMP_GE_OQ)),
        _mm256_and_pd(_mm256_cmp_pd(ap, _mm256_set1_pd(0x1p63), _CMP_LE_OQ), _mm256_cmp_pd(l, _mm256_set1_pd(0x1p61), _CMP_LE_OQ)));
    if (!((_mm256_movemask_pd(in) == 15) & (coordinate_bound <= 0x1p60))) {
      e_out = 0.0f;
      return false;
    }
    // 2^-23 with the sign of o inv: (1 +- 2^-23) 1 / d, exact in double, makes p + |p| 2^-23
    const __m256d c = _mm256_or_pd(_mm256_and_pd(_mm256_xor_pd(vo, vi), _mm256_set1_pd(-0.0)), _mm256_set1_pd(0x1p-23));
    const __m256d one = _mm256_set1_pd(1.0);
    const __m128 near = _mm256_cvtpd_ps(_mm256_fmadd_pd(vo, _mm256_mul_pd(fi, _mm256_add_pd(one, c)), h));
    const __m128 farf = _mm256_cvtpd_ps(_mm256_fmsub_pd(vo, _mm256_mul_pd(fi, _mm256_sub_pd(one, c)), h));
    const __m256d eb = _mm256_add_pd(_mm256_mul_pd(h, _mm256_set1_pd(0x1.00001p0)), _mm256_mul_pd(ap, _mm256_set1_pd(0x1p-22)));
    const __m128d e2 = _mm_max_pd(_mm256_castpd256_pd128(eb), _mm256_extractf128_pd(eb, 1));
    e_out = static_cast<float>(_mm_cvtsd_f64(_mm_max_sd(e2, _mm_unpackhi_pd(e2, e2))) + 0x1p-99);
    const __m256 i2 = _mm256_insertf128_ps(_mm256_castps128_ps256(invf), invf, 1);
    const __m256 n2 = _mm256_insertf128_ps(_mm256_castps128_ps256(near), near, 1);
    const __m256 f2 = _mm256_insertf128_ps(_mm256_castps128_ps256(farf), farf, 1);
    inv[0] = _mm256_permute_ps(i2, 0x00), inv[1] = _mm256_permute_ps(i2, 0x55), inv[2] = _mm256_permute_ps(i2, 0xAA);
    oi[0] = _mm256_permute_ps(n2, 0x00), oi[1] = _mm256_permute_ps(n2, 0x55), oi[2] = _mm256_permute_ps(n2, 0xAA);
    oi[3] = _mm256_permute_ps(f2, 0x00), oi[4] = _mm256_permute_ps(f2, 0x55), oi[5] = _mm256_permute_ps(f2, 0xAA);
    std::memcpy(planes, kPlanes[_mm256_movemask_pd(vi)], sizeof planes);  // (bit i: 1 / d_i negative; bit 3: 0)
    return true;
  }
  /// The state from a WideFusedRay (a usable one: for rays in float).
  IMPACT_WIDE_FMA_TARGET void set(const WideFusedRay& r) {
    for (int i = 0; i < 3; ++i) {
      inv[i] = _mm256_set1_ps(r.inv[i]);
      planes[i] = r.planes[i];
      planes[3 + i] = r.planes[3 + i];
    }
    for (int j = 0; j < 6; ++j) oi[j] = _mm256_set1_ps(r.oi[j]);
  }

  /// kPlanes[sign]: WideFusedRay::planes for the direction's sign bits (bit i: component i negative).
  static constexpr int kPlanes[8][6] = {{0, 64, 128, 32, 96, 160}, {32, 64, 128, 0, 96, 160}, {0, 96, 128, 32, 64, 160},
                                        {32, 96, 128, 0, 64, 160}, {0, 64, 160, 32, 96, 128}, {32, 64, 160, 0, 96, 128},
                                        {0, 96, 160, 32, 64, 128}, {32, 96, 160, 0, 64, 128}};

  /// WideFusedRay::entered_scalar of the eight children at once, the keys left in a register and
  /// the comparison's lanes in `in` (all ones where entered).
  IMPACT_WIDE_FMA_TARGET int entered(const WideBvhNode8& n, __m256 bound, __m256& keys, __m256& in) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    __m256 a[3], b[3];
    for (int i = 0; i < 3; ++i) {
      a[i] = _mm256_fmsub_ps(_mm256_load_ps(reinterpret_cast<const float*>(p + planes[i])), inv[i], oi[i]);
      b[i] = _mm256_fmsub_ps(_mm256_load_ps(reinterpret_cast<const float*>(p + planes[3 + i])), inv[i], oi[3 + i]);
    }
    keys = _mm256_max_ps(_mm256_max_ps(a[0], a[1]), _mm256_max_ps(a[2], _mm256_setzero_ps()));
    in = _mm256_cmp_ps(keys, _mm256_min_ps(_mm256_min_ps(b[0], b[1]), _mm256_min_ps(b[2], bound)), _CMP_LE_OQ);
    return _mm256_movemask_ps(in);
  }
  /// entered() with the keys stored (for the tests).
  IMPACT_WIDE_FMA_TARGET int entered(const WideBvhNode8& n, float bound, float (&keys)[8]) const {
    __m256 lo, in;
    const int m = entered(n, _mm256_set1_ps(bound), lo, in);
    _mm256_storeu_ps(keys, lo);
    return m;
  }
};
#endif

}  // namespace detail
}  // namespace impact
