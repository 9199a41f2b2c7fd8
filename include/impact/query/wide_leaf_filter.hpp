// SPDX-License-Identifier: MIT
/// \file
/// The leaf test of a WideBvh cast (BlockTest): the watertight ray-triangle test
/// (intersect_ray_triangle) over the four triangles of a leaf block (WideTriangleBlock, coordinate
/// by coordinate) at once, with SIMD (SSE2; in double AVX when the CPU has it, checked at run
/// time), in the scalar test's own IEEE operations, so that the lanes it passes include every
/// triangle the scalar test hits and a cast through it returns the scalar test's answers bit for
/// bit: a lane with an edge function within the ray's bound of the error bands (PreparedRay::band,
/// narrow/ray_triangle.hpp), where the scalar test may take an exact sign, is passed as "near an
/// edge" for the scalar test to decide. Used by query/ray_wide_bvh.hpp.
#pragma once

#include "impact/bvh/wide_bvh.hpp"
#include "impact/core/types.hpp"
#include "impact/narrow/ray_triangle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

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

/// A bound of the rounding error of the depth tt the leaf tests compute (BlockTest: the scalar
/// test's operations in double) for every triangle inside the box [lo, hi], for the ray from `o`
/// with the shear factor `sz` (all in the ray's frame kx, ky, kz): an origin exactly in a
/// triangle's plane gives |tt| <= this bound whenever tt is finite; so a finite tt above it proves
/// the origin off the plane (the test of in_plane_lanes is then not needed). +infinity or NaN when
/// a value overflows (no lane is then proven off the plane).
///
/// Derivation (u = 2^-53; eta = 2^-1075 bounds a product's loss to underflow; sums are exact
/// when subnormal). The lanes compute, for each vertex v, ax = fl(v_kx - o_kx) (ay, az likewise),
/// px = fl(ax - fl(sx az)), py = fl(ay - fl(sy az)), pz = fl(sz az), the edge functions eu =
/// fl(fl(px_c py_b) - fl(py_c px_b)) (ev, ew cyclically) and tt = fl(fl(fl(eu pz_a) + fl(ev pz_b)) +
/// fl(ew pz_c)). In the model with exact differences and the rounded sx, sy, sz taken as exact,
/// P = (X - sx Z, Y - sy Z, sz Z) is a linear map of determinant sz of v - o, and the exact depth
/// T = Eu Pz_a + Ev Pz_b + Ew Pz_c = -det[P_a; P_b; P_c] = -+ sz det[a - o; b - o; c - o]: 0 when o
/// lies in the plane, whatever sx, sy, sz. So |tt| <= |tt - T| there. With R_i >= |v_i - o_i| for
/// every vertex in the box, |sx|, |sy| <= 1 (|d_kz| is the largest), each vertex has mx = |X| + |sx||Z|
/// <= Mx = R_x + R_z, my <= My = R_y + R_z, mz = |sz Z| <= Mz = |sz| R_z. From the file comment of
/// narrow/ray_triangle.hpp (the shear and the edge functions' error, derived there against the exact
/// ratio s = d_kx / d_kz with its rounding among the four of g4; against the rounded s taken as exact
/// one rounding fewer, so the same bounds hold): |e - E| <= (10u + 65u^2) 2 Mx My
/// + 2.02 eta (Mx + My) + 2.01 eta, |E| <= 2 Mx My; |pz - Pz| <= g2 Mz + eta, |pz| <= (1 + g2) Mz + eta
/// (g_k = k u / (1 - k u)); the three products and two sums of tt: |tt - sum e pz| <= g3 sum |e pz| +
/// 3 (1 + u)^2 eta; and |e pz - E Pz| <= |e - E| |pz| + |E| |pz - Pz|. Summed over the three terms:
/// |tt - T| <= (3 (20u + 4u + 6u) + 1000 u^2) Mx My Mz + 6.2 eta (Mx My + (Mx + My + 1) Mz + 1).
/// The computed bound is K Mx My Mz + U (Mx My + (Mx + My + 1) Mz + 1) with K = 96u >= 90u + 1000u^2
/// and U = 2^-1000 = 2^75 eta, from the computed R (|fl(lo - o)|, |fl(hi - o)|: each at least (1 - u)
/// times the exact one, rounding being monotone) and nonnegative rounded sums and products: each
/// rounding loses at most a factor (1 - u) (ten on the way to the K term: less than K's slack of 6u) or
/// eta for a product (the products' losses, times factors at most K or 1, are covered by the U term,
/// itself at least 2^-1000, never subnormal). Overflow makes tt or the bound infinite or NaN, so a
/// lane is taken as off the plane only when its tt is finite (then no operation overflowed).
inline double box_plane_bound(const double (&o)[3], const double (&lo)[3], const double (&hi)[3], double sz) {
  double r[3];
  for (int i = 0; i < 3; ++i) {
    const double a = std::abs(lo[i] - o[i]), b = std::abs(hi[i] - o[i]);
    r[i] = a > b ? a : b;
  }
  const double mx = r[0] + r[2], my = r[1] + r[2], mz = std::abs(sz) * r[2];
  const double mxy = mx * my;
  return 96.0 * 0x1p-53 * (mxy * mz) + 0x1p-1000 * ((mxy + ((mx + my) + 1.0) * mz) + 1.0);
}

