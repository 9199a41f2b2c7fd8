// SPDX-License-Identifier: MIT
/// \file
/// Cone against convex hull (convex/certified_pair.hpp's cone–hull penetration), in the cone's frame
/// (base disc of radius r at z = -h, apex (0, 0, h); the hull placed by R, t there), built as
/// convex/cylinder_hull_pair.hpp is for a cylinder. With f(n) = h_A(n) + h_B(-n), the overlap along
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
#include "impact/convex/cylinder_hull_pair.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/deepest_point.hpp"
#include "impact/convex/shapes.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact::detail {

/// The candidates of the file comment for cone a (its frame) and hull b placed by R, t there
/// (use_cylinder_hull_candidates(b) required): Apart when a face plane separates them by more than
/// `margin`; Certified with `out` set (normal from a towards b, depth, depth_gap, the deciding
/// point, iterations the candidates offered) when the best bounds are within `tolerance`; else
/// Open with out.normal and out.depth the best candidate's (depth infinite when none applied).
template <class S>
CylinderHullVerdict cone_hull_candidates(const Cone<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, S margin,
                                         S tolerance, ConvexContact<S>& out) {
  const S r = a.radius, h = a.half_length;
  const S L = cone_slant(a), k_side = r / L;  // a side normal's z; h_A there is h k_side
  // in b's frame: the cone's axis and centre
  const Vec3<S> ax = R.row(2).transpose(), c = -(R.transpose() * t);
  const std::size_t nf = b.faces.size();
  const S* nx = b.face_planes.data();
  const S* ny = nx + nf;
  const S* nz = ny + nf;
  // the faces: f_k = offset_k - m_k . c + max(-h D_k, r sqrt(1 - D_k^2) + h D_k), D_k = m_k . ax
  S along_axis[kCylinderHullMaxFaces];
  S overlap[kCylinderHullMaxFaces];
  std::size_t face = 0;
  const S best_face = hull_face_pass(
      b, ax, c, [&](const auto& F, const auto& D) { return F + (-h * D).max(r * (S(1) - D.square()).max(S(0)).sqrt() + h * D); },
      along_axis, overlap, face);
  if (best_face < -margin) return CylinderHullVerdict::Apart;
  CandidateBounds<S> k;
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  // the edges across the side: an edge whose faces' normals lie on either side of the circle of
  // hull normals u_z = -k_side (its arc crosses it once) holds the crossing u, unit, normal to the
  // edge direction g: u = (-k_side a' +- sqrt(|a'|^2 - k_side^2) g x a') / |a'|^2 with a' the axis
  // less its part along g, the sign putting u between the two normals; f = h k_side + u . (v0 - c)
  S best_edge = std::numeric_limits<S>::infinity();
  Vec3<S> edge_u = Vec3<S>::Zero();
  int edge = -1;
  const S* p = b.vertices.data();
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
      const Vec3<S> m0(nx[i0], ny[i0], nz[i0]), m1(nx[i1], ny[i1], nz[i1]);
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
  int side_start = -1;  // the end of the best crossing edge beyond which its point at n's azimuth lies
  if (edge >= 0) {
    const HullEdge& g = b.edges[static_cast<std::size_t>(edge)];
    const Vec3<S> n = -(R * edge_u);  // a side normal up to rounding
    const Vec3<S> p0 = R * Vec3<S>(b.vertices.row(g.v0).transpose()) + t, p1 = R * Vec3<S>(b.vertices.row(g.v1).transpose()) + t;
    // the edge's point in the plane through the axis at n's azimuth
    const S q0 = -n.y() * p0.x() + n.x() * p0.y(), q1 = -n.y() * p1.x() + n.x() * p1.y();
    if (q0 != q1) {
      const S s = q0 / (q0 - q1);
      if (s >= S(0) && s <= S(1)) {
        const Vec3<S> x = p0 + s * (p1 - p0);
        k.offer(n, best_edge, x, std::max(inside_ball(a, x, L).rho, S(0)));  // rho <= 0: the upper bound only (EPA's seed)
      } else {
        side_start = s < S(0) ? g.v0 : g.v1;
      }
    }
  }
  // a vertex against the side: when the best crossing edge's point at n's azimuth lies beyond an
  // end, the overlap along the side normals falls past that end, towards a vertex x deepest into
  // the side (n the side normal at x's azimuth), certified by x's own ball (exactly, f = rho,
  // unless the base is nearer)
  if (side_start >= 0 && !decided()) {
    const int v = side_vertex(b, ax, c, side_start, r / (S(2) * h));
    if (v >= 0) {
      const Vec3<S> x = R * Vec3<S>(b.vertices.row(v).transpose()) + t;
      const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
      if (rxy > S(0)) {
        const Vec3<S> n(S(2) * h * x.x() / (rxy * L), S(2) * h * x.y() / (rxy * L), k_side);
        k.offer(n, (h * r - S(2) * h * rxy - r * x.z()) / L, x, std::max(inside_ball(a, x, L).rho, S(0)));
      }
    }
  }
  // the base: the hull's highest vertex (f = h + x_z), skipped when it cannot beat the best so far:
  // the hull holds its centroid, so f >= h + z_c
  const S z_c = R.row(2).dot(b.centroid) + t.z();
  if (h + z_c < std::min(k.upper, best_face)) {
    const Vec3<S> x = R * support(b, ax) + t;
    k.offer(Vec3<S>(S(0), S(0), S(-1)), h + x.z(), x, std::max(inside_ball(a, x, L).rho, S(0)));
  }
  // the best face: the cone's deepest point across it and its distance to the hull's boundary
  if (!(decided() && k.upper <= best_face)) offer_hull_face(a, b, R, t, face, best_face, k);
  return k.finish(tolerance, out) ? CylinderHullVerdict::Certified : CylinderHullVerdict::Open;
}

}  // namespace impact::detail
