// SPDX-License-Identifier: MIT
/// \file
/// The node test of the 8-wide AVX cast (query/ray_wide_bvh.hpp): the slab test of one ray
/// against the eight float boxes of a WideBvhNode8 with one fused multiply-add a plane,
/// b * (1 / d) - o * (1 / d), the near and far planes chosen once per ray by the direction's signs,
/// and one multiply-add each after the reductions that widens the entry and exit by a bound on
/// the rounding, so that the test enters every box the double slab test (WideSlab,
/// query/wide_slab.hpp) enters, its key never above WideSlab's entry. WideFusedRay holds the
/// per-ray values (made in double, rounded once to float); entered_scalar is the test as a scalar
/// loop of the same IEEE operations (std::fma), the AVX test (compiled for AVX and FMA by a target
/// attribute on GCC and Clang for x86, used when the CPU has both: wide_fma_available) gives the
/// same keys and mask bit for bit. The error bound is proved in docs/rays.md (issue 14, the
/// node test in one multiply-add a plane) and tested in tests/query/test_ray_wide_bvh8.cpp.
#pragma once

#include "impact/bvh/wide_bvh.hpp"
#include "impact/core/types.hpp"
#include "impact/query/wide_slab.hpp"

#include <algorithm>
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
/// float), oi[i] = float(o_i * inv[i]) (the product in double, then rounded), e a float >=
/// 2^-23 M + 2^-100 with M = max_i |o_i inv[i]| (in double; error_bound). A plane b's parameter is
/// p = fma(b, inv, -oi), within 2.01 u |t| + 0.51 e of the exact (b - o) / d (u = 2^-24); the
/// entry t0 = max(0, near planes) becomes lo = fma(t0, 1 - 2^-19, -e), the exit t1 = min(t_max
/// rounded up, far planes) becomes hi = fma(t1, 1 + 2^-19, e), and a child is entered when
/// lo <= min(hi, bound). The maxima and minima are taken as trees, (a0 max a1) max (a2 max 0),
/// two deep rather than three on the node loop's dependent chain: no operand is NaN (see
/// WideFusedAvx::entered), so any order gives the same values up to the sign of a zero, which
/// the corrections turn into the same -e or e: the keys and masks of any order, bit for bit.
/// Usable for origins and tree coordinates within 2^60, 1 / d within [2^-60, 2^60] in magnitude and M <= 2^63 (so e < 2^41: an empty slot, lower plane FLT_MAX and
/// upper -FLT_MAX, gives lo > 2^66 > 0 > hi and is never entered).
struct WideFusedRay {
  static constexpr float kLow = 1.0f - 0x1p-19f, kHigh = 1.0f + 0x1p-19f;
  float inv[3], oi[3];
  float e = 0.0f;
  int planes[6];  // byte offsets in a WideBvhNode8 of the near planes of x, y, z, then of the far ones
  bool ok = false;

