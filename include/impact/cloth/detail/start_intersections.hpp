// SPDX-License-Identifier: MIT
/// \file
/// Exact intersection of two triangles of a cloth state that may share vertices
/// (triangle_pair_intersects; verify_cloth_state's test), and may_pierce, the cheap filter that
/// cloth_collision_step's start check runs before it on every candidate triangle pair (with
/// g = h / 2: the argument below holds for any g > 0 in place of h).
///
/// Why the filter is enough. Let triangles A and B share a point they may not legitimately share
/// (non-adjacent: any point; sharing a vertex or an edge: see verify_state.hpp), and let every
/// vertex-face pair (a vertex of one that is not a vertex of the other, against the other) and
/// every edge-edge pair with no common vertex be farther apart than h > 0. Then an edge e = (p, q)
/// of one triangle crosses the other's plane with p and q on opposite sides, each farther than h
/// from that plane:
///  - the intersection of two triangles is bounded by their edges, so an edge e of one, say of
///    A, meets B at a point B may not share with it. An edge through a shared vertex meets B
///    elsewhere only within B's plane, and such a coplanar overlap puts a vertex of one triangle
///    in the other or crosses two edges with no common vertex (a pair at distance 0); when A and
///    B share an edge, every edge of A has a shared vertex. So e shares no vertex with B (for
///    one shared vertex, e is the edge of A opposite it);
///  - a segment and a triangle at distance 0 have an endpoint in the triangle or the segment
///    meets one of its edges, unless the segment crosses its interior transversally with its
///    endpoints strictly on opposite sides; the first two are pairs closer than h, so e crosses;
///  - if p were within h of B's plane: were its projection in B, dist(p, B) <= h; else the
///    projection of [p, x] leaves B through an edge of B at the projection of a point r of
///    [p, x], whose height over the plane lies between 0 and p's, so dist(e, that edge) <= h.
///    Either is a pair closer than h; the same for q.
/// So a pair that may_pierce rejects intersects only if one of its vertex-face or edge-edge pairs
/// is closer than h, which the start check's distances see (and throw on or report).
/// Not part of the interface.
#pragma once

#include "impact/core/types.hpp"
#include "impact/geometry/triangle.hpp"
#include "impact/narrow/predicates.hpp"
#include "impact/narrow/triangle_triangle.hpp"

#include <cmath>
#include <limits>

namespace impact::detail::cloth {

/// Exact: the closed triangles A (vertex ids ia) and B (ib), which share at least one vertex id,
/// share more than their common vertex or edge (see verify_state.hpp for the cases).
template <class S>
bool adjacent_pair_intersects(const Vec3<S>* A, const Vec3<S>* B, const int* ia, const int* ib) {
  using namespace detail::tri_tri;
  int sa[3], sb[3], ns = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (ia[i] == ib[j]) sa[ns] = i, sb[ns] = j, ++ns;
  if (ns >= 3) return true;  // the same triangle twice
  double a[3][3], b[3][3];
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) a[i][k] = double(A[i][k]), b[i][k] = double(B[i][k]);
  const double* ta[3] = {a[0], a[1], a[2]};
  const double* tb[3] = {b[0], b[1], b[2]};
  if (degenerate_3d(ta) || degenerate_3d(tb)) return false;
  if (ns == 2) {
    const int oa = 3 - sa[0] - sa[1], ob = 3 - sb[0] - sb[1];
    const double* v = a[sa[0]];
    const double* w = a[sa[1]];
    if (orient3d_double(v, w, a[oa], b[ob]) != 0) return false;
    const Proj pr = drop_axis(injective_axis(ta));
    return pr.o2(v, w, a[oa]) * pr.o2(v, w, b[ob]) > 0;
  }
  // ns == 1: shared vertex.
  const int va = sa[0], vb = sb[0];
  auto opposite_meets = [](const double (&x)[3][3], int vx, const Vec3<S>* Y) {
    const Vec3<S> p = Vec3<S>(S(x[(vx + 1) % 3][0]), S(x[(vx + 1) % 3][1]), S(x[(vx + 1) % 3][2]));
    const Vec3<S> q = Vec3<S>(S(x[(vx + 2) % 3][0]), S(x[(vx + 2) % 3][1]), S(x[(vx + 2) % 3][2]));
    return triangles_intersect(Triangle<S>(p, q, q), Triangle<S>(Y[0], Y[1], Y[2]));
  };
  if (opposite_meets(a, va, B) || opposite_meets(b, vb, A)) return true;
  // An edge (v, x_i) of X lying in Y's plane and pointing into Y's corner at v.
  auto edge_in_corner = [](const double (&x)[3][3], int vx, const double (&y)[3][3], int vy) {
    const double* ty[3] = {y[0], y[1], y[2]};
    const double* v = y[vy];
    const double* y1 = y[(vy + 1) % 3];
    const double* y2 = y[(vy + 2) % 3];
    const Proj pr = drop_axis(injective_axis(ty));
    const int oy = pr.o2(v, y1, y2);
    for (int k = 1; k <= 2; ++k) {
      const double* e = x[(vx + k) % 3];
      if (orient3d_double(v, y1, y2, e) != 0) continue;
      if (pr.o2(v, y1, e) * oy >= 0 && pr.o2(v, e, y2) * oy >= 0) return true;
    }
    return false;
  };
  return edge_in_corner(a, va, b, vb) || edge_in_corner(b, vb, a, va);
}


