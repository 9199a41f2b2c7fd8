// SPDX-License-Identifier: MIT
/// \file
/// Cone against convex hull (convex/certified_pair.hpp's cone–hull penetration), in the cone's frame
/// (base disc of radius r at z = -h, apex (0, 0, h); the hull placed by R, t there), on the
/// skeleton the cylinder's candidates run on too (convex/solid_hull_candidates.hpp; this file gives
/// the cone's part, ConeHullPart). With f(n) = h_A(n) + h_B(-n), the overlap along
/// a unit n from the cone towards the hull (the depth is min_n f) and h_A(w) = max(h w_z, r |w_xy| -
/// h w_z), the features of the Minkowski difference with a finite set of normals give candidates,
/// each an upper bound f(n) at its direction:
///   a face of the hull against the cone's deepest point across it (the apex or a rim point):
///       n = -m, m the face's outward normal, f = offset + m . t + max(-h D, r sqrt(1 - D^2) + h D)
///       with D = m_z (closed form; a negative one separates them, so the loop over the faces is
///       also the hull faces' separating-axis test);
///   a vertex of the hull against the base: n = -z, the hull's highest vertex, f = h + x_z;
///   an edge of the hull across the cone's side: n a side normal, (2h e + r z) / L (L =
///       sqrt(4h^2 + r^2), e a unit azimuth), normal to the edge, where the edge's arc on the Gauss
///       map (from one face's normal to the other's) crosses the circle -n of the side normals
///       (the hull normals u with u_z = -r / L): h_A(n) = h r / L (the whole ruling), and h_B(-n) =
///       u . (edge vertex) with no support call;
///   a vertex of the hull against the side: n the side normal at x's azimuth, f = (h r - 2h |x_xy|
///       - r x_z) / L, for a vertex x that is the hull's support along -n (side_vertex's climb,
///       lean r / (2h), from the end of the best crossing edge past which its point at n's
///       azimuth lies).
/// The apex against a hull edge or vertex and the base rim against an edge or vertex have no finite
/// set of normals: no candidate (EPA).
/// A candidate is certified by a lower bound rho from a point x of one shape inside the other (the
/// ball of radius rho about x, x's distance to that shape's boundary, lies inside it, so every
/// separating translation is at least rho long): the face's cone point inside the hull (rho its
/// least distance to the hull's face planes), the base's vertex, the side's vertex or the edge's
/// point at n's azimuth inside the cone (convex/deepest_point.hpp's inside_ball; exact, rho = f,
/// where that point is nearer the boundary it meets than the other). When the best upper and lower
/// bounds are within the tolerance the answer is certified as EPA's is (depth = the upper bound,
/// depth_gap = upper - lower); otherwise the caller runs GJK and EPA, seeded with the best
/// candidate's normal and stopped early by the local certificate on convex/cone_hull_terms.hpp.
///
/// Numerical contract: separating test EXACT up to rounding (margin given by the caller);
/// candidates APPROXIMATE as EPA's: depth is f(normal) (an upper bound up to rounding),
/// depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/solid_hull_candidates.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact::detail {

/// The cone's part of solid_hull_candidates (convex/solid_hull_candidates.hpp): the formulas of the
/// file comment.
template <class S>
struct ConeHullPart {
  const Cone<S>& shape;
  S L = cone_slant(shape), k_side = shape.radius / L;  // a side normal's z; h_A there is h k_side
  static constexpr S ends[1] = {S(-1)};                // the base

  // the faces: f_k = offset_k - m_k . c + max(-h D_k, r sqrt(1 - D_k^2) + h D_k), D_k = m_k . ax
  template <class F, class D>
  auto face_reach(const F& f, const D& d) const {
    const S r = shape.radius, h = shape.half_length;
    return f + (-h * d).max(r * (S(1) - d.square()).max(S(0)).sqrt() + h * d);
  }

