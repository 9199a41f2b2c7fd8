// SPDX-License-Identifier: MIT
/// \file
/// The penetration of a box and a convex hull by the separating-axis test, without GJK or EPA.
/// The Minkowski difference K = A - B of two convex polytopes is a polytope whose facet normals are
/// the face normals of A, the face normals of B, and the cross products of an edge of A and an edge
/// of B whose arcs on the Gauss map cross (A's arc, between its two faces' normals, against the
/// negated arc of B). The overlap along a unit n, f(n) = h_A(n) + h_B(-n) (h: support function),
/// is negative on some facet normal exactly when the polytopes are apart (a facet plane of K
/// separates the origin from it), and otherwise its least value over the facet normals is the
/// penetration depth (the distance from the origin to K's boundary). So the test walks the
/// candidate normals, stops at the first negative overlap (no contact), and keeps the least.
///
/// Edge pairs are pruned by the Gauss map: a box's edges along its axis u have arcs that tile the
/// great circle normal to u, so a hull edge gives a facet with one of them exactly when its arc
/// (between its two faces' normals n0, n1) crosses that circle: u . n0 and u . n1 of opposite
/// signs. The facet normal is then u x e (e: the hull edge), oriented into the hull edge's arc, and
/// the overlap along it comes from the two edges' points alone (they are the supporting features).
/// Work: the line between the centres first (one hull support; it separates most apart poses),
/// 3 box axes (6 hull supports), one pass over the hull's faces (3 dot products each, kept
/// for the edges), one over its edges (3 sign tests each, a cross product per crossing).
///
/// Numerical contract: exact up to rounding for box–hull pairs, with one threshold: edge pairs
/// with |u x e| <= sqrt(eps) |e| (nearly parallel) are skipped; their facet lies within that angle
/// of a face normal's, so the depth is within about sqrt(eps) (1.5e-8 double) of the size of the
/// truth, and a pair that close to touching may be reported intersecting. Touching (overlap 0)
/// counts as intersecting. Depth, normal (a towards b) and point (midway between the deepest
/// points of a and b) as convex/query.hpp defines them; on a face of the hull the box's deepest
/// point is the centre of its supporting feature (as box–box reports it).
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace impact {
namespace detail {

/// Faces of a hull up to which the separating-axis passes (box_hull_sat, triangle_hull_sat) keep
/// their per-face values on the stack.
inline constexpr std::size_t kSatStackFaces = 256;

/// Per-face scratch of a separating-axis pass over a hull's faces: each face's overlap `f` and the
/// signs of its normal against the other shape's edges (bit k set, as a number 0..7), on the stack
/// for up to kSatStackFaces faces, on the heap beyond.
template <class S>
struct SatFaceScratch {
  explicit SatFaceScratch(std::size_t faces) {
    if (faces > kSatStackFaces) {
      heap_f.resize(faces);
      heap_signs.resize(faces);
      f = heap_f.data();
      signs = heap_signs.data();
    }
  }
  SatFaceScratch(const SatFaceScratch&) = delete;
  SatFaceScratch& operator=(const SatFaceScratch&) = delete;
  std::array<S, kSatStackFaces> stack_f;
  std::array<S, kSatStackFaces> stack_signs;
  std::vector<S> heap_f, heap_signs;
  S* f = stack_f.data();
  S* signs = stack_signs.data();
};

/// Hulls of at most this many faces meet a box by box_hull_sat, larger ones by GJK + EPA: the
/// test's work grows with the faces and edges, EPA's with the log of them. Callgrind per query on
/// 2000 poses (a box against hulls of n points on an ellipsoid, about 2n - 4 faces), SAT / EPA
/// instructions: n = 8: 1.7k / 3.9k, 40: 5.6k / 7.3k, 60: 6.2k / 6.7k, 70: 8.1k / 8.0k,
/// 100: 10.3k / 8.6k.
inline constexpr std::size_t kSatMaxHullFaces = 128;

/// Whether box_hull_sat answers for hull h (built by convex_hull(), small enough).
template <class S>
inline bool use_box_hull_sat(const ConvexHull<S>& h) {
  return !h.face_planes.empty() && h.faces.size() <= kSatMaxHullFaces;
}

/// Closest points of segments p0 + s (p1 - p0) and q0 + t (q1 - q0), s, t in [0, 1] (the edges of
/// an edge–edge contact; their lines are not parallel there). Writes the two points.
template <class S>
inline void sat_edge_points(const Vec3<S>& p0, const Vec3<S>& p1, const Vec3<S>& q0, const Vec3<S>& q1, Vec3<S>& pa, Vec3<S>& pb) {
  const Vec3<S> d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const S a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r), c = d1.dot(r), b = d1.dot(d2);
  const S den = a * e - b * b;
  const auto clamp01 = [](S x) { return x < S(0) ? S(0) : (x > S(1) ? S(1) : x); };
  S s = den > S(0) ? clamp01((b * f - c * e) / den) : S(0);
  S t = e > S(0) ? (b * s + f) / e : S(0);
  if (t < S(0)) {
    t = S(0);
    s = a > S(0) ? clamp01(-c / a) : S(0);
  } else if (t > S(1)) {
    t = S(1);
    s = a > S(0) ? clamp01((b - c) / a) : S(0);
  }
  pa = p0 + s * d1;
  pb = q0 + t * d2;
}

/// Penetration of a box (a, at pa) and a convex hull (b, at pb) by the separating-axis test (see
/// the file comment). Needs the hull's faces and edges (convex_hull() builds them).
template <class S>
ConvexContact<S> box_hull_sat(const Box<S>& a, const RigidTransform<S>& pa, const ConvexHull<S>& b, const RigidTransform<S>& pb) {
  ConvexContact<S> out;
  // Everything in b's frame: the box's centre c and unit axes u_k (columns of U).
  const Mat3<S> U = pb.R.transpose() * pa.R;
  const Vec3<S> c = pb.R.transpose() * (pa.t - pb.t);
  const Vec3<S>& ha = a.half;
  S best = std::numeric_limits<S>::infinity();
  Vec3<S> best_n = Vec3<S>::UnitZ();  // from a towards b
  int kind = 0, index = 0, sub = 0;   // 0: box axis `index` (sub: sign), 1: hull face, 2: edge `index` with box axis `sub`
  Vec3<S> low[6];                     // b's support along -n for the box axes' n = +-u_k

  {  // The line between the centres: a negative overlap along it separates them (most apart poses;
     // touching within rounding is left to the axes below).
    const Vec3<S> line = b.centroid - c;
    const S len = line.norm();
    if (len > S(0)) {
      const Vec3<S> n = line / len;
      const S f = n.dot(c) + ha[0] * std::abs(U.col(0).dot(n)) + ha[1] * std::abs(U.col(1).dot(n)) + ha[2] * std::abs(U.col(2).dot(n)) -
                  n.dot(support(b, Vec3<S>(-n)));
      if (f < -std::numeric_limits<S>::epsilon() * S(16) * (b.size + ha.norm())) return out;  // beyond rounding
    }
  }

  // The box's face normals: n = +-u_k, f(n) = h_a(n) + h_b(-n).
  for (int k = 0; k < 3; ++k) {
    const Vec3<S> u = U.col(k);
    const S uc = u.dot(c);
    for (int sgn = 0; sgn < 2; ++sgn) {
      const Vec3<S> n = sgn == 0 ? u : Vec3<S>(-u);
      const Vec3<S> p = support(b, Vec3<S>(-n));
      low[2 * k + sgn] = p;
      const S f = (sgn == 0 ? uc : -uc) + ha[k] - n.dot(p);
      if (f < S(0)) return out;
      if (f < best) {
        best = f;
        best_n = n;
        kind = 0;
        index = k;
        sub = sgn;
      }
    }
  }

  // The hull's faces: n = -m (m: the face's outward normal), f = h_a(-m) + offset, in one pass
  // over the planes that the compiler vectorises, keeping the signs of u_k . m for the edges.
  const std::size_t nf = b.faces.size();
  if (b.face_planes.size() != 4 * nf) return out;  // not built by convex_hull(): the caller checks
  SatFaceScratch<S> scratch(nf);  // signs: bit k set when u_k . m < 0
  S* const fs = scratch.f;
  S* const signs = scratch.signs;
  {
    const S* nx = b.face_planes.data();
    const S* ny = nx + nf;
    const S* nz = ny + nf;
    const S* off = nz + nf;
    const S u00 = U(0, 0), u10 = U(1, 0), u20 = U(2, 0), u01 = U(0, 1), u11 = U(1, 1), u21 = U(2, 1), u02 = U(0, 2), u12 = U(1, 2),
            u22 = U(2, 2), cx = c.x(), cy = c.y(), cz = c.z(), h0 = ha[0], h1 = ha[1], h2 = ha[2];
    for (std::size_t j = 0; j < nf; ++j) {
      const S d0 = u00 * nx[j] + u10 * ny[j] + u20 * nz[j];
      const S d1 = u01 * nx[j] + u11 * ny[j] + u21 * nz[j];
      const S d2 = u02 * nx[j] + u12 * ny[j] + u22 * nz[j];
      fs[j] = off[j] - (cx * nx[j] + cy * ny[j] + cz * nz[j]) + h0 * std::abs(d0) + h1 * std::abs(d1) + h2 * std::abs(d2);
      signs[j] = (d0 < S(0) ? S(1) : S(0)) + (d1 < S(0) ? S(2) : S(0)) + (d2 < S(0) ? S(4) : S(0));  // numbers: vectorises
    }
  }
  for (std::size_t j = 0; j < nf; ++j)
    if (fs[j] < best) {
      best = fs[j];
      kind = 1;
      index = static_cast<int>(j);
    }
  if (best < S(0)) return out;
  if (kind == 1) best_n = -b.faces[static_cast<std::size_t>(index)].normal;

  // Edge pairs: a hull edge whose arc crosses the great circle normal to u_k (the signs of u_k . m
  // differ at its two faces).
  const S* V = b.vertices.data();
  const auto vertex = [&](int v) { return Vec3<S>(V[3 * v], V[3 * v + 1], V[3 * v + 2]); };
  const S parallel = std::numeric_limits<S>::epsilon();  // sin^2 of the skipped angle
  for (std::size_t i = 0; i < b.edges.size(); ++i) {
    const HullEdge& e = b.edges[i];
    if (signs[e.f0] == signs[e.f1]) continue;
    const int crossed = static_cast<int>(signs[e.f0]) ^ static_cast<int>(signs[e.f1]);
    for (int k = 0; k < 3; ++k) {
      if (!(crossed & (1 << k))) continue;
      const Vec3<S> p0 = vertex(e.v0);
      const Vec3<S> dir = vertex(e.v1) - p0;
      Vec3<S> m = U.col(k).cross(dir);  // b's outward normal at the crossing, up to sign
      const S len2 = m.squaredNorm();
      if (!(len2 > parallel * dir.squaredNorm())) continue;
      if (m.dot(b.faces[static_cast<std::size_t>(e.f0)].normal + b.faces[static_cast<std::size_t>(e.f1)].normal) < S(0)) m = -m;
      m /= std::sqrt(len2);
      // f(-m) = h_a(-m) + h_b(m), h_b(m) = m . p0 (the edge supports b along m).
      const S f = m.dot(p0) - m.dot(c) + ha[0] * std::abs(U.col(0).dot(m)) + ha[1] * std::abs(U.col(1).dot(m)) +
                  ha[2] * std::abs(U.col(2).dot(m));
      if (f < S(0)) return out;
      if (f < best) {
        best = f;
        best_n = -m;
        kind = 2;
        index = static_cast<int>(i);
        sub = k;
      }
    }
  }

  out.intersecting = true;
  out.depth = std::max(best, S(0));
  // The deepest points (b's frame): on a box face b's supporting vertex; on a hull face the centre
  // of the box's supporting feature; on an edge pair the closest points of the two edges.
  const auto box_feature = [&](const Vec3<S>& n, int free_axis) {
    Vec3<S> p = c;
    for (int k = 0; k < 3; ++k) {
      if (k == free_axis) continue;
      const S s = U.col(k).dot(n);
      if (std::abs(s) >= S(1e-9)) p += (s > S(0) ? ha[k] : -ha[k]) * U.col(k);
    }
    return p;
  };
  Vec3<S> point_a, point_b;
  if (kind == 0) {
    point_b = low[2 * index + sub];
    point_a = point_b + out.depth * best_n;
  } else if (kind == 1) {
    point_a = box_feature(best_n, -1);
    point_b = point_a - out.depth * best_n;
  } else {
    const HullEdge& e = b.edges[static_cast<std::size_t>(index)];
    const Vec3<S> mid = box_feature(best_n, sub);
    const Vec3<S> half_edge = ha[sub] * U.col(sub);
    sat_edge_points(Vec3<S>(mid - half_edge), Vec3<S>(mid + half_edge), vertex(e.v0), vertex(e.v1), point_a, point_b);
  }
  // Each lies on its shape's supporting plane, so their midpoint is on the plane midway.
  out.normal = pb.R * best_n;
  out.point = pb.apply(Vec3<S>((point_a + point_b) / S(2)));
  return out;
}

}  // namespace detail
}  // namespace impact
