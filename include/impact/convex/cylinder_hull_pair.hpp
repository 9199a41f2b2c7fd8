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
/// The skeleton (the passes, their order, the bounds kept) is convex/solid_hull_candidates.hpp's,
/// shared with the cone; this file gives the cylinder's part (CylinderHullPart). The face loop
/// runs on whole arrays (Eigen's packets). When the best upper and lower
/// bounds are within the tolerance the answer is certified as EPA's is (depth = the upper bound,
/// depth_gap = upper - lower); otherwise (an edge or a vertex against the rim, a contact whose
/// ball is cut) the caller runs EPA, stopped early by the local certificate of
/// convex/local_certificate.hpp on cylinder_hull_terms: the cylinder's terms and the hull's
/// feature at EPA's normal (a vertex: a linear term; an edge: linear plus an abs term), a lower
/// bound of the overlap everywhere, accepted where the true overlap at the certified normal is
/// within the tolerance of it; at a face candidate's normal (a rim against a face, its ball cut by
/// a neighbouring face), on the cylinder's terms and a square inside that face
/// (add_hull_face_square_terms: the vertex and edge terms miss the face's kink).
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
#include "impact/convex/solid_hull_candidates.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace impact::detail {

/// The overlap of cylinder a (its frame) and hull b (placed by R, t there) along unit n, the hull's
/// part from its support point.
template <class S>
S cylinder_hull_overlap(const Cylinder<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n) {
  const Vec3<S> v = support(b, Vec3<S>(-(R.transpose() * n)));
  return a.half_length * std::abs(n.z()) + a.radius * std::sqrt(std::max(n.x() * n.x() + n.y() * n.y(), S(0))) - n.dot(R * v + t);
}

/// The cylinder's part of solid_hull_candidates (convex/solid_hull_candidates.hpp): the formulas of
/// the file comment.
template <class S>
struct CylinderHullPart {
  const Cylinder<S>& shape;
  static constexpr S ends[2] = {S(1), S(-1)};  // the caps

  // the faces: f_k = offset_k - n_k . c + h |n_k . ax| + r sqrt(1 - (n_k . ax)^2)
  template <class F, class D>
  auto face_reach(const F& f, const D& d) const {
    return f + shape.half_length * d.abs() + shape.radius * (S(1) - d.square()).max(S(0)).sqrt();
  }

  /// The edges across the side: the least f = r + u . (v0 - c) over the crossings u (unit).
  int best_crossing_edge(const ConvexHull<S>& b, const Vec3<S>&, const S* along_axis, const Vec3<S>& c, S& best_edge,
                         Vec3<S>& edge_u) const {
    const S* p = b.vertices.data();
    int edge = -1;
    for (std::size_t e = 0; e < b.edges.size(); ++e) {
      const HullEdge& g = b.edges[e];
      const S d0 = along_axis[static_cast<std::size_t>(g.f0)], d1 = along_axis[static_cast<std::size_t>(g.f1)];
      if (!(d0 * d1 < S(0))) continue;
      const Vec3<S> m0 = hull_face_normal(b, static_cast<std::size_t>(g.f0)),
                    m1 = hull_face_normal(b, static_cast<std::size_t>(g.f1));
      const S w0 = std::abs(d1), w1 = std::abs(d0);
      const Vec3<S> u(w0 * m0.x() + w1 * m1.x(), w0 * m0.y() + w1 * m1.y(), w0 * m0.z() + w1 * m1.z());
      const S len = u.norm();
      if (!(len > S(0))) continue;
      const S* v = p + 3 * g.v0;
      const S f = shape.radius + (u.x() * (v[0] - c.x()) + u.y() * (v[1] - c.y()) + u.z() * (v[2] - c.z())) / len;
      if (f < best_edge) {
        best_edge = f;
        edge_u = u / len;
        edge = static_cast<int>(e);
      }
    }
    return edge;
  }
  /// The edge's point at n's azimuth, offered when its ball inside the cylinder is not empty.
  void offer_edge_point(CandidateBounds<S>& k, const Vec3<S>& n, S f, const Vec3<S>& x) const {
    const InsideBall<S> ball = inside_ball(shape, x);
    if (ball.rho > S(0)) k.offer(n, f, x, ball.rho);
  }
  S lean() const { return S(0); }
  /// The vertex against the side: n = x's radial direction, f = r - |x_xy|.
  void offer_side_vertex(CandidateBounds<S>& k, const Vec3<S>& x, S rxy) const {
    const InsideBall<S> ball = inside_ball(shape, x);
    k.offer(Vec3<S>(x.x() / rxy, x.y() / rxy, S(0)), shape.radius - rxy, x, std::max(ball.rho, S(0)));
  }
  /// The vertex against cap s, offered when its ball inside the cylinder is not empty.
  void offer_end(CandidateBounds<S>& k, S s, const Vec3<S>& x) const {
    const InsideBall<S> ball = inside_ball(shape, x);
    if (ball.rho > S(0)) k.offer(Vec3<S>(S(0), S(0), s), shape.half_length - s * x.z(), x, ball.rho);
  }
};

