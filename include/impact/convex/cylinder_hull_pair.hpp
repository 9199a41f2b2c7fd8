// SPDX-License-Identifier: MIT
/// \file
/// Cylinder against convex hull (convex/certified_pair.hpp's cylinder–hull penetration), in the cylinder's
/// frame (its axis z, its centre the origin; the hull placed by R, t there). With
/// f(n) = h_A(n) + h_B(-n), the overlap along a unit n from the cylinder towards the hull (the
/// depth is min_n f), the features of the Minkowski difference that have a finite set of normals
/// give candidates, each an upper bound f(n) at its direction:
///   a face of the hull against the cylinder's deepest point across it (a rim point): n = -m, m
///       the face's outward normal, f = offset + m . t + h |m_z| + r |P_z m| (closed form; a
///       negative one separates them, so the loop over the faces is also the hull faces'
///       separating-axis test);
///   a vertex of the hull against a cap: n = +-z, the hull's deepest vertex along -n;
///   an edge of the hull across the cylinder's side: n normal to the axis and to the edge, where
///       the edge's arc on the Gauss map (from one face's normal to the other's) crosses the
///       great circle normal to the axis: the crossing u = |d1| m0 + |d0| m1 (d_i = m_i . z of
///       opposite signs) is a normal of the hull at the edge, so h_B(u) = u . (edge vertex) with
///       no support call;
///   a vertex of the hull against the side: n = x's radial direction (normal to the axis), f =
///       r - |x_xy| for a vertex x that is the hull's support along -n (side_vertex's climb, from
///       the end of the best crossing edge past which the overlap along the circle normal to the
///       axis still falls).
/// A candidate is certified by a lower bound rho from a point x of one shape inside the other (the
/// ball of radius rho about x, x's distance to that shape's boundary, lies inside it, so every
/// separating translation is at least rho long): the face's rim point inside the hull (rho the
/// least distance to the hull's face planes), the cap's vertex, the side's vertex or the edge's
/// point at n's azimuth inside the cylinder (convex/deepest_point.hpp's inside_ball; exact, rho =
/// f, for a vertex or an edge point nearer the side or cap it meets than the other boundary).
/// The face loop runs on whole arrays (Eigen's packets). When the best upper and lower
/// bounds are within the tolerance the answer is certified as EPA's is (depth = the upper bound,
/// depth_gap = upper - lower); otherwise (an edge or a vertex against the rim, a contact whose
/// ball is cut) the caller runs EPA, stopped early by the local certificate of
/// convex/local_certificate.hpp on cylinder_hull_terms: the cylinder's terms and the hull's
/// feature at EPA's normal (a vertex: a linear term; an edge: linear plus an abs term), a lower
/// bound of the overlap everywhere, accepted where the true overlap at the certified normal is
/// within the tolerance of it.
///
/// Numerical contract: separating test EXACT up to rounding (margin given by the caller);
/// candidates APPROXIMATE as EPA's: depth is f(normal) (an upper bound up to rounding),
/// depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact::detail {

/// Hulls with at most this many faces take the candidates (their per-face values live on the stack).
inline constexpr std::size_t kCylinderHullMaxFaces = 256;

/// Whether hull b can take cylinder_hull_candidates (face planes and edges built by convex_hull()).
template <class S>
inline bool use_cylinder_hull_candidates(const ConvexHull<S>& b) {
  return !b.face_planes.empty() && b.faces.size() <= kCylinderHullMaxFaces && b.face_planes.size() == 4 * b.faces.size();
}

/// The overlap of cylinder a (its frame) and hull b (placed by R, t there) along unit n, the hull's
/// part from its support point.
template <class S>
S cylinder_hull_overlap(const Cylinder<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n) {
  const Vec3<S> v = support(b, Vec3<S>(-(R.transpose() * n)));
  return a.half_length * std::abs(n.z()) + a.radius * std::sqrt(std::max(n.x() * n.x() + n.y() * n.y(), S(0))) - n.dot(R * v + t);
}