/// The watertight test (intersect_ray_triangle) over the four triangles of a WideTriangleBlock at
/// once: the same IEEE operations in the same order as the scalar test, in S (double: two lanes an
/// SSE2 instruction; float: four). A lane with an edge function not above the ray's band bound
/// (`band`: PreparedRay::band for triangles in the tree's box, +infinity when not set) is near an
/// edge: a candidate, which the scalar test decides (it may take exact signs there). So is a lane
/// inside its triangle's edges whose depth tt lies behind the origin, or a hit lane whose origin
/// neither its depth (finite and above box_plane_bound) nor orient3d's filter places off the
/// triangle's plane (the scalar test then asks whether the origin lies exactly in the plane: a hit
/// at t = 0). Any other
/// lane is a candidate exactly when the scalar test hits its triangle (no two edge functions of
/// opposite strict signs, det != 0, the depth in [0, t_max det]), as the scalar test takes its
/// values as they are. The caller runs the scalar test on the candidates only (in double, the
/// lanes not near an edge may be finished from their values). Without SSE2 every lane is a
/// candidate. In double, on a CPU with AVX (checked at run time), four lanes an instruction (the
/// same operations, so the same bits). Set up once a ray.
template <class S> class BlockTest {
 public:
  /// The scalar test's intermediate values of a block's four lanes, as the SIMD test computed
  /// them (the same bits): the edge functions, their sum det and the scaled depth tt. A lane the
  /// test passed is hit with a bound t_max unless tt is outside [0, t_max det] (det > 0) or
  /// [t_max det, 0] (det < 0); then t = min(tt / det, t_max) and the barycentrics are e / det, as
  /// detail::finish_ray_hit computes them.
  /// `near` has bit c set when lane c is near an edge: its values must not be used (the scalar
  /// test decides it). Left uninitialised (a leaf visit pays only for the lanes it tests):
  /// candidates() writes all four lanes and `near` whenever it passes one, and only a passed lane
  /// is read.
  struct alignas(32) LaneValues {
    S eu[4], ev[4], ew[4], det[4], tt[4];  // NOLINT(cppcoreguidelines-pro-type-member-init)
    int near;                              // NOLINT(cppcoreguidelines-pro-type-member-init)
  };
  /// True when candidates() fills LaneValues (S = double with SSE2: the lanes are computed in
  /// the scalar test's operations, no recomputation in double as for float).
#if defined(__SSE2__)
  static constexpr bool kHasValues = std::is_same_v<S, double>;
#else
  static constexpr bool kHasValues = false;
#endif

  BlockTest() : off_{0, 1, 2}, o_{S(0), S(0), S(0)}, sx_(S(0)), sy_(S(0)), sz_(S(1)), band_(std::numeric_limits<S>::infinity()), plane_bound_(std::numeric_limits<S>::infinity()), valid_(false) {
#if defined(IMPACT_BLOCK_TEST_AVX)
    for (int i = 0; i < 3; ++i) box_o_[i] = box_inv_[i] = S(0);
#endif
  }
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
    band_ = pr.band;
    plane_bound_ = std::numeric_limits<S>::infinity();
    valid_ = pr.valid;
  }
  /// Sets the band bound for triangles inside the box [lo, hi] (original axes), as
  /// PreparedRay::bound_band does (the same value for the same ray and box), and in double the
  /// bound of the depth's rounding error for an origin in a triangle's plane (box_plane_bound:
  /// a hit lane with a finite depth above it needs no in-plane test). Until it is called (and in
  /// float) every hit lane gets the in-plane test.
  void bound_band(const Vec3<S>& lo, const Vec3<S>& hi) {
    const S l[3] = {lo[off_[0]], lo[off_[1]], lo[off_[2]]}, h[3] = {hi[off_[0]], hi[off_[1]], hi[off_[2]]};
    band_ = box_edge_band(o_, l, h);
    if constexpr (std::is_same_v<S, double>) plane_bound_ = box_plane_bound(o_, l, h, sz_);
  }
  /// bound_band's bound of the depth only (for a test made by set() from a PreparedRay whose band
  /// bound_band already set for the same box).
  void bound_plane(const Vec3<S>& lo, const Vec3<S>& hi) {
    if constexpr (std::is_same_v<S, double>) {
      const S l[3] = {lo[off_[0]], lo[off_[1]], lo[off_[2]]}, h[3] = {hi[off_[0]], hi[off_[1]], hi[off_[2]]};
      plane_bound_ = box_plane_bound(o_, l, h, sz_);
    } else {
      (void)lo, (void)hi;
    }
  }
  /// The bound of bound_band's box for the depth of an origin in a triangle's plane (+infinity
  /// before bound_band; for the tests).
  S plane_bound() const { return plane_bound_; }
