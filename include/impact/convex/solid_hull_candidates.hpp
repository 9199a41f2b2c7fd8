// SPDX-License-Identifier: MIT
/// \file
/// The skeleton that the candidates of a cylinder and of a cone against a convex hull share
/// (convex/cylinder_hull_pair.hpp, convex/cone_hull_pair.hpp: their file comments give each
/// candidate's formula), in the solid's frame (its axis z, the hull placed by R, t there):
/// solid_hull_candidates runs the pass over the hull's faces (also the faces' separating-axis
/// test), the best edge across the solid's side and its point at the normal's azimuth, the vertex
/// deepest into the side beyond that edge's end (side_vertex), the hull's deepest vertex across
/// each flat end (a cylinder's two caps, a cone's base) and the best face, keeping the best upper
/// and lower bounds (CandidateBounds). What differs between the shapes comes from a part object
/// (CylinderHullPart, ConeHullPart) with:
///   shape                          the cylinder or cone;
///   face_reach(F, D)               the solid's support along minus each face normal added to the
///                                  face's overlap without it, F (D = m . axis; whole arrays);
///   best_crossing_edge(b, ax, along_axis, c, f, u)  the best edge across the side (its index, -1
///                                  for none; f its overlap, u its unit normal; b's frame, the
///                                  axis ax, the centre c);
///   offer_edge_point(k, n, f, x)   that edge's point x offered with its lower bound;
///   lean()                         side_vertex's lean (0 for a cylinder);
///   offer_side_vertex(k, x, rxy)   the side vertex x (|x_xy| = rxy) offered;
///   ends                           the signs s of the flat ends' normals (0, 0, s);
///   offer_end(k, s, x)             the hull's deepest vertex x across that end offered.
///
/// Numerical contract: separating test EXACT up to rounding (margin given by the caller);
/// candidates APPROXIMATE as EPA's: depth is f(normal) (an upper bound up to rounding),
/// depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/shapes.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact::detail {

/// Hulls with at most this many faces take the candidates (their per-face values live on the stack).
inline constexpr std::size_t kCylinderHullMaxFaces = 256;

/// Whether hull b can take the cylinder's and cone's candidates (face planes and edges built by convex_hull()).
template <class S>
inline bool use_cylinder_hull_candidates(const ConvexHull<S>& b) {
  return !b.face_planes.empty() && b.faces.size() <= kCylinderHullMaxFaces && b.face_planes.size() == 4 * b.faces.size();
}

