// SPDX-License-Identifier: MIT
/// \file
/// Triangle–triangle intersection: the leaf test of mesh–mesh collision.
///
/// Numerical contract of triangles_intersect: EXACT for the coordinates it is given. Every decision
/// is the sign of an exact orient3d / orient2d predicate (narrow/predicates.hpp), so the answer is
/// that of exact real arithmetic on the (float or double) inputs. Triangles are closed point sets:
/// touching (a shared vertex, an edge on an edge, a vertex on a face) counts as intersecting, as in
/// FCL. Coplanar triangles are intersected in a projection that is exactly injective on their
/// plane. Degenerate triangles (collinear or coincident vertices) are treated as the segments and
/// points they are.
///
/// Algorithm: the non-degenerate, non-coplanar case is the orientation-predicate test of Guigue &
/// Devillers ("Fast and robust triangle-triangle overlap test using orientation predicates",
/// JGT 2003): each triangle is first rejected against the other's plane, then the two intervals on
/// the planes' common line are compared with two more orient3d signs. Coplanar and degenerate
/// configurations take a separate, slower but equally exact path.
///
/// triangle_intersection (contacts) is APPROXIMATE in the point it reports (floating-point
/// construction), but it is computed only for pairs that triangles_intersect accepts.
#pragma once

#include "impact/geometry/triangle.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/predicates.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace impact {

/// A triangle prepared for many intersection tests against other triangles (the caller holds one
/// triangle of mesh A and tests many of mesh B): its plane and filter terms are computed once.
template <class S> struct PreparedTriangle {
  OrientPlane plane;  ///< the vertices (in double), the rounded normal and the filter terms

  PreparedTriangle() = default;
  explicit PreparedTriangle(const Triangle<S>& t) : plane(t.a, t.b, t.c) {}
};

namespace detail::tri_tri {

// ---- 2D (projection dropping axis k: coordinates i = k + 1, j = k + 2 mod 3) -------------------

struct Proj {
  int i, j;
  int o2(const double* a, const double* b, const double* c) const { return orient2d_double(a[i], a[j], b[i], b[j], c[i], c[j]); }
  /// r inside the bounding box of p, q (in the projection).
  bool in_box(const double* p, const double* q, const double* r) const {
    return std::min(p[i], q[i]) <= r[i] && r[i] <= std::max(p[i], q[i]) && std::min(p[j], q[j]) <= r[j] && r[j] <= std::max(p[j], q[j]);
  }
};

inline Proj drop_axis(int k) { return {(k + 1) % 3, (k + 2) % 3}; }

/// Closed segments pq and rs intersect (2D, exact; zero-length segments allowed).
inline bool seg_seg_2d(const Proj& pr, const double* p, const double* q, const double* r, const double* s) {
  const int o1 = pr.o2(p, q, r), o2 = pr.o2(p, q, s), o3 = pr.o2(r, s, p), o4 = pr.o2(r, s, q);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  if (o1 == 0 && pr.in_box(p, q, r)) return true;
  if (o2 == 0 && pr.in_box(p, q, s)) return true;
  if (o3 == 0 && pr.in_box(r, s, p)) return true;
  if (o4 == 0 && pr.in_box(r, s, q)) return true;
  return false;
}

/// Point p in the closed (possibly degenerate) triangle t (2D, exact).
inline bool point_in_tri_2d(const Proj& pr, const double* p, const double* const* t) {
  if (pr.o2(t[0], t[1], t[2]) != 0) {
    const int s0 = pr.o2(t[0], t[1], p), s1 = pr.o2(t[1], t[2], p), s2 = pr.o2(t[2], t[0], p);
    return !((s0 < 0 || s1 < 0 || s2 < 0) && (s0 > 0 || s1 > 0 || s2 > 0));
  }
  // degenerate in this projection: its hull is the union of its edges
  return seg_seg_2d(pr, t[0], t[1], p, p) || seg_seg_2d(pr, t[1], t[2], p, p) || seg_seg_2d(pr, t[2], t[0], p, p);
}

/// Two closed (possibly degenerate) triangles intersect (2D, exact): an edge pair crosses or one
/// contains a vertex of the other.
inline bool tri_tri_2d(const Proj& pr, const double* const* a, const double* const* b) {
  for (int e = 0; e < 3; ++e)
    for (int f = 0; f < 3; ++f)
      if (seg_seg_2d(pr, a[e], a[(e + 1) % 3], b[f], b[(f + 1) % 3])) return true;
  return point_in_tri_2d(pr, a[0], b) || point_in_tri_2d(pr, b[0], a);
}

// ---- 3D helpers for the slow path ---------------------------------------------------------------

/// Exact: the three points are collinear (or coincident).
inline bool degenerate_3d(const double* const* t) {
  for (int k = 0; k < 3; ++k)
    if (drop_axis(k).o2(t[0], t[1], t[2]) != 0) return false;
  return true;
}

/// An axis k whose projection is injective on the plane of the non-degenerate triangle t.
inline int injective_axis(const double* const* t) {
  double n[3];
  for (int k = 0; k < 3; ++k) {
    const Proj pr = drop_axis(k);
    n[k] = std::fabs((t[1][pr.i] - t[0][pr.i]) * (t[2][pr.j] - t[0][pr.j]) - (t[1][pr.j] - t[0][pr.j]) * (t[2][pr.i] - t[0][pr.i]));
  }
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int x, int y) { return n[x] > n[y]; });
  for (int k : order)
    if (drop_axis(k).o2(t[0], t[1], t[2]) != 0) return k;
  return order[0];  // unreachable for non-degenerate t
}