  /// The edges across the side: an edge whose faces' normals lie on either side of the circle of
  /// hull normals u_z = -k_side (its arc crosses it once) holds the crossing u, unit, normal to the
  /// edge direction g: u = (-k_side a' +- sqrt(|a'|^2 - k_side^2) g x a') / |a'|^2 with a' the axis
  /// less its part along g, the sign putting u between the two normals; f = h k_side + u . (v0 - c).
  int best_crossing_edge(const ConvexHull<S>& b, const Vec3<S>& ax, const S* along_axis, const Vec3<S>& c, S& best_edge,
                         Vec3<S>& edge_u) const {
    const S h = shape.half_length;
    const S* p = b.vertices.data();
    int edge = -1;
    for (std::size_t e = 0; e < b.edges.size(); ++e) {
      const HullEdge& g = b.edges[e];
      const std::size_t i0 = static_cast<std::size_t>(g.f0), i1 = static_cast<std::size_t>(g.f1);
      if (!((along_axis[i0] + k_side) * (along_axis[i1] + k_side) < S(0))) continue;
      const S* v0 = p + 3 * g.v0;
      const S* v1 = p + 3 * g.v1;
      Vec3<S> d(v1[0] - v0[0], v1[1] - v0[1], v1[2] - v0[2]);
      const S dd = d.squaredNorm();
      if (!(dd > S(0))) continue;
      d /= std::sqrt(dd);
      const Vec3<S> ap = ax - ax.dot(d) * d;
      const S aa = ap.squaredNorm(), disc = aa - k_side * k_side;
      if (!(disc > S(0))) continue;
      const Vec3<S> along = (-k_side / aa) * ap, across = (std::sqrt(disc) / aa) * d.cross(ap);
      Vec3<S> u = along + across;
      {  // between the faces' normals m0, m1 (normal to g as u is): u . m1 >= (m0 . m1)(u . m0) and back
        const Vec3<S> m0 = hull_face_normal(b, i0), m1 = hull_face_normal(b, i1);
        const S c01 = m0.dot(m1), p0 = u.dot(m0), p1 = u.dot(m1);
        if (!(p1 >= c01 * p0 && p0 >= c01 * p1)) u = along - across;
      }
      const S f = h * k_side + (u.x() * (v0[0] - c.x()) + u.y() * (v0[1] - c.y()) + u.z() * (v0[2] - c.z()));
      if (f < best_edge) {
        best_edge = f;
        edge_u = u;
        edge = static_cast<int>(e);
      }
    }
    return edge;
  }
  /// The edge's point at n's azimuth, offered with its ball inside the cone (rho <= 0: the upper
  /// bound only, EPA's seed).
  void offer_edge_point(CandidateBounds<S>& k, const Vec3<S>& n, S f, const Vec3<S>& x) const {
    k.offer(n, f, x, std::max(inside_ball(shape, x, L).rho, S(0)));
  }
  S lean() const { return shape.radius / (S(2) * shape.half_length); }
  /// The vertex against the side: n the side normal at x's azimuth, f = (h r - 2h |x_xy| - r x_z) / L.
  void offer_side_vertex(CandidateBounds<S>& k, const Vec3<S>& x, S rxy) const {
    const S r = shape.radius, h = shape.half_length;
    const Vec3<S> n(S(2) * h * x.x() / (rxy * L), S(2) * h * x.y() / (rxy * L), k_side);
    k.offer(n, (h * r - S(2) * h * rxy - r * x.z()) / L, x, std::max(inside_ball(shape, x, L).rho, S(0)));
  }
  /// The hull's highest vertex against the base (s = -1): f = h + x_z.
  void offer_end(CandidateBounds<S>& k, S s, const Vec3<S>& x) const {
    k.offer(Vec3<S>(S(0), S(0), s), shape.half_length - s * x.z(), x, std::max(inside_ball(shape, x, L).rho, S(0)));
  }
};

/// The candidates of the file comment for cone a (its frame) and hull b placed by R, t there
/// (use_cylinder_hull_candidates(b) required): solid_hull_candidates with the cone's part.
template <class S>
CylinderHullVerdict cone_hull_candidates(const Cone<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, S margin,
                                         S tolerance, ConvexContact<S>& out) {
  return solid_hull_candidates(ConeHullPart<S>{a}, b, R, t, margin, tolerance, out);
}

}  // namespace impact::detail