/// The outward unit normal of hull b's face k (from its face planes, stored by component).
template <class S>
inline Vec3<S> hull_face_normal(const ConvexHull<S>& b, std::size_t k) {
  const std::size_t nf = b.faces.size();
  const S* m = b.face_planes.data();
  return Vec3<S>(m[k], m[nf + k], m[2 * nf + k]);
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
    for_each_neighbor(b, v, consider);
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
/// True when it became the best candidate.
template <class S, class A>
bool offer_hull_face(const A& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, std::size_t face, S f,
                     CandidateBounds<S>& k) {
  const std::size_t nf = b.faces.size();
  using Faces = Eigen::Array<S, Eigen::Dynamic, 1>;
  const Eigen::Index count = static_cast<Eigen::Index>(nf);
  const S* nx = b.face_planes.data();
  const Eigen::Map<const Faces> NX(nx, count), NY(nx + nf, count), NZ(nx + 2 * nf, count), OFF(nx + 3 * nf, count);
  const Vec3<S> m = R * Vec3<S>(nx[face], nx[nf + face], nx[2 * nf + face]);
  const Vec3<S> x = support(a, Vec3<S>(-m));
  const Vec3<S> y = R.transpose() * (x - t);
  const S rho = (OFF - (NX * y.x() + NY * y.y() + NZ * y.z())).minCoeff();
  const bool best = f < k.upper;
  k.offer(Vec3<S>(-m), f, x, rho > S(0) ? rho : S(0));
  return best;
}

/// What the candidates found (solid_hull_candidates): apart (a face plane of the hull separates them by more
/// than the margin), else certified or not, with `best` the best candidate's normal and depth.
enum class CylinderHullVerdict { Apart, Certified, Open };

/// The candidates of a solid of revolution part.shape (its frame) and hull b placed by R, t there
/// (use_cylinder_hull_candidates(b) required), as the file comment says: Apart when a face plane
/// separates them by more than `margin`; Certified with `out` set (normal from the solid towards
/// b, depth, depth_gap, the deciding point, iterations the candidates offered) when the best bounds
/// are within `tolerance`; else Open with out.normal and out.depth the best candidate's (depth
/// infinite when none applied). `best_face`, when given, is set to the face whose candidate is the
/// best one, else to b.faces.size().
template <class S, class Part>
CylinderHullVerdict solid_hull_candidates(const Part& part, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, S margin,
                                          S tolerance, ConvexContact<S>& out, std::size_t* best_face = nullptr) {
  const auto& a = part.shape;
  const S h = a.half_length;
  // in b's frame: the solid's axis and centre
  const Vec3<S> ax = R.row(2).transpose(), c = -(R.transpose() * t);
  S along_axis[kCylinderHullMaxFaces];  // m_k . z of each face
  S overlap[kCylinderHullMaxFaces];
  std::size_t face = 0;
  const S face_overlap = hull_face_pass(
      b, ax, c, [&](const auto& F, const auto& D) { return part.face_reach(F, D); }, along_axis, overlap, face);
  if (best_face) *best_face = b.faces.size();
  if (face_overlap < -margin) return CylinderHullVerdict::Apart;
  CandidateBounds<S> k;
  const auto decided = [&] { return k.upper - k.lower <= tolerance; };
  // the edges across the side
  S best_edge = std::numeric_limits<S>::infinity();
  Vec3<S> edge_u = Vec3<S>::Zero();
  const int edge = part.best_crossing_edge(b, ax, along_axis, c, best_edge, edge_u);
  int side_start = -1;  // the end of the best crossing edge beyond which its point at n's azimuth lies
  if (edge >= 0) {
    const HullEdge& g = b.edges[static_cast<std::size_t>(edge)];
    const Vec3<S> n = -(R * edge_u);  // the side's normal there up to rounding
    const Vec3<S> p0 = R * Vec3<S>(b.vertices.row(g.v0).transpose()) + t, p1 = R * Vec3<S>(b.vertices.row(g.v1).transpose()) + t;
    // the edge's point in the plane through the axis at n's azimuth
    const S q0 = -n.y() * p0.x() + n.x() * p0.y(), q1 = -n.y() * p1.x() + n.x() * p1.y();
    if (q0 != q1) {
      const S s = q0 / (q0 - q1);
      if (s >= S(0) && s <= S(1)) {
        part.offer_edge_point(k, n, best_edge, Vec3<S>(p0 + s * (p1 - p0)));
      } else {
        side_start = s < S(0) ? g.v0 : g.v1;
      }
    }
  }
  // a vertex against the side: when the best crossing edge's point at n's azimuth lies beyond an
  // end, the overlap along the side normals falls past that end, towards a vertex x deepest into
  // the side, certified by x's own ball (exactly, f = rho, unless a flat end is nearer)
  if (side_start >= 0 && !decided()) {
    const int v = side_vertex(b, ax, c, side_start, part.lean());
    if (v >= 0) {
      const Vec3<S> x = R * Vec3<S>(b.vertices.row(v).transpose()) + t;
      const S rxy = std::sqrt(x.x() * x.x() + x.y() * x.y());
      if (rxy > S(0)) part.offer_side_vertex(k, x, rxy);
    }
  }
  // the flat ends: the hull's deepest vertex along -s z (f = h - s x_z), skipped when it cannot
  // beat the best so far: the hull holds its centroid, so f >= h - s z_c
  const S z_c = R.row(2).dot(b.centroid) + t.z();
  for (const S s : part.ends) {
    if (h - s * z_c >= std::min(k.upper, face_overlap)) continue;
    part.offer_end(k, s, Vec3<S>(R * support(b, Vec3<S>(-s * ax)) + t));
  }
  // the best face: the solid's deepest point across it and its distance to the hull's boundary
  if (!(decided() && k.upper <= face_overlap) && offer_hull_face(a, b, R, t, face, face_overlap, k) && best_face)
    *best_face = face;
  return k.finish(tolerance, out) ? CylinderHullVerdict::Certified : CylinderHullVerdict::Open;
}

}  // namespace impact::detail
