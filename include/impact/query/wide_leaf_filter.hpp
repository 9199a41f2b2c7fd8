// SPDX-License-Identifier: MIT
/// \file
/// The leaf test of a WideBvh cast (BlockTest): the watertight ray-triangle test
/// (intersect_ray_triangle) over the four triangles of a leaf block (WideTriangleBlock, coordinate
/// by coordinate) at once, with SIMD (SSE2; in double AVX when the CPU has it, checked at run
/// time), in the scalar test's own IEEE operations, so that the lanes it passes are exactly the
/// triangles the scalar test hits and a cast through it returns the scalar test's answers bit for
/// bit. Used by query/ray_wide_bvh.hpp.
#pragma once

#include "impact/bvh/wide_bvh.hpp"
#include "impact/core/types.hpp"
#include "impact/narrow/ray_triangle.hpp"

#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// the AVX block test: compiled for AVX whatever the target, called when the CPU has it
#if defined(__SSE2__) && (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define IMPACT_BLOCK_TEST_AVX 1
#endif

namespace impact {
namespace detail {

/// The watertight test (intersect_ray_triangle) over the four triangles of a WideTriangleBlock at
/// once: the same IEEE operations in the same order as the scalar test, in S (double: two lanes an
/// SSE2 instruction; float: four), so a lane is a candidate exactly when the scalar test hits its
/// triangle (no two edge functions of opposite strict signs, det != 0, the depth in [0, t_max
/// det]); in float a lane with an edge function equal to zero, which the scalar test recomputes in
/// double, is a candidate too. The caller runs the scalar test on the candidates only. Without
/// SSE2 every lane is a candidate. In double, on a CPU with AVX (checked at run time), four lanes
/// an instruction (the same operations, so the same bits). Set up once a ray.
template <class S> class BlockTest {
 public:
  BlockTest() = default;
  /// `allow_avx` false keeps to SSE2 (for the tests that compare the two).
  void set(const PreparedRay<S>& pr, bool allow_avx = true) {
#if defined(IMPACT_BLOCK_TEST_AVX)
    avx_ = allow_avx && std::is_same_v<S, double> && avx_available();
#else
    (void)allow_avx;
#endif
    const int k[3] = {pr.kx, pr.ky, pr.kz};
    for (int i = 0; i < 3; ++i) off_[i] = k[i], o_[i] = pr.ray.origin[k[i]];
    sx_ = pr.sx, sy_ = pr.sy, sz_ = pr.sz;
    valid_ = pr.valid;
  }
  /// Bit c set when the triangle in lane c of `b` may be hit with t_max = `t_max` (see the class
  /// comment). Lanes at and above `count` (<= 4) are clear.
  template <class T> int candidates(const WideTriangleBlock<T>& b, int count, S t_max) const {
    if (!valid_) return 0;
    const int lanes = (1 << count) - 1;
#if defined(__SSE2__)
    if constexpr (std::is_same_v<S, double>) {
#if defined(IMPACT_BLOCK_TEST_AVX)
      if (avx_) return candidates_avx(b, t_max) & lanes;
#endif
      const __m128d o0 = _mm_set1_pd(o_[0]), o1 = _mm_set1_pd(o_[1]), o2 = _mm_set1_pd(o_[2]);
      const __m128d sx = _mm_set1_pd(sx_), sy = _mm_set1_pd(sy_), sz = _mm_set1_pd(sz_);
      const __m128d tmax = _mm_set1_pd(t_max), zero = _mm_setzero_pd();
      int m = 0;
      for (int h = 0; h < 2; ++h) {
        __m128d px[3], py[3], pz[3];
        for (int v = 0; v < 3; ++v) {
          const __m128d ax = _mm_sub_pd(load2(b.v[3 * v + off_[0]] + 2 * h), o0);
          const __m128d ay = _mm_sub_pd(load2(b.v[3 * v + off_[1]] + 2 * h), o1);
          const __m128d az = _mm_sub_pd(load2(b.v[3 * v + off_[2]] + 2 * h), o2);
          px[v] = _mm_sub_pd(ax, _mm_mul_pd(sx, az));
          py[v] = _mm_sub_pd(ay, _mm_mul_pd(sy, az));
          pz[v] = _mm_mul_pd(sz, az);
        }
        const __m128d eu = _mm_sub_pd(_mm_mul_pd(px[2], py[1]), _mm_mul_pd(py[2], px[1]));
        const __m128d ev = _mm_sub_pd(_mm_mul_pd(px[0], py[2]), _mm_mul_pd(py[0], px[2]));
        const __m128d ew = _mm_sub_pd(_mm_mul_pd(px[1], py[0]), _mm_mul_pd(py[1], px[0]));
        const __m128d neg = _mm_or_pd(_mm_or_pd(_mm_cmplt_pd(eu, zero), _mm_cmplt_pd(ev, zero)), _mm_cmplt_pd(ew, zero));
        const __m128d pos = _mm_or_pd(_mm_or_pd(_mm_cmpgt_pd(eu, zero), _mm_cmpgt_pd(ev, zero)), _mm_cmpgt_pd(ew, zero));
        const __m128d det = _mm_add_pd(_mm_add_pd(eu, ev), ew);
        const __m128d tt = _mm_add_pd(_mm_add_pd(_mm_mul_pd(eu, pz[0]), _mm_mul_pd(ev, pz[1])), _mm_mul_pd(ew, pz[2]));
        const __m128d tmd = _mm_mul_pd(tmax, det);
        const __m128d up = _mm_cmpgt_pd(det, zero);
        const __m128d out_up = _mm_or_pd(_mm_cmplt_pd(tt, zero), _mm_cmpgt_pd(tt, tmd));
        const __m128d out_down = _mm_or_pd(_mm_cmpgt_pd(tt, zero), _mm_cmplt_pd(tt, tmd));
        const __m128d miss = _mm_or_pd(_mm_or_pd(_mm_and_pd(neg, pos), _mm_cmpeq_pd(det, zero)),
                                       _mm_or_pd(_mm_and_pd(up, out_up), _mm_andnot_pd(up, out_down)));
        m |= (~_mm_movemask_pd(miss) & 3) << (2 * h);
      }
      return m & lanes;
    } else {
      const __m128 o0 = _mm_set1_ps(o_[0]), o1 = _mm_set1_ps(o_[1]), o2 = _mm_set1_ps(o_[2]);
      const __m128 sx = _mm_set1_ps(sx_), sy = _mm_set1_ps(sy_), sz = _mm_set1_ps(sz_);
      const __m128 tmax = _mm_set1_ps(t_max), zero = _mm_setzero_ps();
      __m128 px[3], py[3], pz[3];
      for (int v = 0; v < 3; ++v) {
        const __m128 ax = _mm_sub_ps(_mm_load_ps(b.v[3 * v + off_[0]]), o0);
        const __m128 ay = _mm_sub_ps(_mm_load_ps(b.v[3 * v + off_[1]]), o1);
        const __m128 az = _mm_sub_ps(_mm_load_ps(b.v[3 * v + off_[2]]), o2);
        px[v] = _mm_sub_ps(ax, _mm_mul_ps(sx, az));
        py[v] = _mm_sub_ps(ay, _mm_mul_ps(sy, az));
        pz[v] = _mm_mul_ps(sz, az);
      }
      const __m128 eu = _mm_sub_ps(_mm_mul_ps(px[2], py[1]), _mm_mul_ps(py[2], px[1]));
      const __m128 ev = _mm_sub_ps(_mm_mul_ps(px[0], py[2]), _mm_mul_ps(py[0], px[2]));
      const __m128 ew = _mm_sub_ps(_mm_mul_ps(px[1], py[0]), _mm_mul_ps(py[1], px[0]));
      const __m128 some_zero = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(eu, zero), _mm_cmpeq_ps(ev, zero)), _mm_cmpeq_ps(ew, zero));
      const __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(eu, zero), _mm_cmplt_ps(ev, zero)), _mm_cmplt_ps(ew, zero));
      const __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(eu, zero), _mm_cmpgt_ps(ev, zero)), _mm_cmpgt_ps(ew, zero));
      const __m128 det = _mm_add_ps(_mm_add_ps(eu, ev), ew);
      const __m128 tt = _mm_add_ps(_mm_add_ps(_mm_mul_ps(eu, pz[0]), _mm_mul_ps(ev, pz[1])), _mm_mul_ps(ew, pz[2]));
      const __m128 tmd = _mm_mul_ps(tmax, det);
      const __m128 up = _mm_cmpgt_ps(det, zero);
      const __m128 out_up = _mm_or_ps(_mm_cmplt_ps(tt, zero), _mm_cmpgt_ps(tt, tmd));
      const __m128 out_down = _mm_or_ps(_mm_cmpgt_ps(tt, zero), _mm_cmplt_ps(tt, tmd));
      const __m128 miss = _mm_or_ps(_mm_or_ps(_mm_and_ps(neg, pos), _mm_cmpeq_ps(det, zero)),
                                    _mm_or_ps(_mm_and_ps(up, out_up), _mm_andnot_ps(up, out_down)));
      return ~_mm_movemask_ps(_mm_andnot_ps(some_zero, miss)) & lanes;
    }