#if defined(IMPACT_BLOCK_TEST_AVX)
  /// What hits_avx gives of a block's lanes: the hit's t (raised to the entry into the triangle's
  /// box), 1 / det, the edge functions, det and the scaled depth tt, as the scalar test and
  /// detail::mesh_hit_t compute them (the same bits). Only passed lanes are meaningful. `near`:
  /// the lanes near an edge (not among the hit lanes; the scalar test decides them), written
  /// whenever hits_avx returns.
  struct alignas(32) LaneHits {
    S t[4], inv_det[4], eu[4], ev[4], ew[4], det[4], tt[4];  // NOLINT(cppcoreguidelines-pro-type-member-init)
    int near;                                                // NOLINT(cppcoreguidelines-pro-type-member-init)
  };
  /// A test made by set_ray(o, d, inv) (in place, each member written once: no zeroing first, as
  /// BlockTest() does).
  BlockTest(const Vec3<S>& o, const Vec3<S>& d, const Vec3<S>& inv) { set_ray(o, d, inv); }  // NOLINT(cppcoreguidelines-pro-type-member-init)
  /// set(PreparedRay<S>(Ray<S>(o, d))) without the PreparedRay (the same frame, shear and
  /// roundings), for S = double, with `inv` = safe_inverse(d), finite on every axis (a ray the
  /// 8-wide AVX cast takes), for the box entries of hits_avx. The band bound is +infinity (every
  /// lane near an edge) until bound_band sets it.
  void set_ray(const Vec3<S>& o, const Vec3<S>& d, const Vec3<S>& inv) {
    static_assert(std::is_same_v<S, double>, "set_ray: a ray in double");
    const S ax = std::abs(d[0]), ay = std::abs(d[1]), az = std::abs(d[2]);
    // PreparedRay's frame (kz the axis of the largest |d_i|, the first of equal ones; kx, ky the
    // next ones, swapped when d_kz < 0), without jumps: for random rays each is a coin toss
    const int xy = ax >= ay ? 1 : 0, xz = ax >= az ? 1 : 0, yz = ay >= az ? 1 : 0;
    const int kz = 2 - 2 * (xy & xz) - ((xy ^ 1) & yz);
    const int kx0 = (0x09 >> (2 * kz)) & 3, ky0 = (0x12 >> (2 * kz)) & 3;  // (kz + 1) % 3, (kz + 2) % 3
    const S dz = d[kz];
    valid_ = dz != S(0);
    const int flip = -static_cast<int>(dz < S(0));
    const int kx = kx0 ^ ((kx0 ^ ky0) & flip), ky = kx0 ^ ky0 ^ kx;
    off_[0] = kx, off_[1] = ky, off_[2] = kz;
    for (int i = 0; i < 3; ++i) o_[i] = o[off_[i]], box_o_[i] = o[i], box_inv_[i] = inv[i];
    band_ = plane_bound_ = std::numeric_limits<S>::infinity();
    if (valid_) {
      sx_ = d[kx] / dz, sy_ = d[ky] / dz, sz_ = S(1) / dz;
    } else {
      sx_ = sy_ = S(0), sz_ = S(1);
    }
    avx_ = true;
  }
  /// The lanes of `b` (the first `count`, <= 4) hit with t_max = `t_max` by the narrow-phase rule
  /// of the wide cast (detail::ray_mesh_triangle_hit: the watertight test, the hit raised to the
  /// entry into the triangle's box, the t = 0 back-face rule), four at once in 256-bit AVX: bit c
  /// set when lane c is hit, and then `h` holds its values (LaneHits); the lanes near an edge are
  /// not decided here but set in h.near, for the scalar rule. For a test made by
  /// set_ray; compiled for AVX (call only when the CPU has it). The box entry runs
  /// detail::ray_box_entry's operations on the lanes (no NaN: `inv` is finite), its vertex
  /// minimum and maximum taken before the subtraction of the origin (rounding is monotone: the
  /// same values). From code compiled for AVX, hits_avx_inline.
  template <class T> __attribute__((target("avx"))) int hits_avx(const WideTriangleBlock<T>& b, int count, S t_max, LaneHits& h) const {
    return hits_avx_inline(b, count, t_max, h);
  }
  /// hits_avx, always inlined (into callers compiled for AVX only: the AVX leaf of the cast, where
  /// Clang 14 otherwise kept it a call a block).
  template <class T>
  __attribute__((always_inline)) __attribute__((target("avx"))) int hits_avx_inline(const WideTriangleBlock<T>& b, int count, S t_max, LaneHits& h) const {
    static_assert(std::is_same_v<S, double>, "hits_avx: a ray in double");
    __m256d eu, ev, ew, det, tt;
    int near_lanes = 0;
    int m = lanes_avx(b, t_max, (1 << count) - 1, eu, ev, ew, det, tt, near_lanes);
    h.near = near_lanes;
    if (!m) return 0;
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
    const __m256d zero = _mm256_setzero_pd(), tmax = _mm256_set1_pd(t_max);
    const __m256d inv_det = _mm256_div_pd(_mm256_set1_pd(1.0), det);
    const __m256d t = _mm256_min_pd(tmax, _mm256_mul_pd(tt, inv_det));  // std::min(tt / det, t_max)
    __m256d t0 = zero, t1 = tmax;
    for (int i = 0; i < 3; ++i) {  // ray_box_entry on the triangles' boxes
      const __m256d p = load4(b.v[i]), q = load4(b.v[3 + i]), r = load4(b.v[6 + i]);
      const __m256d o = _mm256_broadcast_sd(box_o_ + i), inv = _mm256_broadcast_sd(box_inv_ + i);
      const __m256d n = _mm256_mul_pd(_mm256_sub_pd(_mm256_min_pd(_mm256_min_pd(p, q), r), o), inv);
      const __m256d f = _mm256_mul_pd(_mm256_sub_pd(_mm256_max_pd(_mm256_max_pd(p, q), r), o), inv);
      const __m256d near = _mm256_min_pd(f, n);  // n > f ? f : n (the swap)
      __m256d far = _mm256_max_pd(n, f);
      far = _mm256_add_pd(far, _mm256_mul_pd(_mm256_and_pd(far, abs_mask), _mm256_set1_pd(4.0 * std::numeric_limits<S>::epsilon())));
      t0 = _mm256_max_pd(near, t0);
      t1 = _mm256_min_pd(far, t1);
    }
    const __m256d th = _mm256_max_pd(t0, t);  // t < entry ? entry : t
    const __m256d back = _mm256_cmp_pd(det, zero, _CMP_LE_OQ);
    const __m256d out = _mm256_or_pd(_mm256_cmp_pd(t0, t1, _CMP_GT_OQ), _mm256_and_pd(back, _mm256_cmp_pd(th, zero, _CMP_EQ_OQ)));
    m &= ~_mm256_movemask_pd(out);
    _mm256_store_pd(h.t, th);
    _mm256_store_pd(h.inv_det, inv_det);
    _mm256_store_pd(h.eu, eu);
    _mm256_store_pd(h.ev, ev);
    _mm256_store_pd(h.ew, ew);
    _mm256_store_pd(h.det, det);
    _mm256_store_pd(h.tt, tt);
    return m;
  }