  /// The values of the ray (o, inv = 1 / d computed in S); `coordinate_bound` bounds the tree's
  /// coordinates (WideBvh::coordinate_bound).
  template <class S> WideFusedRay(const Vec3<S>& o, const Vec3<S>& inv_d, S coordinate_bound) {
    bool in = double(coordinate_bound) <= 0x1p60;
    double m = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double od = double(o[i]), id = double(inv_d[i]), ai = std::abs(id);
      in = in & (std::abs(od) <= 0x1p60) & (ai <= 0x1p60) & (ai >= 0x1p-60);  // false for NaN
      inv[i] = static_cast<float>(id);
      const double p = od * double(inv[i]);
      oi[i] = static_cast<float>(p);
      m = std::max(m, std::abs(p));
      planes[i] = static_cast<int>(sizeof(float[8])) * (2 * i + (id < 0.0 ? 1 : 0));
      planes[3 + i] = planes[i] ^ static_cast<int>(sizeof(float[8]));
    }
    ok = in && m <= 0x1p63;
    e = ok ? error_bound(m) : 0.0f;
  }
  /// e for M = m: at least 2^-23 M + 2^-100 (the double operations and the rounding to float
  /// lose less than the 2^-20 M 2^-23 and 2^-100 added for them), in three operations.
  static float error_bound(double m) { return static_cast<float>(m * 0x1.00001p-23 + 0x1p-99); }
  /// False when some magnitude is out of range (see above): the cast uses another node test.
  bool usable() const { return ok; }

  /// The children of `n` entered before `bound` (bit c), keys[c] = lo[c] (the others anything);
  /// `t_max_up` a float >= t_max. The AVX test's operations one lane at a time.
  int entered_scalar(const WideBvhNode8& n, float t_max_up, float bound, float (&keys)[8]) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    // maxps / minps: the second operand unless the first wins
    const auto maxps = [](float x, float y) { return x > y ? x : y; };
    const auto minps = [](float x, float y) { return x < y ? x : y; };
    int mask = 0;
    for (int c = 0; c < 8; ++c) {
      float a[3], b[3];
      for (int i = 0; i < 3; ++i) {
        a[i] = std::fma(reinterpret_cast<const float*>(p + planes[i])[c], inv[i], -oi[i]);
        b[i] = std::fma(reinterpret_cast<const float*>(p + planes[3 + i])[c], inv[i], -oi[i]);
      }
      const float t0 = maxps(maxps(a[0], a[1]), maxps(a[2], 0.0f)), t1 = minps(minps(b[0], b[1]), minps(b[2], t_max_up));
      const float lo = std::fma(t0, kLow, -e), hi = std::fma(t1, kHigh, e);
      keys[c] = lo;
      mask |= (lo <= minps(hi, bound) ? 1 : 0) << c;
    }
    return mask;
  }
};

#if defined(IMPACT_WIDE_AVX)
/// The fused node test in 256-bit AVX with FMA (call only when wide_fma_available()).
struct WideFusedAvx {
  __m256 inv[3], oi[3], e;  // WideFusedRay's values broadcast
  int planes[6];