/// The candidates of the file comment for cylinder a (its frame) and hull b placed by R, t there
/// (use_cylinder_hull_candidates(b) required): solid_hull_candidates with the cylinder's part
/// (`best_face` as there).
template <class S>
CylinderHullVerdict cylinder_hull_candidates(const Cylinder<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t,
                                             S margin, S tolerance, ConvexContact<S>& out, std::size_t* best_face = nullptr) {
  return solid_hull_candidates(CylinderHullPart<S>{a}, b, R, t, margin, tolerance, out, best_face);
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
  for_each_neighbor(b, v, consider);
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
OverlapTerms<S> cylinder_hull_terms(const Cylinder<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t,
                                    const Vec3<S>& n) {
  OverlapTerms<S> f;
  f.add(Vec3<S>::UnitZ(), a.radius, true);
  f.add(Vec3<S>::UnitZ(), a.half_length, false);
  add_hull_feature_terms(b, R, t, n, f);
  return f;
}

/// The terms of a square P inside face `face` of hull b (placed by R, t in the frame of f): P lies
/// in a triangle of three of the face's vertices (a fan from its first vertex; the one that holds
/// the largest square), in that triangle's plane, centred at x's projection c onto it, of half-side
/// s. The triangle is inside the hull (its corners are vertices), so h_B(-w) >= h_P(-w) = -w . c
/// + s |e0 . w| + s |e1 . w| (e0, e1 orthonormal in the plane), linear plus two abs terms: a lower
/// bound of the hull's part of the overlap everywhere, equal to it at minus the triangle's normal,
/// where the two kinks meet (a merged face's triangles are within its merge angle of its normal:
/// there the bound is only near the overlap, and the certificate fails rather than err). With x
/// the other shape's support along the face's normal, this bounds a contact of the face with a
/// curved point of the other shape (a cylinder's rim), where the hull's vertex and edge terms
/// (add_hull_feature_terms) miss the face. s = delta / sqrt(2) less 1e-6 of it, delta c's least
/// distance to the triangle's edges; false (f unchanged) when c is inside no triangle by more
/// than 1e-9 of the hull's size.
template <class S>
bool add_hull_face_square_terms(const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, std::size_t face, const Vec3<S>& x,
                                OverlapTerms<S>& f) {
  const std::vector<int>& fv = b.faces[face].vertices;
  const Vec3<S> y = R.transpose() * (x - t);
  const auto vertex = [&](std::size_t i) { return Vec3<S>(b.vertices.row(fv[i]).transpose()); };
  S best = S(1e-9) * b.size;
  Vec3<S> centre = Vec3<S>::Zero(), normal = Vec3<S>::Zero();
  for (std::size_t i = 1; i + 1 < fv.size(); ++i) {
    const Vec3<S> p[3] = {vertex(0), vertex(i), vertex(i + 1)};
    const Vec3<S> m = (p[1] - p[0]).cross(p[2] - p[0]);
    const S mm = m.norm();
    if (!(mm > S(0))) continue;
    const Vec3<S> u = m / mm;  // outward: the vertices turn counter-clockwise seen from outside
    const Vec3<S> c = y - u.dot(y - p[0]) * u;
    S delta = std::numeric_limits<S>::infinity();
    for (int k = 0; k < 3; ++k) {  // u x edge points inwards
      const Vec3<S> e = p[(k + 1) % 3] - p[k];
      const S len = e.norm();
      delta = len > S(0) ? std::min(delta, u.cross(e).dot(c - p[k]) / len) : -S(1);
    }
    if (delta > best) {
      best = delta;
      centre = c;
      normal = u;
    }
  }
  if (!(normal.squaredNorm() > S(0))) return false;
  const S s = best / std::sqrt(S(2)) * (S(1) - S(1e-6));
  const Vec3<S> e0 = any_orthogonal(normal), e1 = normal.cross(e0);
  f.add(Vec3<S>(R * e0), s, false);
  f.add(Vec3<S>(R * e1), s, false);
  f.linear -= R * centre + t;
  return true;
}

}  // namespace impact::detail