/// The vertex of hull b deepest into the side of a solid of revolution (axis ax through c, b's
/// frame) near vertex v: a vertex x that is b's support along -(q(x) / |q(x)| + lean ax), q(x) =
/// P (x - c) its offset from the axis (P = I - ax ax^T), the outward side normal at x's azimuth up
/// to its length: lean 0 for a cylinder (the overlap along n = q / |q|, normal to the axis towards
/// b, is then r - |q|), r / (2h) for a cone (its side normal (2h q / |q| + r ax) / L). Climbs from
/// v to the neighbour farthest along that direction (taken afresh at each vertex; all vertices for
/// hulls without an edge graph) for at most kSideVertexSteps steps; -1 when it does not settle or a
/// vertex lies on the axis. The support test holds up to rounding.
inline constexpr int kSideVertexSteps = 8;
template <class S>
int side_vertex(const ConvexHull<S>& b, const Vec3<S>& ax, const Vec3<S>& c, int v, S lean = S(0)) {
  const S* p = b.vertices.data();
  const int nv = static_cast<int>(b.vertices.rows());
  for (int step = 0; step < kSideVertexSteps; ++step) {
    const S* x = p + 3 * v;
    const Vec3<S> y(x[0] - c.x(), x[1] - c.y(), x[2] - c.z());
    const Vec3<S> q = y - y.dot(ax) * ax;
    const S qq = q.squaredNorm();
    if (!(qq > S(0))) return -1;
    const Vec3<S> w = lean == S(0) ? q : Vec3<S>(q + (lean * std::sqrt(qq)) * ax);  // the side normal, scaled by |q|
    const auto inward = [&](int i) { return -(p[3 * i] * w.x() + p[3 * i + 1] * w.y() + p[3 * i + 2] * w.z()); };
    S best = inward(v);
    int next = v;
    const auto consider = [&](int i) {
      const S s = inward(i);
      if (s > best) {
        best = s;
        next = i;
      }
    };
    if (b.neighbors.empty()) {
      for (int i = 0; i < nv; ++i) consider(i);
    } else {
      for (int k = b.neighbor_start[static_cast<std::size_t>(v)]; k < b.neighbor_start[static_cast<std::size_t>(v) + 1]; ++k)
        consider(b.neighbors[static_cast<std::size_t>(k)]);
    }
    if (next == v) return v;
    v = next;
  }
  return -1;
}

/// The pass over the faces of hull b that the cylinder and cone candidates share, in b's frame
/// (the solid's axis ax and centre c there): along_axis[k] = m_k . ax and overlap[k] = offset_k -
/// m_k . c + the solid's support along -m_k, the overlap along minus face k's outward normal m_k;
/// with_reach(F, D) adds that support to F (a function of D = m . ax alone: the solid is one of
/// revolution), as
/// whole arrays (Eigen's packets: two or four faces an instruction); returns the least overlap and
/// sets `face` to its face. A negative one separates the shapes (a separating-axis test of the
/// hull's faces).
template <class S, class Reach>
S hull_face_pass(const ConvexHull<S>& b, const Vec3<S>& ax, const Vec3<S>& c, const Reach& with_reach, S* along_axis, S* overlap,
                 std::size_t& face) {
  const std::size_t nf = b.faces.size();
  using Faces = Eigen::Array<S, Eigen::Dynamic, 1>;
  const Eigen::Index count = static_cast<Eigen::Index>(nf);
  const S* nx = b.face_planes.data();
  const Eigen::Map<const Faces> NX(nx, count), NY(nx + nf, count), NZ(nx + 2 * nf, count), OFF(nx + 3 * nf, count);
  Eigen::Map<Faces> D(along_axis, count), F(overlap, count);
  D = NX * ax.x() + NY * ax.y() + NZ * ax.z();
  F = OFF - (NX * c.x() + NY * c.y() + NZ * c.z());
  F = with_reach(F, D);
  S best = std::numeric_limits<S>::infinity();
  face = 0;
  for (std::size_t k = 0; k < nf; ++k) {
    if (overlap[k] < best) {
      best = overlap[k];
      face = k;
    }
  }
  return best;
}

/// The face candidate the cylinder and cone candidates share: x, the solid's deepest point across
/// hull b's face `face` (its support along n = -R m, a's frame; b placed by R, t there), offered
/// with the face's overlap `f` and the radius of the largest ball about x inside the hull (its
/// least distance to the face planes; 0 when x is outside: the upper bound only, a seed for EPA).
template <class S, class A>
void offer_hull_face(const A& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, std::size_t face, S f, CandidateBounds<S>& k) {
  const std::size_t nf = b.faces.size();
  using Faces = Eigen::Array<S, Eigen::Dynamic, 1>;
  const Eigen::Index count = static_cast<Eigen::Index>(nf);
  const S* nx = b.face_planes.data();
  const Eigen::Map<const Faces> NX(nx, count), NY(nx + nf, count), NZ(nx + 2 * nf, count), OFF(nx + 3 * nf, count);
  const Vec3<S> m = R * Vec3<S>(nx[face], nx[nf + face], nx[2 * nf + face]);
  const Vec3<S> x = support(a, Vec3<S>(-m));
  const Vec3<S> y = R.transpose() * (x - t);
  const S rho = (OFF - (NX * y.x() + NY * y.y() + NZ * y.z())).minCoeff();
  k.offer(Vec3<S>(-m), f, x, rho > S(0) ? rho : S(0));
}

