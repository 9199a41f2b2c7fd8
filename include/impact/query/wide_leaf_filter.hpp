// SPDX-License-Identifier: MIT
/// \file
/// The certified float filter of a WideBvh's leaves (LeafFilter, SSE only): four leaf-order
/// float triangles at once, a triangle skipped only when the watertight ray-triangle test
/// (intersect_ray_triangle) is certain to reject it, so that a cast through the filter returns the
/// test's answers bit for bit. The bounds it relies on are stated on the class. Used by
/// query/ray_wide_bvh.hpp for trees whose triangles are stored as floats.
#pragma once

#include "impact/core/types.hpp"
#include "impact/narrow/ray_triangle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace impact {
namespace detail {

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

}  // namespace detail
}  // namespace impact