#endif
  /// Bit c set when the triangle in lane c of `b` may be hit with t_max = `t_max` (see the class
  /// comment). Lanes at and above `count` (<= 4) are clear.
  /// When kHasValues and the result is not zero, `values` holds the lanes' values (else it is
  /// left as it was).
  template <class T> int candidates(const WideTriangleBlock<T>& b, int count, S t_max, LaneValues* values = nullptr) const {
    if (!valid_) return 0;
    const int lanes = (1 << count) - 1;
#if defined(__SSE2__)
    if constexpr (std::is_same_v<S, double>) {
#if defined(IMPACT_BLOCK_TEST_AVX)
      if (avx_) return candidates_avx(b, t_max, lanes, values);
#endif
      int m = 0, near = 0;
      for (int h = 0; h < 2; ++h) {
        const int r = sse_lanes<SseDouble>(b, h, t_max, values);
        m |= (r & 3) << (2 * h);
        near |= (r >> 4) << (2 * h);
      }
      if ((m & lanes) && values) values->near = near & lanes;
      return m & lanes;
    } else {
      return sse_lanes<SseFloat>(b, 0, t_max) & lanes;
    }
#else
    (void)b;
    (void)t_max;
    return lanes;
#endif
  }

 private:
  /// The lanes of `lanes` (bit j: lane `first` + j of `b`) whose triangle may have the origin
  /// exactly in its plane, which the scalar rule then decides (finish_ray_hit: t exactly 0): those
  /// that orient3d's filter (narrow/predicates.hpp, with its underflow term) cannot place off the
  /// plane. Called with the hit lanes whose depth does not place the origin off the plane (above
  /// plane_bound_; almost none on the benches' rays: those from a surface or within rounding of
  /// one; out of line, so that the leaf test stays small enough to be inlined), in the ray frame's order of the axes (a permutation:
  /// the same magnitude). In double (the lanes' values are).
  template <class T> IMPACT_NOINLINE int in_plane_lanes(const WideTriangleBlock<T>& b, int lanes, int first) const {
    int on = 0;
    for (int m = lanes; m; m &= m - 1) {
      const int j = __builtin_ctz(static_cast<unsigned>(m)), c = first + j;
      double p[3][3];
      for (int v = 0; v < 3; ++v)
        for (int i = 0; i < 3; ++i) p[v][i] = double(b.v[3 * v + off_[i]][c]);
      const double ux = p[1][0] - p[0][0], uy = p[1][1] - p[0][1], uz = p[1][2] - p[0][2];
      const double vx = p[2][0] - p[0][0], vy = p[2][1] - p[0][1], vz = p[2][2] - p[0][2];
      const double n[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
      const double q[3] = {std::fabs(uy * vz) + std::fabs(uz * vy), std::fabs(uz * vx) + std::fabs(ux * vz), std::fabs(ux * vy) + std::fabs(uy * vx)};
      const double o[3] = {double(o_[0]), double(o_[1]), double(o_[2])};
      const int s = orient3d_filtered(p[0], n, q, o, uv_safe(ux, uy, uz, vx, vy, vz));
      if (s == 0 || s == 2) on |= 1 << j;
    }
    return on;
  }
#if defined(IMPACT_BLOCK_TEST_AVX)
  static bool avx_available() {
    static const bool avx = __builtin_cpu_supports("avx");
    return avx;
  }
  /// `w` as it is, through an empty asm statement (no instruction): the compiler cannot see how
  /// it was made, so it cannot merge it with later masks (lanes_avx).
  static int opaque_word(int w) {
    __asm__("" : "+r"(w));
    return w;
  }
  __attribute__((target("avx"))) static __m256d load4(const float* f) { return _mm256_cvtps_pd(_mm_load_ps(f)); }
  __attribute__((target("avx"))) static __m256d load4(const double* f) { return _mm256_load_pd(f); }
  /// The double test of the four lanes in 256-bit AVX (no FMA: the scalar test's roundings).
  template <class T> __attribute__((target("avx"))) int candidates_avx(const WideTriangleBlock<T>& b, S t_max, int lanes, LaneValues* values) const {
    // (zeroed: g++ cannot see that lanes_avx writes them whenever m is not 0)
    __m256d eu = _mm256_setzero_pd(), ev = eu, ew = eu, det = eu, tt = eu;
    int near_lanes = 0;
    const int m = lanes_avx(b, t_max, lanes, eu, ev, ew, det, tt, near_lanes);
    if (values && (m | near_lanes)) values->near = near_lanes;
    if (m && values) {
      _mm256_store_pd(values->eu, eu);
      _mm256_store_pd(values->ev, ev);
      _mm256_store_pd(values->ew, ew);
      _mm256_store_pd(values->det, det);
      _mm256_store_pd(values->tt, tt);
    }
    return m | near_lanes;
  }
  /// The lanes of `lanes` the double test passes that are not near an edge, and its values, in
  /// 256-bit AVX; `near_out` gets the lanes of `lanes` near an edge (an edge function not above
  /// band_, or NaN). Always inlined (its callers are compiled for AVX): Clang 14 kept it a call,
  /// its five vectors returned through memory (bunny, long rays: 35 instructions a cast).
  template <class T>
  __attribute__((always_inline)) __attribute__((target("avx"))) int lanes_avx(const WideTriangleBlock<T>& b, S t_max, int lanes, __m256d& eu_out, __m256d& ev_out, __m256d& ew_out,
                                               __m256d& det_out, __m256d& tt_out, int& near_out) const {
    const __m256d o0 = _mm256_broadcast_sd(o_), o1 = _mm256_broadcast_sd(o_ + 1), o2 = _mm256_broadcast_sd(o_ + 2);
    const __m256d sx = _mm256_broadcast_sd(&sx_), sy = _mm256_broadcast_sd(&sy_), sz = _mm256_broadcast_sd(&sz_);
    const __m256d tmax = _mm256_set1_pd(t_max), zero = _mm256_setzero_pd();
    __m256d px[3], py[3], az[3];
    for (int v = 0; v < 3; ++v) {
      const __m256d ax = _mm256_sub_pd(load4(b.v[3 * v + off_[0]]), o0);
      const __m256d ay = _mm256_sub_pd(load4(b.v[3 * v + off_[1]]), o1);
      az[v] = _mm256_sub_pd(load4(b.v[3 * v + off_[2]]), o2);
      px[v] = _mm256_sub_pd(ax, _mm256_mul_pd(sx, az[v]));
      py[v] = _mm256_sub_pd(ay, _mm256_mul_pd(sy, az[v]));
    }
    const __m256d eu = _mm256_sub_pd(_mm256_mul_pd(px[2], py[1]), _mm256_mul_pd(py[2], px[1]));
    const __m256d ev = _mm256_sub_pd(_mm256_mul_pd(px[0], py[2]), _mm256_mul_pd(py[0], px[2]));
    const __m256d ew = _mm256_sub_pd(_mm256_mul_pd(px[1], py[0]), _mm256_mul_pd(py[1], px[0]));
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL)), band = _mm256_broadcast_sd(&band_);
    const __m256d near = _mm256_or_pd(_mm256_or_pd(_mm256_cmp_pd(_mm256_and_pd(eu, abs_mask), band, _CMP_NGT_UQ),
                                                   _mm256_cmp_pd(_mm256_and_pd(ev, abs_mask), band, _CMP_NGT_UQ)),
                                      _mm256_cmp_pd(_mm256_and_pd(ew, abs_mask), band, _CMP_NGT_UQ));
    const int near_lanes = _mm256_movemask_pd(near);
    near_out = near_lanes & lanes;
    // Outside its triangle (edge functions of opposite strict signs) or near an edge. A lane not
    // near an edge has |e| > band >= 0 for all three (no zero, no NaN), so its strict signs are its
    // sign bits: opposite strict signs exactly when eu's sign bit differs from ev's or ew's (the
    // decision of the comparisons with zero, in three operations instead of eleven).
    // (The word taken as the compiler cannot see into it: Clang 14 otherwise merges it with the
    // sign bits of the depth's masks below into vector logic on booleans, which AVX without AVX2
    // runs as 128-bit integer packs: about 3 instructions more a block that reaches the depth.)
    const int outside = opaque_word(_mm256_movemask_pd(_mm256_or_pd(_mm256_or_pd(_mm256_xor_pd(eu, ev), _mm256_xor_pd(eu, ew)), near)));
    // every lane outside or near an edge: the depth is not needed (about half the blocks a cast
    // opens; the same operations for the others)
    if ((outside & lanes) == lanes) return 0;
    __m256d pz[3];
    for (int v = 0; v < 3; ++v) pz[v] = _mm256_mul_pd(sz, az[v]);
    const __m256d det = _mm256_add_pd(_mm256_add_pd(eu, ev), ew);
    const __m256d tt = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(eu, pz[0]), _mm256_mul_pd(ev, pz[1])), _mm256_mul_pd(ew, pz[2]));
    // The scalar test's checks of the depth, for det > 0 tt < 0 or tt > t_max det, for det < 0
    // tt > 0 or tt < t_max det, as one pair on tt and t_max det with det's sign taken out (exact:
    // negation is, and a product's rounding is symmetric in sign), so the same decisions on every
    // lane that is not outside: there the edge functions are nonzero, not NaN and of one sign, so
    // det is neither 0 nor NaN (a sum of same-signed nonzero values) and its check det == 0 is
    // not needed; NaN depths fail both comparisons, as in the scalar test. (The AND/ANDNOT blend
    // on det > 0 it replaces took 16 vector operations, now 7.)
    const __m256d det_sign = _mm256_andnot_pd(abs_mask, det);
    const __m256d tt_up = _mm256_xor_pd(tt, det_sign);
    const __m256d tmd_up = _mm256_mul_pd(tmax, _mm256_and_pd(det, abs_mask));
    // Inside the edges but behind the origin (tt's rounded sign): the scalar rule decides, since
    // an origin exactly in the triangle's plane is a hit at t = 0 there (finish_ray_hit)
    const __m256d behind = _mm256_cmp_pd(tt_up, zero, _CMP_LT_OQ);
    const __m256d miss = _mm256_or_pd(behind, _mm256_cmp_pd(tt_up, tmd_up, _CMP_GT_OQ));
    near_out |= _mm256_movemask_pd(behind) & ~outside & lanes;
    eu_out = eu, ev_out = ev, ew_out = ew, det_out = det, tt_out = tt;
    const int m = ~(_mm256_movemask_pd(miss) | outside) & lanes;  // (near lanes count as missed here: outside or behind holds them)
    if (!m) return 0;
    // hit lanes with a finite depth above plane_bound_ have the origin off the plane; the others
    // may be in it, which in_plane_lanes asks (the scalar rule takes those: t exactly 0 there)
    const __m256d att = _mm256_and_pd(tt, abs_mask);
    const __m256d off = _mm256_and_pd(_mm256_cmp_pd(att, _mm256_broadcast_sd(&plane_bound_), _CMP_GT_OQ),
                                      _mm256_cmp_pd(att, _mm256_set1_pd(std::numeric_limits<double>::infinity()), _CMP_LT_OQ));
    const int maybe = m & ~_mm256_movemask_pd(off);
    const int on = maybe ? in_plane_lanes(b, maybe, 0) : 0;
    near_out |= on;
    return m & ~on;
  }
  bool avx_ = false;
  S box_o_[3], box_inv_[3];  // set_ray's origin and 1 / d (the box entries; only hits_avx reads them)