inline bool lex_less(const double* p, const double* q) {
  return p[0] < q[0] || (p[0] == q[0] && (p[1] < q[1] || (p[1] == q[1] && p[2] < q[2])));
}

/// The hull of collinear points is the segment between the lexicographic extremes.
inline void degenerate_segment(const double* const* t, const double*& p, const double*& q) {
  p = t[0], q = t[0];
  for (int k = 1; k < 3; ++k) {
    if (lex_less(t[k], p)) p = t[k];
    if (lex_less(q, t[k])) q = t[k];
  }
}

/// Closed segment pq (possibly a point) against the closed non-degenerate triangle t (3D, exact).
inline bool seg_tri_3d(const double* p, const double* q, const double* const* t) {
  const int sp = orient3d_double(t[0], t[1], t[2], p), sq = orient3d_double(t[0], t[1], t[2], q);
  if (sp * sq > 0) return false;
  if (sp == 0 && sq == 0) {
    const Proj pr = drop_axis(injective_axis(t));
    const double* s[3] = {p, q, q};
    return tri_tri_2d(pr, s, t);
  }
  // the line pq crosses the plane at one point of the segment: is it inside t?
  const int o0 = orient3d_double(p, q, t[0], t[1]), o1 = orient3d_double(p, q, t[1], t[2]), o2 = orient3d_double(p, q, t[2], t[0]);
  return !((o0 < 0 || o1 < 0 || o2 < 0) && (o0 > 0 || o1 > 0 || o2 > 0));
}

/// Closed segments pq and rs (possibly points) in 3D, exact: coplanar, and intersecting in every
/// coordinate projection (one of which is injective on their common plane or line).
inline bool seg_seg_3d(const double* p, const double* q, const double* r, const double* s) {
  if (orient3d_double(p, q, r, s) != 0) return false;
  for (int k = 0; k < 3; ++k)
    if (!seg_seg_2d(drop_axis(k), p, q, r, s)) return false;
  return true;
}

/// Slow exact path: a triangle is degenerate, or the two are coplanar.
inline bool tri_tri_degenerate_or_coplanar(const double* const* a, const double* const* b) {
  const bool da = degenerate_3d(a), db = degenerate_3d(b);
  if (!da && !db) return tri_tri_2d(drop_axis(injective_axis(a)), a, b);  // coplanar
  if (!da) {
    const double *p, *q;
    degenerate_segment(b, p, q);
    return seg_tri_3d(p, q, a);
  }
  const double *p, *q;
  degenerate_segment(a, p, q);
  if (!db) return seg_tri_3d(p, q, b);
  const double *r, *s;
  degenerate_segment(b, r, s);
  return seg_seg_3d(p, q, r, s);
}

/// For signs s of three vertices against a plane (not all equal and nonzero, not all zero): the
/// vertex alone on its closed side, and that side (+1 or -1).
inline void alone_vertex(const int* s, int& index, int& side) {
  int pos = 0, neg = 0;
  for (int k = 0; k < 3; ++k) pos += s[k] > 0, neg += s[k] < 0;
  if (pos == 1) {
    index = s[0] > 0 ? 0 : (s[1] > 0 ? 1 : 2);
    side = 1;
  } else if (neg == 1) {
    index = s[0] < 0 ? 0 : (s[1] < 0 ? 1 : 2);
    side = -1;
  } else {  // two on one side, one on the plane
    index = s[0] == 0 ? 0 : (s[1] == 0 ? 1 : 2);
    side = pos == 2 ? -1 : 1;
  }
}