/// Exact: the closed triangles A (vertex ids ia) and B (ib) share a point they may not: any point
/// when they share no vertex id, otherwise as adjacent_pair_intersects.
template <class S>
bool triangle_pair_intersects(const Vec3<S>* A, const Vec3<S>* B, const int* ia, const int* ib) {
  bool shared = false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) shared = shared || ia[i] == ib[j];
  return shared ? adjacent_pair_intersects(A, B, ia, ib) : triangles_intersect(Triangle<S>(A[0], A[1], A[2]), Triangle<S>(B[0], B[1], B[2]));
}

/// The plane of a triangle at x0 for may_pierce, computed once per step: the unit normal n and
/// offset c in double, and the threshold tau that a signed distance n . x - c must exceed (in
/// magnitude) before a vertex counts as possibly more than g from the plane. Rounding: with
/// u = b - a, v = c - a rounded and m = fl(u x v), each component of m is within 4 eps of its
/// permanent p (|u_1 v_2| + |u_2 v_1|, ...) of the exact normal N, so |m - N| <= 4 eps |p|, and
/// the normalised m is within nu = 8 eps |p| / (|m| - 4 eps |p|) + 3 eps of N / |N|. For a point x
/// with every coordinate at most `scale` in magnitude (as every vertex of the step's system),
/// |x - a| <= 4 scale, and the two dot products and the subtraction add at most 20 eps 3 scale,
/// so the computed signed distance is within E = (4 nu + 60 eps) scale of the exact one; tau is
/// g - 2 E (twice the bound). A triangle whose |m| is not above 1e-150 or whose tau is not
/// positive gets tau = -infinity: every vertex counts, and its pairs always go to the exact test.
struct PiercePlane {
  double n[3] = {0, 0, 0};
  double c = 0;
  double tau = -std::numeric_limits<double>::infinity();
};

inline PiercePlane pierce_plane(const double* a, const double* b, const double* c, double g, double scale) {
  constexpr double eps = std::numeric_limits<double>::epsilon();
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double m[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double p[3] = {std::fabs(u[1] * v[2]) + std::fabs(u[2] * v[1]), std::fabs(u[2] * v[0]) + std::fabs(u[0] * v[2]),
                       std::fabs(u[0] * v[1]) + std::fabs(u[1] * v[0])};
  const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
  const double plen = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  PiercePlane pl;
  const double lower = len - 4 * eps * plen;
  if (!(len > 1e-150) || !(lower > 0)) return pl;
  const double nu = 8 * eps * plen / lower + 3 * eps;
  const double tau = g - 2 * (4 * nu + 60 * eps) * scale;
  if (!(tau > 0)) return pl;
  for (int k = 0; k < 3; ++k) pl.n[k] = m[k] / len;
  pl.c = pl.n[0] * a[0] + pl.n[1] * a[1] + pl.n[2] * a[2];
  pl.tau = tau;
  return pl;
}

/// Conservative: false only if no vertex of q is more than g above the plane pl (pierce_plane
/// with that g) while another is more than g below it, in exact arithmetic on the inputs.
inline bool may_straddle(const PiercePlane& pl, const double (&q)[3][3]) {
  bool above = false, below = false;
  for (int k = 0; k < 3; ++k) {
    const double d = pl.n[0] * q[k][0] + pl.n[1] * q[k][1] + pl.n[2] * q[k][2] - pl.c;
    above = above || !(d <= pl.tau);  // NaN-safe: -infinity tau counts every vertex
    below = below || !(d >= -pl.tau);
  }
  return above && below;
}

/// Conservative: false only if neither triangle (a with plane pa, b with plane pb) has vertices
/// more than g on both sides of the other's plane; by the file comment, such a pair intersects
/// only where one of its vertex-face or edge-edge pairs is within g.
inline bool may_pierce(const PiercePlane& pa, const double (&a)[3][3], const PiercePlane& pb, const double (&b)[3][3]) {
  return may_straddle(pa, b) || may_straddle(pb, a);
}

}  // namespace impact::detail::cloth