/// What cylinder_hull_candidates found: apart (a face plane of the hull separates them by more
/// than the margin), else certified or not, with `best` the best candidate's normal and depth.
enum class CylinderHullVerdict { Apart, Certified, Open };

/// The candidates of the file comment for cylinder a (its frame) and hull b placed by R, t there
/// (use_cylinder_hull_candidates(b) required): Apart when a face plane separates them by more than
/// `margin`; Certified with `out` set (normal from a towards b, depth, depth_gap, the deciding
/// point, iterations the candidates offered) when the best bounds are within `tolerance`; else
/// Open with out.normal and out.depth the best candidate's (depth infinite when none applied).
template <class S>
CylinderHullVerdict cylinder_hull_candidates(const Cylinder<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, S margin,
                                             S tolerance, ConvexContact<S>& out) {
  const S r = a.radius, h = a.half_length;
  // in b's frame: the cylinder's axis and centre
  const Vec3<S> ax = R.row(2).transpose(), c = -(R.transpose() * t);
  const std::size_t nf = b.faces.size();
  const S* nx = b.face_planes.data();
  const S* ny = nx + nf;
  const S* nz = ny + nf;
  // the faces: f_k = offset_k - n_k . c + h |n_k . ax| + r sqrt(1 - (n_k . ax)^2)
  S along_axis[kCylinderHullMaxFaces];  // m_k . z of each face
  S overlap[kCylinderHullMaxFaces];
  std::size_t face = 0;
  const S best_face = hull_face_pass(
      b, ax, c, [&](const auto& F, const auto& D) { return F + h * D.abs() + r * (S(1) - D.square()).max(S(0)).sqrt(); }, along_axis, overlap, face);
  if (best_face < -margin) return CylinderHullVerdict::Apart;
  CandidateBounds<S> k;
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  // the edges across the side: the least f = r + u . (v0 - c) over the crossings u (unit)
  S best_edge = std::numeric_limits<S>::infinity();
  Vec3<S> edge_u = Vec3<S>::Zero();
  int edge = -1;
  const S* p = b.vertices.data();
  for (std::size_t e = 0; e < b.edges.size(); ++e) {
    const HullEdge& g = b.edges[e];
    const S d0 = along_axis[static_cast<std::size_t>(g.f0)], d1 = along_axis[static_cast<std::size_t>(g.f1)];
    if (!(d0 * d1 < S(0))) continue;
    const std::size_t i0 = static_cast<std::size_t>(g.f0), i1 = static_cast<std::size_t>(g.f1);
    const S w0 = std::abs(d1), w1 = std::abs(d0);
    const Vec3<S> u(w0 * nx[i0] + w1 * nx[i1], w0 * ny[i0] + w1 * ny[i1], w0 * nz[i0] + w1 * nz[i1]);
    const S len = u.norm();
    if (!(len > S(0))) continue;
    const S* v = p + 3 * g.v0;
    const S f = r + (u.x() * (v[0] - c.x()) + u.y() * (v[1] - c.y()) + u.z() * (v[2] - c.z())) / len;
    if (f < best_edge) {
      best_edge = f;
      edge_u = u / len;
      edge = static_cast<int>(e);
    }
  }
  int side_start = -1;  // the end of the best crossing edge beyond which its xy foot lies
  if (edge >= 0) {
    const HullEdge& g = b.edges[static_cast<std::size_t>(edge)];
    const Vec3<S> n = -(R * edge_u);  // normal to z up to rounding
    const Vec3<S> p0 = R * Vec3<S>(b.vertices.row(g.v0).transpose()) + t, p1 = R * Vec3<S>(b.vertices.row(g.v1).transpose()) + t;
    // the edge's point where its xy projection lies along n's azimuth
    const S q0 = -n.y() * p0.x() + n.x() * p0.y(), q1 = -n.y() * p1.x() + n.x() * p1.y();
    if (q0 != q1) {
      const S s = q0 / (q0 - q1);
      if (s >= S(0) && s <= S(1)) {
        const Vec3<S> x = p0 + s * (p1 - p0);
        const InsideBall<S> ball = inside_ball(a, x);
        if (ball.rho > S(0)) k.offer(n, best_edge, x, ball.rho);
      } else {
        side_start = s < S(0) ? g.v0 : g.v1;
      }
    }
  }
  // a vertex against the side: when the best crossing edge's foot (the point of its xy line
  // nearest the axis) lies beyond an end, the overlap along the circle normal to the axis falls
  // past that end, towards a vertex x deepest into the side (n = x's radial direction,
  // f = r - |x_xy|), certified by x's own ball (exactly, f = rho, unless a cap is nearer)
  if (side_start >= 0 && !decided()) {
    const int v = side_vertex(b, ax, c, side_start);
    if (v >= 0) {
      const Vec3<S> x = R * Vec3<S>(b.vertices.row(v).transpose()) + t;
      const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
      if (rxy > S(0)) {
        const InsideBall<S> ball = inside_ball(a, x);
        k.offer(Vec3<S>(x.x() / rxy, x.y() / rxy, S(0)), r - rxy, x, std::max(ball.rho, S(0)));
      }
    }
  }
  // the caps: the hull's deepest vertex along -+z (f = h - s x_z), skipped when it cannot beat the
  // best so far: the hull holds its centroid, so f >= h - s z_c
  const S z_c = R.row(2).dot(b.centroid) + t.z();
  for (const S s : {S(1), S(-1)}) {
    if (h - s * z_c >= std::min(k.upper, best_face)) continue;
    const Vec3<S> x = R * support(b, Vec3<S>(-s * ax)) + t;
    const InsideBall<S> ball = inside_ball(a, x);
    if (ball.rho > S(0)) k.offer(Vec3<S>(S(0), S(0), s), h - s * x.z(), x, ball.rho);
  }
  // the best face: the cylinder's deepest point across it and its distance to the hull's boundary
  if (!(decided() && k.upper <= best_face)) offer_hull_face(a, b, R, t, face, best_face, k);
  return k.finish(tolerance, out) ? CylinderHullVerdict::Certified : CylinderHullVerdict::Open;
}