#else
    (void)b;
    (void)t_max;
    return lanes;
#endif
  }

 private:
#if defined(IMPACT_BLOCK_TEST_AVX)
  static bool avx_available() {
    static const bool avx = __builtin_cpu_supports("avx");
    return avx;
  }
  __attribute__((target("avx"))) static __m256d load4(const float* f) { return _mm256_cvtps_pd(_mm_load_ps(f)); }
  __attribute__((target("avx"))) static __m256d load4(const double* f) { return _mm256_load_pd(f); }
  /// The double test of the four lanes in 256-bit AVX (no FMA: the scalar test's roundings).
  template <class T> __attribute__((target("avx"))) int candidates_avx(const WideTriangleBlock<T>& b, S t_max) const {
    const __m256d o0 = _mm256_set1_pd(o_[0]), o1 = _mm256_set1_pd(o_[1]), o2 = _mm256_set1_pd(o_[2]);
    const __m256d sx = _mm256_set1_pd(sx_), sy = _mm256_set1_pd(sy_), sz = _mm256_set1_pd(sz_);
    const __m256d tmax = _mm256_set1_pd(t_max), zero = _mm256_setzero_pd();
    __m256d px[3], py[3], pz[3];
    for (int v = 0; v < 3; ++v) {
      const __m256d ax = _mm256_sub_pd(load4(b.v[3 * v + off_[0]]), o0);
      const __m256d ay = _mm256_sub_pd(load4(b.v[3 * v + off_[1]]), o1);
      const __m256d az = _mm256_sub_pd(load4(b.v[3 * v + off_[2]]), o2);
      px[v] = _mm256_sub_pd(ax, _mm256_mul_pd(sx, az));
      py[v] = _mm256_sub_pd(ay, _mm256_mul_pd(sy, az));
      pz[v] = _mm256_mul_pd(sz, az);
    }
    const __m256d eu = _mm256_sub_pd(_mm256_mul_pd(px[2], py[1]), _mm256_mul_pd(py[2], px[1]));
    const __m256d ev = _mm256_sub_pd(_mm256_mul_pd(px[0], py[2]), _mm256_mul_pd(py[0], px[2]));
    const __m256d ew = _mm256_sub_pd(_mm256_mul_pd(px[1], py[0]), _mm256_mul_pd(py[1], px[0]));
    const __m256d neg = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(eu, zero, _CMP_LT_OQ), _mm256_cmp_pd(ev, zero, _CMP_LT_OQ)),
                                     _mm256_cmp_pd(ew, zero, _CMP_LT_OQ));
    const __m256d pos = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(eu, zero, _CMP_GT_OQ), _mm256_cmp_pd(ev, zero, _CMP_GT_OQ)),
                                     _mm256_cmp_pd(ew, zero, _CMP_GT_OQ));
    const __m256d det = _mm256_add_pd(_mm256_add_pd(eu, ev), ew);
    const __m256d tt = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(eu, pz[0]), _mm256_mul_pd(ev, pz[1])), _mm256_mul_pd(ew, pz[2]));
    const __m256d tmd = _mm256_mul_pd(tmax, det);
    const __m256d up = _mm256_cmp_pd(det, zero, _CMP_GT_OQ);
    const __m256d out_up = _mm256_or_pd(_mm256_cmp_pd(tt, zero, _CMP_LT_OQ), _mm256_cmp_pd(tt, tmd, _CMP_GT_OQ));
    const __m256d out_down = _mm256_or_pd(_mm256_cmp_pd(tt, zero, _CMP_GT_OQ), _mm256_cmp_pd(tt, tmd, _CMP_LT_OQ));
    const __m256d miss = _mm256_or_pd(_mm256_or_pd(_mm256_and_pd(neg, pos), _mm256_cmp_pd(det, zero, _CMP_EQ_OQ)),
                                      _mm256_or_pd(_mm256_and_pd(up, out_up), _mm256_andnot_pd(up, out_down)));
    return ~_mm256_movemask_pd(miss) & 15;
  }
  bool avx_ = false;
#endif
#if defined(__SSE2__)
  static __m128d load2(const float* f) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f)))); }
  static __m128d load2(const double* f) { return _mm_load_pd(f); }
#endif
  int off_[3] = {0, 1, 2};  // the block's rows of the ray frame's x, y, z axes (kx, ky, kz)
  S o_[3] = {S(0), S(0), S(0)}, sx_ = S(0), sy_ = S(0), sz_ = S(1);
  bool valid_ = false;
};

}  // namespace detail
}  // namespace impact