/// Guigue–Devillers interval test for non-degenerate, non-coplanar triangles that both straddle
/// (or touch) the other's plane. sa: signs of a's vertices against b's plane, sb: of b's against a's.
inline bool tri_tri_straddling(const double* const* a_in, const double* const* b_in, const int* sa, const int* sb_in) {
  int ia, side_a;
  alone_vertex(sa, ia, side_a);
  const double* p[3] = {a_in[ia], a_in[(ia + 1) % 3], a_in[(ia + 2) % 3]};
  const double* q[3] = {b_in[0], b_in[1], b_in[2]};
  int sb[3] = {sb_in[0], sb_in[1], sb_in[2]};
  if (side_a < 0) {  // flip b's orientation so that p[0] is on its positive side
    std::swap(q[1], q[2]);
    std::swap(sb[1], sb[2]);
  }
  int ib, side_b;
  alone_vertex(sb, ib, side_b);
  const double* r[3] = {q[ib], q[(ib + 1) % 3], q[(ib + 2) % 3]};
  if (side_b < 0) std::swap(p[1], p[2]);  // flip a's orientation so that r[0] is on its positive side
  return orient3d_double(p[0], p[1], r[0], r[1]) <= 0 && orient3d_double(p[0], p[2], r[2], r[0]) <= 0;
}

template <class S> inline void to_double(const Triangle<S>& t, double (&out)[3][3]) {
  for (int v = 0; v < 3; ++v)
    for (int k = 0; k < 3; ++k) out[v][k] = double(t[v][k]);
}

inline bool all_same_strict(const int* s) { return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0); }

}  // namespace detail::tri_tri

/// Exact: true when the closed triangles share at least one point (see the file comment). The
/// prepared form of a is reused across calls; b is any triangle.
template <class S> inline bool triangles_intersect(const PreparedTriangle<S>& a, const Triangle<S>& b) {
  static_assert(is_supported_scalar_v<S>, "triangles_intersect: float or double");
  double bv[3][3];
  detail::tri_tri::to_double(b, bv);
  int sb[3];
  for (int k = 0; k < 3; ++k) sb[k] = a.plane.orient(bv[k]);
  if (detail::tri_tri::all_same_strict(sb)) return false;
  const OrientPlane pb(b.a, b.b, b.c);
  const double* pa[3] = {a.plane.a, a.plane.b, a.plane.c};
  int sa[3];
  for (int k = 0; k < 3; ++k) sa[k] = pb.orient(pa[k]);
  if (detail::tri_tri::all_same_strict(sa)) return false;
  const double* pbv[3] = {bv[0], bv[1], bv[2]};
  if ((sb[0] == 0 && sb[1] == 0 && sb[2] == 0) || (sa[0] == 0 && sa[1] == 0 && sa[2] == 0))
    return detail::tri_tri::tri_tri_degenerate_or_coplanar(pa, pbv);
  return detail::tri_tri::tri_tri_straddling(pa, pbv, sa, sb);
}

/// Exact: true when the closed triangles a and b share at least one point. Touching counts;
/// coplanar and degenerate (segment, point) triangles are handled exactly.
template <class S> inline bool triangles_intersect(const Triangle<S>& a, const Triangle<S>& b) {
  return triangles_intersect(PreparedTriangle<S>(a), b);
}

/// Contact information of two intersecting triangles.
template <class S> struct TriangleContact {
  Vec3<S> point;     ///< a point of the intersection (midpoint of [p, q])
  Vec3<S> p, q;      ///< endpoints of the intersection segment (non-coplanar case); p == q == point otherwise
  bool coplanar = false;  ///< coplanar or degenerate configuration: only point is meaningful
  Vec3<S> normal_a;  ///< unit normal of a ((b - a) x (c - a) normalised); zero if a is degenerate
  Vec3<S> normal_b;  ///< unit normal of b; zero if b is degenerate
};

namespace detail::tri_tri {

/// Points where the triangle t (exact signs s, floating distances d) meets the other plane.
inline int plane_cut(const double* const* t, const int* s, const double* d, double (&out)[3][3]) {
  int m = 0;
  for (int k = 0; k < 3 && m < 3; ++k) {
    const int l = (k + 1) % 3;
    if (s[k] == 0) {
      for (int c = 0; c < 3; ++c) out[m][c] = t[k][c];
      ++m;
    }
    if (s[k] * s[l] < 0 && m < 3) {
      double f = d[k] / (d[k] - d[l]);
      f = std::min(1.0, std::max(0.0, f));
      for (int c = 0; c < 3; ++c) out[m][c] = t[k][c] + f * (t[l][c] - t[k][c]);
      ++m;
    }
  }
  return m;
}

}  // namespace detail::tri_tri

