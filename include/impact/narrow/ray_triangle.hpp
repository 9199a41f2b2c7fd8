// SPDX-License-Identifier: MIT
/// \file
/// Watertight ray–triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
/// Intersection", JCGT 2013), with exact signs of its edge functions.
///
/// Numerical contract: the hit/miss decision of the closed triangle for the ray's LINE is EXACT;
/// t, the barycentrics and the checks of t against [0, t_max] are APPROXIMATE, except that an
/// origin exactly in the triangle's plane gives t = 0 exactly (detail::finish_ray_hit). The ray is mapped to
/// a ray space where it runs along +z from the origin o (a permutation making the dominant
/// direction component z, kx, ky swapped when d_kz < 0, then the shear x - s_x z, y - s_y z with
/// s = d_kx / d_kz, d_ky / d_kz rounded); the triangle is hit when its three edge functions (the 2D
/// cross products of the sheared vertices, e.g. eu = c_x b_y - c_y b_x for the edge (b, c)) do not
/// have opposite strict signs, zero counting as inside. In exact arithmetic eu has the sign of
/// det[c - o, b - o, d] in the original axes (eu d_kz equals det[C; B; d] in the permuted frame,
/// whose orientation is that of d_kz: the signs cancel; tests/narrow/test_ray_triangle.cpp checks
/// it), likewise ev with det[a - o, c - o, d] and ew with det[b - o, a - o, d]. Every computed edge
/// function within its error band (below) has its sign replaced by that determinant's, evaluated
/// exactly on the inputs as given (detail::orient3d_direction_exact, narrow/predicates.hpp:
/// 128-bit integers when the values lie on one small grid, else the differences as exact
/// expansions, or big integers): the value becomes 0, or keeps its magnitude
/// with the exact sign (a value of exact sign set to the smallest normal if it was 0). Outside the
/// band the computed sign is the exact one. So every sign is exact; it is a function of the
/// edge's two vertices and the ray only (antisymmetric in the two), whatever the triangle: a ray
/// through a shared edge or vertex of a closed mesh hits at least one adjacent triangle, on any
/// mesh, in float and double alike (the same decisions), with no leak through seams (a ray may
/// report both). Rays in the triangle's plane (all three signs zero) and degenerate triangles
/// report no hit.
///
/// The band (u = 2^-53 in double, 2^-24 in float; u and the underflow unit eta = 2^-1075, 2^-150).
/// For the edge (b, c) let C = c - o, B = b - o (exact), m_cx = |C_kx| + |s_x| |C_kz|, m_cy = |C_ky|
/// + |s_y| |C_kz|, m_bx, m_by likewise, P = m_cx m_by + m_cy m_bx, Sm = m_cx + m_cy + m_bx + m_by.
///  - A rounded difference or sum has relative error at most u (no underflow error: IEEE sums are
///    exact when subnormal); a product fl(xy) = xy (1 + d) + n, |d| <= u, |n| <= eta.
///  - The sheared coordinate c_x = fl(fl(c_x - o_x) - fl(s_x fl(c_z - o_z))), s_x rounded once: its
///    error against C_kx - s_x C_kz (exact s_x) is at most g4 m_cx + (1 + u) eta, g4 = 4u / (1 - 4u)
///    (two roundings on the first term, four on the second).
///  - The edge function fl(fl(c_x b_y) - fl(c_y b_x)) on coordinates with those errors e_cx, ...:
///    |e_cx| (m_by + |e_by|) + m_cx |e_by| per product before rounding, then u on each product and on
///    the difference, and the exact value's |eu| <= P. Summed: |computed - exact| <= (2 g4 + g4^2)
///    (1 + u)^2 P + (2u + u^2) P + 1.01 eta Sm + 2.01 eta <= (10u + 65u^2) P + 1.01 eta Sm + 2.01 eta.
///  - The computed band is detail::edge_band: K P + U (Sm + 1) with K = (10 + 2^-10) u and U = 2^-1000
///    (double) or 2^-126 (float), from the computed m (|fl(c - o)|, |s| rounded, rounded sums and
///    products): each m at least (1 - u)^4 m - eta, P at least (1 - u)^10 P - (m's) eta, the band's
///    own three roundings (1 - u)^3. K (1 - 13u) >= 10u + 65u^2 with room; U is 2^24 (float) or
///    2^75 (double) times eta, so U (Sm + 1) covers the eta terms and the losses of K P to
///    underflow. So a computed edge function larger than its band in magnitude has the exact sign.
///    Overflow gives an infinite or NaN value or band, which counts as inside (exact sign).
///  - A per-ray bound (PreparedRay::band) skips the band for most triangles: for triangles inside a
///    box, R_i = max(|fl(lo_i - o_i)|, |fl(hi_i - o_i)|) bounds every |fl(x_i - o_i)| (rounding is
///    monotone), |s| <= 1 (|d_kz| is the largest), so every computed m_x is at most fl(R_kx + R_kz),
///    m_y at most fl(R_ky + R_kz), and edge_band (nondecreasing in each argument, every operation
///    monotone) of those two bounds is at least every computed band of a triangle in the box. Its
///    default, +infinity, computes every triangle's band.
/// In float, an edge function within the float band sends the triangle to the double test on the
/// same inputs (exactly converted), whose band and exact signs decide; otherwise the float values.
/// Assumes no -ffast-math and no FMA contraction (the band's derivation counts each rounding, and
/// the watertightness argument the symmetry of the edge functions): the CMake target
/// impact::impact passes -ffp-contract=off to g++ and clang; a build that includes the headers
/// without it must too when it targets a processor with FMA (-march=native, -mfma).
#pragma once