  /// The state of a ray in double, in one pass of 256-bit AVX over the three axes: WideFusedRay's
  /// checks and values bit for bit (tested). False when WideFusedRay would not be usable; `e` gets
  /// its e (0 when not usable). Its limits (2^60) are within CoordinateRange<double>: the public
  /// 8-wide cast relies on them as its argument check (query/ray_wide_bvh.hpp).
  IMPACT_WIDE_FMA_TARGET bool set(const Vec3<double>& o, const Vec3<double>& inv_d, double coordinate_bound, float& e_out) {
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
    // (x, y, z, 0) and (1/dx, 1/dy, 1/dz, 1): the fourth lane passes every check and adds 0 to M
    const __m256d vo = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(o.data())), _mm_load_sd(o.data() + 2), 1);
    const __m256d vi = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(inv_d.data())), _mm_set_pd(1.0, inv_d[2]), 1);
    const __m256d ai = _mm256_and_pd(vi, abs_mask);
    const __m256d big = _mm256_set1_pd(0x1p60);
    const __m256d in = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(_mm256_and_pd(vo, abs_mask), big, _CMP_LE_OQ), _mm256_cmp_pd(ai, big, _CMP_LE_OQ)),
                                     _mm256_cmp_pd(ai, _mm256_set1_pd(0x1p-60), _CMP_GE_OQ));
    const __m128 invf = _mm256_cvtpd_ps(vi);
    const __m256d p = _mm256_mul_pd(vo, _mm256_cvtps_pd(invf));
    const __m128 oif = _mm256_cvtpd_ps(p);
    const __m256d ap = _mm256_and_pd(p, abs_mask);
    const __m128d m2 = _mm_max_pd(_mm256_castpd256_pd128(ap), _mm256_extractf128_pd(ap, 1));
    const double m = _mm_cvtsd_f64(_mm_max_sd(m2, _mm_unpackhi_pd(m2, m2)));  // (NaN only when a check fails)
    if (!((_mm256_movemask_pd(in) == 15) & (coordinate_bound <= 0x1p60) & (m <= 0x1p63))) {
      e_out = 0.0f;
      return false;
    }
    e_out = WideFusedRay::error_bound(m);
    const __m256 i2 = _mm256_insertf128_ps(_mm256_castps128_ps256(invf), invf, 1);
    const __m256 o2 = _mm256_insertf128_ps(_mm256_castps128_ps256(oif), oif, 1);
    inv[0] = _mm256_permute_ps(i2, 0x00), inv[1] = _mm256_permute_ps(i2, 0x55), inv[2] = _mm256_permute_ps(i2, 0xAA);
    oi[0] = _mm256_permute_ps(o2, 0x00), oi[1] = _mm256_permute_ps(o2, 0x55), oi[2] = _mm256_permute_ps(o2, 0xAA);
    e = _mm256_set1_ps(e_out);
    std::memcpy(planes, kPlanes[_mm256_movemask_pd(vi)], sizeof planes);  // (bit i: 1 / d_i negative; bit 3: 0)
    return true;
  }
  /// The state from a WideFusedRay (a usable one: for rays in float).
  IMPACT_WIDE_FMA_TARGET void set(const WideFusedRay& r) {
    for (int i = 0; i < 3; ++i) {
      inv[i] = _mm256_set1_ps(r.inv[i]);
      oi[i] = _mm256_set1_ps(r.oi[i]);
      planes[i] = r.planes[i];
      planes[3 + i] = r.planes[3 + i];
    }
    e = _mm256_set1_ps(r.e);
  }

  /// kPlanes[sign]: WideFusedRay::planes for the direction's sign bits (bit i: component i negative).
  static constexpr int kPlanes[8][6] = {{0, 64, 128, 32, 96, 160}, {32, 64, 128, 0, 96, 160}, {0, 96, 128, 32, 64, 160},
                                        {32, 96, 128, 0, 64, 160}, {0, 64, 160, 32, 96, 128}, {32, 64, 160, 0, 96, 128},
                                        {0, 96, 160, 32, 64, 128}, {32, 96, 160, 0, 64, 128}};

  /// WideFusedRay::entered_scalar of the eight children at once, the keys left in a register.
  IMPACT_WIDE_FMA_TARGET int entered(const WideBvhNode8& n, __m256 t_max_up, __m256 bound, __m256& keys) const {
    __m256 in;
    return entered(n, t_max_up, bound, keys, in);
  }
  /// entered() with the comparison's lanes too (all ones where entered).
  IMPACT_WIDE_FMA_TARGET int entered(const WideBvhNode8& n, __m256 t_max_up, __m256 bound, __m256& keys, __m256& in) const {
    const char* p = reinterpret_cast<const char*>(n.bounds);
    __m256 a[3], b[3];
    for (int i = 0; i < 3; ++i) {
      a[i] = _mm256_fmsub_ps(_mm256_load_ps(reinterpret_cast<const float*>(p + planes[i])), inv[i], oi[i]);
      b[i] = _mm256_fmsub_ps(_mm256_load_ps(reinterpret_cast<const float*>(p + planes[3 + i])), inv[i], oi[i]);
    }
    // No operand is NaN (a usable ray's products are finite or infinite, no sum adds opposite
    // infinities), so the order of the maxima and minima changes at most the sign of a zero:
    // taken as trees, two deep on the node loop's dependent chain instead of three.
    const __m256 t0 = _mm256_max_ps(_mm256_max_ps(a[0], a[1]), _mm256_max_ps(a[2], _mm256_setzero_ps()));
    const __m256 t1 = _mm256_min_ps(_mm256_min_ps(b[0], b[1]), _mm256_min_ps(b[2], t_max_up));
    const __m256 lo = _mm256_fmsub_ps(t0, _mm256_set1_ps(WideFusedRay::kLow), e);
    const __m256 hi = _mm256_fmadd_ps(t1, _mm256_set1_ps(WideFusedRay::kHigh), e);
    keys = lo;
    // lo <= hi and lo <= bound as one comparison (two side by side and an `and`, one operation
    // shorter on the chain, measured no faster: docs/rays.md)
    in = _mm256_cmp_ps(lo, _mm256_min_ps(hi, bound), _CMP_LE_OQ);
    return _mm256_movemask_ps(in);
  }
  /// entered() with the keys stored (for the tests).
  IMPACT_WIDE_FMA_TARGET int entered(const WideBvhNode8& n, float t_max_up, float bound, float (&keys)[8]) const {
    __m256 lo;
    const int m = entered(n, _mm256_set1_ps(t_max_up), _mm256_set1_ps(bound), lo);
    _mm256_storeu_ps(keys, lo);
    return m;
  }
};
#endif

}  // namespace detail
}  // namespace impact