/// Intersection of two triangles: nullopt exactly when triangles_intersect is false; otherwise a
/// point of the intersection and both unit normals. For transversal (non-coplanar, non-degenerate)
/// pairs, [p, q] is the intersection segment and point its midpoint. The reported geometry is
/// APPROXIMATE (floating-point constructions, in double); the decision is exact. Slower than
/// triangles_intersect: meant for the pairs the caller wants contacts for.
template <class S> std::optional<TriangleContact<S>> triangle_intersection(const Triangle<S>& a, const Triangle<S>& b) {
  if (!triangles_intersect(a, b)) return std::nullopt;
  double av[3][3], bv[3][3];
  detail::tri_tri::to_double(a, av);
  detail::tri_tri::to_double(b, bv);
  const double* pa[3] = {av[0], av[1], av[2]};
  const double* pb[3] = {bv[0], bv[1], bv[2]};
  TriangleContact<S> out;
  out.normal_a = a.template cast<double>().normal().template cast<S>();
  out.normal_b = b.template cast<double>().normal().template cast<S>();
  int sa[3], sb[3];
  for (int k = 0; k < 3; ++k) sb[k] = detail::orient3d_double(pa[0], pa[1], pa[2], pb[k]), sa[k] = detail::orient3d_double(pb[0], pb[1], pb[2], pa[k]);
  const bool flat = (sa[0] == 0 && sa[1] == 0 && sa[2] == 0) || (sb[0] == 0 && sb[1] == 0 && sb[2] == 0);
  if (!flat) {
    const Triangle<double> ta = a.template cast<double>(), tb = b.template cast<double>();
    const Vec3<double> na = ta.scaled_normal(), nb = tb.scaled_normal();
    double da[3], db[3];
    for (int k = 0; k < 3; ++k) da[k] = nb.dot(ta[k] - tb.a), db[k] = na.dot(tb[k] - ta.a);
    double ca[3][3], cb[3][3];
    const int ma = detail::tri_tri::plane_cut(pa, sa, da, ca), mb = detail::tri_tri::plane_cut(pb, sb, db, cb);
    const Vec3<double> dir = na.cross(nb);
    auto at = [](const double* x) { return Vec3<double>(x[0], x[1], x[2]); };
    auto interval = [&](double (&c)[3][3], int m, Vec3<double>& lo, Vec3<double>& hi, double& tlo, double& thi) {
      tlo = std::numeric_limits<double>::infinity(), thi = -tlo;
      for (int k = 0; k < m; ++k) {
        const double t = dir.dot(at(c[k]));
        if (t < tlo) tlo = t, lo = at(c[k]);
        if (t > thi) thi = t, hi = at(c[k]);
      }
    };
    Vec3<double> alo, ahi, blo, bhi;
    double atl, ath, btl, bth;
    if (ma > 0 && mb > 0) {
      interval(ca, ma, alo, ahi, atl, ath);
      interval(cb, mb, blo, bhi, btl, bth);
      const Vec3<double> p = atl >= btl ? alo : blo;
      const Vec3<double> q = ath <= bth ? ahi : bhi;
      out.p = p.cast<S>();
      out.q = q.cast<S>();
      out.point = ((p + q) * 0.5).cast<S>();
      return out;
    }
  }
  // coplanar or degenerate: a closest pair between the two hulls (distance zero up to rounding)
  out.coplanar = true;
  const Triangle<double> ta = a.template cast<double>(), tb = b.template cast<double>();
  double best = std::numeric_limits<double>::infinity();
  Vec3<double> point = ta.a;
  auto consider = [&](const Vec3<double>& x, const Vec3<double>& y) {
    const double d2 = (x - y).squaredNorm();
    if (d2 < best) best = d2, point = (x + y) * 0.5;
  };
  // a segment crossing a triangle's plane transversally meets it at the crossing point
  auto crossing = [&](const Triangle<double>& seg_tri, const Triangle<double>& tri) {
    const Vec3<double> n = tri.scaled_normal();
    for (int e = 0; e < 3; ++e) {
      const Vec3<double>& x = seg_tri[e];
      const Vec3<double>& y = seg_tri[(e + 1) % 3];
      const double dx = n.dot(x - tri.a), dy = n.dot(y - tri.a);
      if ((dx < 0 && dy > 0) || (dx > 0 && dy < 0)) {
        const Vec3<double> c = x + (dx / (dx - dy)) * (y - x);
        consider(c, closest_point_on_triangle(c, tri).point);
      }
    }
  };
  for (int k = 0; k < 3; ++k) {
    consider(ta[k], closest_point_on_triangle(ta[k], tb).point);
    consider(tb[k], closest_point_on_triangle(tb[k], ta).point);
    for (int l = 0; l < 3; ++l) {
      const auto c = closest_points_segment_segment(Segment<double>(ta[k], ta[(k + 1) % 3]), Segment<double>(tb[l], tb[(l + 1) % 3]));
      consider(c.point_a, c.point_b);
    }
  }
  crossing(ta, tb);
  crossing(tb, ta);
  out.point = point.cast<S>();
  out.p = out.q = out.point;
  return out;
}

}  // namespace impact