#endif
#if defined(__SSE2__)
  /// SSE2 in double: two lanes a register (a float block's coordinates converted exactly).
  struct SseDouble {
    using V = __m128d;
    static constexpr int kLanes = 2;
    static constexpr bool kFloat = false;
    static V set1(double x) { return _mm_set1_pd(x); }
    static V zero() { return _mm_setzero_pd(); }
    static V load(const float* f) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(f)))); }
    static V load(const double* f) { return _mm_load_pd(f); }
    static V add(V a, V b) { return _mm_add_pd(a, b); }
    static V sub(V a, V b) { return _mm_sub_pd(a, b); }
    static V mul(V a, V b) { return _mm_mul_pd(a, b); }
    static V lt(V a, V b) { return _mm_cmplt_pd(a, b); }
    static V gt(V a, V b) { return _mm_cmpgt_pd(a, b); }
    static V eq(V a, V b) { return _mm_cmpeq_pd(a, b); }
    static V not_gt(V a, V b) { return _mm_cmpngt_pd(a, b); }  // true for NaN
    static V abs(V a) { return _mm_and_pd(a, _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL))); }
    static V bit_or(V a, V b) { return _mm_or_pd(a, b); }
    static V bit_and(V a, V b) { return _mm_and_pd(a, b); }
    static V and_not(V a, V b) { return _mm_andnot_pd(a, b); }  // ~a & b
    static int sign_bits(V a) { return _mm_movemask_pd(a); }
    static void store(double* p, V a) { _mm_store_pd(p, a); }
  };
  /// SSE in float: four lanes a register.
  struct SseFloat {
    using V = __m128;
    static constexpr int kLanes = 4;
    static constexpr bool kFloat = true;
    static V set1(float x) { return _mm_set1_ps(x); }
    static V zero() { return _mm_setzero_ps(); }
    static V load(const float* f) { return _mm_load_ps(f); }
    static V add(V a, V b) { return _mm_add_ps(a, b); }
    static V sub(V a, V b) { return _mm_sub_ps(a, b); }
    static V mul(V a, V b) { return _mm_mul_ps(a, b); }
    static V lt(V a, V b) { return _mm_cmplt_ps(a, b); }
    static V gt(V a, V b) { return _mm_cmpgt_ps(a, b); }
    static V eq(V a, V b) { return _mm_cmpeq_ps(a, b); }
    static V not_gt(V a, V b) { return _mm_cmpngt_ps(a, b); }  // true for NaN
    static V abs(V a) { return _mm_and_ps(a, _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff))); }
    static V bit_or(V a, V b) { return _mm_or_ps(a, b); }
    static V bit_and(V a, V b) { return _mm_and_ps(a, b); }
    static V and_not(V a, V b) { return _mm_andnot_ps(a, b); }  // ~a & b
    static int sign_bits(V a) { return _mm_movemask_ps(a); }
    static void store(float* p, V a) { _mm_store_ps(p, a); }
  };
  /// The test of lanes [h L, h L + L) of `b` (L = Ops::kLanes), written once for both lane types:
  /// bit j set when lane h L + j is a candidate (see the class comment: a lane near an edge is
  /// one). In double, bit 4 + j also set when lane h L + j is near an edge, and `values` (when not
  /// null) gets the lanes' values (LaneValues, but for `near`) when one passes.
  template <class Ops, class T> int sse_lanes(const WideTriangleBlock<T>& b, int h, S t_max, LaneValues* values = nullptr) const {
    using V = typename Ops::V;
    const V zero = Ops::zero(), tmax = Ops::set1(t_max);
    const V sx = Ops::set1(sx_), sy = Ops::set1(sy_), sz = Ops::set1(sz_);
    V px[3], py[3], pz[3];
    for (int v = 0; v < 3; ++v) {
      const V ax = Ops::sub(Ops::load(b.v[3 * v + off_[0]] + Ops::kLanes * h), Ops::set1(o_[0]));
      const V ay = Ops::sub(Ops::load(b.v[3 * v + off_[1]] + Ops::kLanes * h), Ops::set1(o_[1]));
      const V az = Ops::sub(Ops::load(b.v[3 * v + off_[2]] + Ops::kLanes * h), Ops::set1(o_[2]));
      px[v] = Ops::sub(ax, Ops::mul(sx, az));
      py[v] = Ops::sub(ay, Ops::mul(sy, az));
      pz[v] = Ops::mul(sz, az);
    }
    const V eu = Ops::sub(Ops::mul(px[2], py[1]), Ops::mul(py[2], px[1]));
    const V ev = Ops::sub(Ops::mul(px[0], py[2]), Ops::mul(py[0], px[2]));
    const V ew = Ops::sub(Ops::mul(px[1], py[0]), Ops::mul(py[1], px[0]));
    const V neg = Ops::bit_or(Ops::bit_or(Ops::lt(eu, zero), Ops::lt(ev, zero)), Ops::lt(ew, zero));
    const V pos = Ops::bit_or(Ops::bit_or(Ops::gt(eu, zero), Ops::gt(ev, zero)), Ops::gt(ew, zero));
    const V det = Ops::add(Ops::add(eu, ev), ew);
    const V tt = Ops::add(Ops::add(Ops::mul(eu, pz[0]), Ops::mul(ev, pz[1])), Ops::mul(ew, pz[2]));
    const V tmd = Ops::mul(tmax, det);
    const V up = Ops::gt(det, zero);
    const V out_up = Ops::bit_or(Ops::lt(tt, zero), Ops::gt(tt, tmd));
    const V out_down = Ops::bit_or(Ops::gt(tt, zero), Ops::lt(tt, tmd));
    V miss = Ops::bit_or(Ops::bit_or(Ops::bit_and(neg, pos), Ops::eq(det, zero)), Ops::bit_or(Ops::bit_and(up, out_up), Ops::and_not(up, out_down)));
    // near an edge (an edge function not above the band bound, or NaN): the scalar test decides
    const V band = Ops::set1(band_);
    // or inside the edges but behind the origin (tt's rounded sign: an origin exactly in the
    // triangle's plane is a hit at t = 0 for the scalar rule, finish_ray_hit)
    const V behind = Ops::and_not(Ops::bit_and(neg, pos), Ops::bit_or(Ops::bit_and(up, Ops::lt(tt, zero)), Ops::and_not(up, Ops::gt(tt, zero))));
    const V near = Ops::bit_or(Ops::bit_or(Ops::bit_or(Ops::not_gt(Ops::abs(eu), band), Ops::not_gt(Ops::abs(ev), band)), Ops::not_gt(Ops::abs(ew), band)), behind);
    miss = Ops::and_not(near, miss);
    const int m = ~Ops::sign_bits(miss) & ((1 << Ops::kLanes) - 1);
    if constexpr (!Ops::kFloat) {
      if (m && values) {
        const int at = Ops::kLanes * h;
        Ops::store(values->eu + at, eu), Ops::store(values->ev + at, ev), Ops::store(values->ew + at, ew);
        Ops::store(values->det + at, det), Ops::store(values->tt + at, tt);
      }
      const int near_bits = Ops::sign_bits(near);
      int on = 0;
      if (m & ~near_bits) {  // hit lanes: those not proven off the plane (plane_bound_, as lanes_avx) to in_plane_lanes
        const V att = Ops::abs(tt);
        const V off = Ops::bit_and(Ops::gt(att, Ops::set1(plane_bound_)), Ops::lt(att, Ops::set1(std::numeric_limits<S>::infinity())));
        const int maybe = m & ~near_bits & ~Ops::sign_bits(off);
        on = maybe ? in_plane_lanes(b, maybe, Ops::kLanes * h) : 0;  // (t exactly 0 there)
      }
      return m | ((near_bits | on) << 4);
    } else {
      (void)values;
      return m;
    }
  }
#endif
  // (initialised by the constructors: the one of the AVX cast writes each member once)
  int off_[3];  // the block's rows of the ray frame's x, y, z axes (kx, ky, kz)
  S o_[3], sx_, sy_, sz_;
  S band_;  // the bound of the edge functions' bands (PreparedRay::band)
  S plane_bound_;  // box_plane_bound (double; +infinity until bound_band)
  bool valid_;
};

}  // namespace detail
}  // namespace impact
