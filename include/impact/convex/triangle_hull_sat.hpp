// SPDX-License-Identifier: MIT
/// \file
/// The penetration of a triangle and a convex hull by the separating-axis test, without GJK or
/// EPA (the mesh–hull contacts of convex/mesh_convex.hpp, one call per triangle).
/// As in convex/polytope_sat.hpp: the overlap along a unit n (from the triangle a towards the hull
/// b), f(n) = h_a(n) + h_b(-n), is negative along some facet normal of the Minkowski difference
/// exactly when the two are apart, and otherwise its least value over the facet normals is the
/// penetration depth. For a flat triangle T and a polytope H those normals are: T's two sides
/// +-n_T; the hull's faces, n = -m (m outward); and n = -m for m normal to a triangle edge e_k
/// and a hull edge, when the hull edge's arc on the Gauss map (between its faces' normals m0, m1)
/// crosses the great circle normal to e_k (e_k . m0 and e_k . m1 of opposite signs; m oriented
/// into the arc, where the hull edge supports H along m) and the triangle's edge supports T along
/// -m (the third vertex is not higher along -m: otherwise the pair is a vertex and an edge, no
/// facet). Along such an m, f = m . (p - v_k) (p on the hull edge, v_k on the triangle's).
/// Work: the line between the centroids first (one hull support; it separates most apart
/// triangles), one pass over the hull's faces (six dot products each, vectorised; three of them
/// keep the signs for the edges; the signs as differences of the other three stop the
/// vectorisation and cost 5 % more), one over its edges (a sign test; a cross product per crossing),
/// and two hull supports for +-n_T. Callgrind, the convex bench's mesh–hull poses (a 40-point
/// hull, 76 faces, 114 edges): about 7.3k instructions a triangle against GJK + EPA's 9.8k.
///
/// Numerical contract: exact up to rounding, with the threshold of box_hull_sat: edge pairs with
/// |e_k x d| <= sqrt(eps) |e_k| |d| (nearly parallel) are skipped; their facet lies within that
/// angle of a face normal's, so the depth is within about sqrt(eps) (1.5e-8 in double) of the size
/// of the truth, and a pair that close to touching may be reported intersecting. Touching counts as
/// intersecting. A degenerate triangle (a segment or a point) has no +-n_T; its edges and the
/// hull's faces give the facets. Depth, normal (triangle towards hull) and point (midway between
/// the two deepest points) as convex/query.hpp defines them; where the triangle's face decides,
/// the hull's deepest vertex and its image on the triangle's plane; where a hull face does, the
/// centre of the triangle's deepest vertices (those within 1e-9 of the size of the deepest).
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/polytope_sat.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace impact {
namespace detail {

/// Whether triangle_hull_sat answers for hull h (built by convex_hull(), small enough): the same
/// limit as box_hull_sat's.
template <class S>
inline bool use_triangle_hull_sat(const ConvexHull<S>& h) {
  return use_box_hull_sat(h);
}

/// Penetration of triangle t (a) and hull b, both in b's frame, by the separating-axis test (see
/// the file comment). The contact (normal, point) in b's frame; not intersecting when they are
/// apart. Needs the hull's faces and edges (convex_hull() builds them; use_triangle_hull_sat).
template <class S>
ConvexContact<S> triangle_hull_sat(const Triangle<S>& t, const ConvexHull<S>& b) {
  ConvexContact<S> out;
  const Vec3<S> v[3] = {t.a, t.b, t.c};
  const Vec3<S> e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  const S rounding = std::numeric_limits<S>::epsilon() * S(16) *
                     (b.size + std::max({e[0].cwiseAbs().sum(), e[1].cwiseAbs().sum(), e[2].cwiseAbs().sum()}));

  {  // The line between the centroids: a negative overlap along it separates them (most apart
     // triangles; touching within rounding is left to the axes below).
    const Vec3<S> g = (v[0] + v[1] + v[2]) / S(3);
    const Vec3<S> line = b.centroid - g;
    const S len = line.norm();
    if (len > S(0)) {
      const Vec3<S> n = line / len;
      const S f = std::max({n.dot(v[0]), n.dot(v[1]), n.dot(v[2])}) - n.dot(support(b, Vec3<S>(-n)));
      if (f < -rounding) return out;
    }
  }

  S best = std::numeric_limits<S>::infinity();
  Vec3<S> best_n = Vec3<S>::UnitZ();  // from the triangle towards the hull
  int kind = 0, index = 0, sub = 0;   // 0: the triangle's side (point_b in low), 1: hull face, 2: triangle edge `sub`, hull edge `index`
  Vec3<S> low = Vec3<S>::Zero();

  // The hull's faces: n = -m, f = offset - min_i m . v_i, in one pass over the planes that the
  // compiler vectorises, keeping the signs of m . e_k for the edges.
  const std::size_t nf = b.faces.size();
  if (b.face_planes.size() != 4 * nf || nf == 0) return out;  // not built by convex_hull(): the caller checks
  SatFaceScratch<S> scratch(nf);  // signs: bit k set when m . e_k < 0
  S* const fs = scratch.f;
  S* const signs = scratch.signs;
  {
    const S* nx = b.face_planes.data();
    const S* ny = nx + nf;
    const S* nz = ny + nf;
    const S* off = nz + nf;
    const S ax = v[0].x(), ay = v[0].y(), az = v[0].z(), bx = v[1].x(), by = v[1].y(), bz = v[1].z(), cx = v[2].x(), cy = v[2].y(),
            cz = v[2].z();
    const S e0x = e[0].x(), e0y = e[0].y(), e0z = e[0].z(), e1x = e[1].x(), e1y = e[1].y(), e1z = e[1].z(), e2x = e[2].x(), e2y = e[2].y(),
            e2z = e[2].z();
    for (std::size_t j = 0; j < nf; ++j) {
      const S da = ax * nx[j] + ay * ny[j] + az * nz[j];
      const S db = bx * nx[j] + by * ny[j] + bz * nz[j];
      const S dc = cx * nx[j] + cy * ny[j] + cz * nz[j];
      const S s0 = e0x * nx[j] + e0y * ny[j] + e0z * nz[j];
      const S s1 = e1x * nx[j] + e1y * ny[j] + e1z * nz[j];
      const S s2 = e2x * nx[j] + e2y * ny[j] + e2z * nz[j];
      fs[j] = off[j] - std::min(std::min(da, db), dc);
      signs[j] = (s0 < S(0) ? S(1) : S(0)) + (s1 < S(0) ? S(2) : S(0)) + (s2 < S(0) ? S(4) : S(0));  // numbers: vectorises
    }
  }
  for (std::size_t j = 0; j < nf; ++j)
    if (fs[j] < best) {
      best = fs[j];
      index = static_cast<int>(j);
    }
  if (best < S(0)) return out;
  kind = 1;
  best_n = -b.faces[static_cast<std::size_t>(index)].normal;

  // The triangle's sides: n = +-n_T, f(n_T) = max_i n_T . v_i - min_H n_T . x, f(-n_T) = max_H n_T . x - min_i n_T . v_i.
  const Vec3<S> scaled = e[0].cross(-e[2]);
  const S area2 = scaled.norm();
  if (area2 > S(0)) {
    // the triangle's extent along n from all three vertices: exact also when rounding made n of
    // a collinear triangle (its cross product of a few ulps) point anywhere
    const Vec3<S> n = scaled / area2;
    const S d0 = n.dot(v[0]), d1 = n.dot(v[1]), d2 = n.dot(v[2]);
    const Vec3<S> lo = support(b, Vec3<S>(-n)), hi = support(b, n);
    const S up = std::max({d0, d1, d2}) - n.dot(lo), down = n.dot(hi) - std::min({d0, d1, d2});
    if (up < S(0) || down < S(0)) return out;
    if (up < best) {
      best = up;
      best_n = n;
      kind = 0;
      low = lo;
    }
    if (down < best) {
      best = down;
      best_n = -n;
      kind = 0;
      low = hi;
    }
  }

  // Edge pairs: a hull edge whose arc crosses the great circle normal to e_k.
  const S* V = b.vertices.data();
  const auto vertex = [&](int i) { return Vec3<S>(V[3 * i], V[3 * i + 1], V[3 * i + 2]); };
  const S parallel = std::numeric_limits<S>::epsilon();  // sin^2 of the skipped angle
  for (std::size_t i = 0; i < b.edges.size(); ++i) {
    const HullEdge& he = b.edges[i];
    if (signs[he.f0] == signs[he.f1]) continue;
    const int crossed = static_cast<int>(signs[he.f0]) ^ static_cast<int>(signs[he.f1]);
    const Vec3<S> p0 = vertex(he.v0);
    const Vec3<S> dir = vertex(he.v1) - p0;
    for (int k = 0; k < 3; ++k) {
      if (!(crossed & (1 << k))) continue;
      Vec3<S> m = e[k].cross(dir);  // the hull's outward normal at the crossing, up to sign
      const S len2 = m.squaredNorm();
      if (!(len2 > parallel * e[k].squaredNorm() * dir.squaredNorm())) continue;
      if (m.dot(b.faces[static_cast<std::size_t>(he.f0)].normal + b.faces[static_cast<std::size_t>(he.f1)].normal) < S(0)) m = -m;
      // the triangle's edge k supports it along -m unless the third vertex is higher there
      if (m.dot(v[(k + 2) % 3] - v[k]) < S(0)) continue;
      m /= std::sqrt(len2);
      const S f = m.dot(p0 - v[k]);
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
  Vec3<S> point_a, point_b;
  if (kind == 0) {  // the hull's deepest vertex, and its image on the triangle's supporting plane
    point_b = low;
    point_a = point_b + out.depth * best_n;
  } else if (kind == 1) {  // the triangle's deepest vertices (their centre), and its image on the face
    const S top = std::max({best_n.dot(v[0]), best_n.dot(v[1]), best_n.dot(v[2])});
    const S tie = S(1e-9) * (b.size + e[0].cwiseAbs().sum() + e[1].cwiseAbs().sum());
    Vec3<S> sum = Vec3<S>::Zero();
    int count = 0;
    for (const auto& x : v)
      if (best_n.dot(x) >= top - tie) {
        sum += x;
        ++count;
      }
    point_a = sum / S(count);
    point_a += (top - best_n.dot(point_a)) * best_n;
    point_b = point_a - out.depth * best_n;
  } else {
    const HullEdge& he = b.edges[static_cast<std::size_t>(index)];
    sat_edge_points(v[sub], v[(sub + 1) % 3], vertex(he.v0), vertex(he.v1), point_a, point_b);
  }
  out.normal = best_n;
  out.point = (point_a + point_b) / S(2);
  return out;
}

}  // namespace detail
}  // namespace impact