/// Adds to f the terms of hull b (placed by R, t in the frame of f) near unit n: its support
/// feature along -n, its farthest vertex v (a linear term), or the edge from v to the neighbour u
/// nearly as far (within 1e-3 of the size along -n: linear plus an abs term, h_B(-w) >= max(-w . v,
/// -w . u)). A lower bound of the hull's part of the overlap everywhere (any points of the hull
/// bound its support from below), equal to it near n where that feature is the hull's support.
template <class S>
void add_hull_feature_terms(const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f) {
  const Vec3<S> d = -(R.transpose() * n);
  const S* p = b.vertices.data();
  const auto along = [&](int i) { return p[3 * i] * d.x() + p[3 * i + 1] * d.y() + p[3 * i + 2] * d.z(); };
  // the farthest vertex v (the hull's support: a climb on its edge graph, a scan for small
  // hulls) and, of its neighbours (of all vertices for small hulls, which have no edge graph), the
  // farthest u
  const int nv = static_cast<int>(b.vertices.rows());
  const int v = support_vertex(b, d);
  const S best = along(v);
  int u = -1;
  S second = -std::numeric_limits<S>::infinity();
  const auto consider = [&](int i) {
    const S x = along(i);
    if (i != v && x > second) {
      second = x;
      u = i;
    }
  };
  if (b.neighbors.empty()) {
    for (int i = 0; i < nv; ++i) consider(i);
  } else {
    for (int q = b.neighbor_start[static_cast<std::size_t>(v)]; q < b.neighbor_start[static_cast<std::size_t>(v) + 1]; ++q)
      consider(b.neighbors[static_cast<std::size_t>(q)]);
  }
  const Vec3<S> pv = R * Vec3<S>(b.vertices.row(v).transpose()) + t;
  if (u >= 0 && best - second <= S(1e-3) * b.size) {
    const Vec3<S> pu = R * Vec3<S>(b.vertices.row(u).transpose()) + t;
    const Vec3<S> e = pu - pv;
    const S len = e.norm();
    if (len > S(0)) {
      f.add(Vec3<S>(e / len), len / S(2), false);
      f.linear -= (pv + pu) / S(2);
      return;
    }
  }
  f.linear -= pv;
}

/// The terms of convex/local_certificate.hpp for cylinder a (its frame) and hull b placed by R, t
/// there, near unit n: the cylinder's disc and abs terms about z, and the hull's support feature
/// along -n (add_hull_feature_terms). A lower bound of the overlap everywhere, equal to it near n
/// where that feature is the hull's support.
template <class S>
OverlapTerms<S> cylinder_hull_terms(const Cylinder<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n) {
  OverlapTerms<S> f;
  f.add(Vec3<S>::UnitZ(), a.radius, true);
  f.add(Vec3<S>::UnitZ(), a.half_length, false);
  add_hull_feature_terms(b, R, t, n, f);
  return f;
}

}  // namespace impact::detail