#include "impact/core/config.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/triangle.hpp"
#include "impact/narrow/predicates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>

namespace impact {

/// A ray–triangle hit. point = ray.at(t) = u a + v b + w c (approximately).
template <class S> struct RayTriangleHit {
  S t = S(0);                   ///< ray parameter in [0, ray.t_max]
  S u = S(0), v = S(0), w = S(0);  ///< barycentric weights of the triangle's a, b, c (each in [0, 1], sum 1)
  bool front = true;            ///< true when the ray meets the side the normal (b - a) x (c - a) points to
};

namespace detail {

/// The constants of the edge functions' error band (see the file comment): K and U.
template <class S> struct EdgeBand;
template <> struct EdgeBand<double> {
  static constexpr double kRelative = (10.0 + 0x1p-10) * 0x1p-53;
  static constexpr double kAbsolute = 0x1p-1000;
};
template <> struct EdgeBand<float> {
  static constexpr float kRelative = (10.0f + 0x1p-10f) * 0x1p-24f;
  static constexpr float kAbsolute = 0x1p-126f;
};

/// The error band of the computed edge function of an edge (b, c) from its vertices' magnitudes
/// m_cx, m_cy, m_bx, m_by (file comment): K P + U (Sm + 1), nondecreasing in each argument.
template <class S> inline S edge_band(S mcx, S mcy, S mbx, S mby) {
  return EdgeBand<S>::kRelative * (mcx * mby + mcy * mbx) + EdgeBand<S>::kAbsolute * ((mcx + mcy) + (mbx + mby) + S(1));
}

/// A bound of edge_band over every triangle inside the box [lo, hi], for the ray from `o`, all
/// three in the ray's frame (kx, ky, kz): see the file comment. +infinity when a value is not
/// finite (every triangle's band is then computed).
template <class S> inline S box_edge_band(const S (&o)[3], const S (&lo)[3], const S (&hi)[3]) {
  S r[3];
  for (int i = 0; i < 3; ++i) {
    const S a = std::abs(lo[i] - o[i]), b = std::abs(hi[i] - o[i]);
    r[i] = a > b ? a : b;
  }
  const S mx = r[0] + r[2], my = r[1] + r[2];
  const S band = edge_band(mx, my, mx, my);
  return band < std::numeric_limits<S>::infinity() ? band : std::numeric_limits<S>::infinity();  // (NaN: infinity)
}

}  // namespace detail

/// A ray prepared for many triangles: the axis permutation and the shear to ray space.
template <class S> struct PreparedRay {
  Ray<S> ray;
  int kx = 0, ky = 1, kz = 2;
  S sx = S(0), sy = S(0), sz = S(1);
  bool valid = false;  ///< false for a zero direction (it hits nothing)
  /// A per-ray bound of the edge functions' error bands (file comment): a triangle whose three
  /// edge functions exceed it in magnitude needs no band of its own. +infinity (the default)
  /// computes every triangle's band; bound_band sets it for triangles inside a box.
  S band = std::numeric_limits<S>::infinity();

  PreparedRay() = default;
  explicit PreparedRay(const Ray<S>& r) : ray(r) {
    const Vec3<S> ad = r.direction.cwiseAbs();
    kz = ad.x() >= ad.y() ? (ad.x() >= ad.z() ? 0 : 2) : (ad.y() >= ad.z() ? 1 : 2);
    kx = (kz + 1) % 3;
    ky = (kx + 1) % 3;
    const S dz = r.direction[kz];
    valid = dz != S(0);
    if (!valid) return;
    if (dz < S(0)) std::swap(kx, ky);  // keep the frame right-handed
    sx = r.direction[kx] / dz;
    sy = r.direction[ky] / dz;
    sz = S(1) / dz;
  }
  /// Sets `band` for triangles whose vertices lie in the box [lo, hi] (the caller guarantees it;
  /// a triangle outside would be decided on a band that may be too narrow).
  void bound_band(const Vec3<S>& lo, const Vec3<S>& hi) {
    const S o[3] = {ray.origin[kx], ray.origin[ky], ray.origin[kz]};
    const S l[3] = {lo[kx], lo[ky], lo[kz]}, h[3] = {hi[kx], hi[ky], hi[kz]};
    band = detail::box_edge_band(o, l, h);
  }
};

namespace detail {

/// Whether `origin` lies exactly in the triangle's plane, for finish_ray_hit, which asks only when
/// the ray's line meets the closed triangle (exact signs): the origin is then in the plane only if
/// it is a point of the triangle, so outside the triangle's bounding box it is not (six
/// comparisons decide most calls); inside it, the exact orient3d decides.
template <class S> inline bool origin_in_plane(const Triangle<S>& tri, const Vec3<S>& origin) {
  for (int k = 0; k < 3; ++k) {
    const S x = origin[k];
    if ((x < tri.a[k] && x < tri.b[k] && x < tri.c[k]) || (x > tri.a[k] && x > tri.b[k] && x > tri.c[k])) return false;
  }
  return orient3d(tri.a, tri.b, tri.c, origin) == 0;
}

/// The end of the watertight test: the edge functions' signs (exact), then t = tt / det against
/// [0, t_max]. For an origin exactly in the triangle's plane t is 0, but tt is rounding noise
/// there (of either sign, for rays whose dominant axis is not the normal's): so a ray that meets
/// the triangle asks origin_in_plane(tri, origin) (a box test, then the exact orient3d of
/// the triangle and the origin; per hit candidate, none for misses), and true makes t exactly 0. A ray from a
/// point of the triangle is then hit at t = 0, with `front` telling the side it enters, which the
/// mesh casts' tie rule (query/ray_mesh.hpp) and the particles' colliders rely on: into the front
/// it hits, away from it it does not (before, tt's rounded sign lost a third of the oblique rays
/// into the front and could report those away from it at a t of a few ulps).
template <class S, class W>
inline std::optional<RayTriangleHit<S>> finish_ray_hit(W eu, W ev, W ew, S az, S bz, S cz, S t_max, const Triangle<S>& tri, const Vec3<S>& origin) {
  if ((eu < W(0) || ev < W(0) || ew < W(0)) && (eu > W(0) || ev > W(0) || ew > W(0))) return std::nullopt;
  const W det = eu + ev + ew;
  if (det == W(0)) return std::nullopt;
  W tt = eu * W(az) + ev * W(bz) + ew * W(cz);
  if (origin_in_plane(tri, origin)) tt = W(0);
  if (det > W(0)) {
    if (tt < W(0) || tt > W(t_max) * det) return std::nullopt;
  } else {
    if (tt > W(0) || tt < W(t_max) * det) return std::nullopt;
  }
  const W inv = W(1) / det;
  RayTriangleHit<S> h;
  h.t = std::min(S(tt * inv), t_max);
  h.u = S(eu * inv), h.v = S(ev * inv), h.w = S(ew * inv);
  h.front = det > W(0);
  return h;
}

/// An edge function `e` with the exact sign `sign` (file comment): 0, e itself, -e, or the
/// smallest normal double of that sign when e is 0.
inline double with_exact_sign(double e, int sign) {
  if (sign == 0) return 0.0;
  if (e != 0.0) return (e > 0.0) == (sign > 0) ? e : -e;
  return sign > 0 ? std::numeric_limits<double>::min() : -std::numeric_limits<double>::min();
}

/// The magnitudes m_x = |X_kx| + |s_x| |X_kz|, m_y = |X_ky| + |s_y| |X_kz| of a vertex X = x - o
/// (file comment).
template <class S> inline void edge_magnitudes(const PreparedRay<S>& pr, const Vec3<S>& X, S& mx, S& my) {
  const S z = std::abs(X[pr.kz]);
  mx = std::abs(X[pr.kx]) + std::abs(pr.sx) * z;
  my = std::abs(X[pr.ky]) + std::abs(pr.sy) * z;
}

template <class S> std::optional<RayTriangleHit<S>> intersect_ray_triangle_near_edges(const PreparedRay<S>& pr, const Triangle<S>& tri, S eu, S ev,
                                                                                      S ew);

}  // namespace detail

/// Watertight intersection of a prepared ray with the closed triangle tri (see the file comment).
template <class S> inline std::optional<RayTriangleHit<S>> intersect_ray_triangle(const PreparedRay<S>& pr, const Triangle<S>& tri) {
  static_assert(is_supported_scalar_v<S>, "intersect_ray_triangle: float or double");
  if (!pr.valid) return std::nullopt;
  const Vec3<S> A = tri.a - pr.ray.origin, B = tri.b - pr.ray.origin, C = tri.c - pr.ray.origin;
  const int kx = pr.kx, ky = pr.ky, kz = pr.kz;
  const S ax = A[kx] - pr.sx * A[kz], ay = A[ky] - pr.sy * A[kz];
  const S bx = B[kx] - pr.sx * B[kz], by = B[ky] - pr.sy * B[kz];
  const S cx = C[kx] - pr.sx * C[kz], cy = C[ky] - pr.sy * C[kz];
  const S cxby = cx * by, cybx = cy * bx, axcy = ax * cy, aycx = ay * cx, bxay = bx * ay, byax = by * ax;
  const S eu = cxby - cybx, ev = axcy - aycx, ew = bxay - byax;
  // an edge function within the per-ray bound of the bands: the triangle's own bands decide
  if (IMPACT_UNLIKELY(!(std::abs(eu) > pr.band && std::abs(ev) > pr.band && std::abs(ew) > pr.band)))
    return detail::intersect_ray_triangle_near_edges(pr, tri, eu, ev, ew);
  const S az = pr.sz * A[kz], bz = pr.sz * B[kz], cz = pr.sz * C[kz];
  return detail::finish_ray_hit<S, S>(eu, ev, ew, az, bz, cz, pr.ray.t_max, tri, pr.ray.origin);
}

namespace detail {

/// intersect_ray_triangle's end when an edge function is within the per-ray bound (eu, ev, ew its
/// values): each edge function within its own band takes the exact sign (in float: the double
/// test decides); the others are kept. Out of line: rare (about 1e-9 of the triangles of a cast
/// with a box bound, every triangle without).
template <class S>
IMPACT_NOINLINE std::optional<RayTriangleHit<S>> intersect_ray_triangle_near_edges(const PreparedRay<S>& pr, const Triangle<S>& tri, S eu, S ev,
                                                                                   S ew) {
  const Vec3<S>& o = pr.ray.origin;
  const Vec3<S> A = tri.a - o, B = tri.b - o, C = tri.c - o;
  S amx, amy, bmx, bmy, cmx, cmy;
  edge_magnitudes(pr, A, amx, amy);
  edge_magnitudes(pr, B, bmx, bmy);
  edge_magnitudes(pr, C, cmx, cmy);
  const bool in_u = !(std::abs(eu) > edge_band(cmx, cmy, bmx, bmy));
  const bool in_v = !(std::abs(ev) > edge_band(amx, amy, cmx, cmy));
  const bool in_w = !(std::abs(ew) > edge_band(bmx, bmy, amx, amy));
  const S az = pr.sz * A[pr.kz], bz = pr.sz * B[pr.kz], cz = pr.sz * C[pr.kz];
  if (!(in_u || in_v || in_w)) return finish_ray_hit<S, S>(eu, ev, ew, az, bz, cz, pr.ray.t_max, tri, o);
  if constexpr (std::is_same_v<S, float>) {  // the double test on the same inputs decides
    const PreparedRay<double> prd(Ray<double>(o.template cast<double>(), pr.ray.direction.template cast<double>(), double(pr.ray.t_max)));
    const auto h = intersect_ray_triangle(prd, Triangle<double>(tri.a.template cast<double>(), tri.b.template cast<double>(), tri.c.template cast<double>()));
    if (!h) return std::nullopt;
    RayTriangleHit<S> r;
    r.t = std::min(S(h->t), pr.ray.t_max);
    r.u = S(h->u), r.v = S(h->v), r.w = S(h->w);
    r.front = h->front;
    return r;
  } else {
    const double po[3] = {o.x(), o.y(), o.z()}, pd[3] = {pr.ray.direction.x(), pr.ray.direction.y(), pr.ray.direction.z()};
    const double pa[3] = {tri.a.x(), tri.a.y(), tri.a.z()}, pb[3] = {tri.b.x(), tri.b.y(), tri.b.z()}, pc[3] = {tri.c.x(), tri.c.y(), tri.c.z()};
    // eu ~ det[c - o, b - o, d], ev ~ det[a - o, c - o, d], ew ~ det[b - o, a - o, d]
    if (in_u) eu = with_exact_sign(eu, orient3d_direction_exact(po, pc, pb, pd));
    if (in_v) ev = with_exact_sign(ev, orient3d_direction_exact(po, pa, pc, pd));
    if (in_w) ew = with_exact_sign(ew, orient3d_direction_exact(po, pb, pa, pd));
    return finish_ray_hit<S, S>(eu, ev, ew, az, bz, cz, pr.ray.t_max, tri, o);
  }
}

}  // namespace detail

/// Watertight intersection of the ray (origin + s direction, s in [0, t_max]) with the closed
/// triangle: nullopt on a miss. Prepare the ray once (PreparedRay) when testing many triangles.
template <class S> inline std::optional<RayTriangleHit<S>> intersect_ray_triangle(const Ray<S>& ray, const Triangle<S>& tri) {
  return intersect_ray_triangle(PreparedRay<S>(ray), tri);
}

}  // namespace impact
