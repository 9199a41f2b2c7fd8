// SPDX-License-Identifier: MIT
/// \file
/// The point of a simplex (a point, segment, triangle or tetrahedron) closest to the origin, as GJK
/// needs it at each step (convex/gjk_distance.hpp): the signed-volumes method of Montanari, Petrinic
/// & Barbieri ("Improving the GJK algorithm for faster and more reliable distance queries between
/// convex objects", ACM TOG 36(3), 2017). The barycentric weights of the origin's projection onto
/// the simplex's affine hull are ratios of signed volumes: a tetrahedron's determinants with each
/// vertex in turn replaced by the origin; for a triangle with normal n the determinants det(n, x, y)
/// of its sub-triangles (the paper takes their areas in the coordinate plane where the projection
/// is largest, after projecting the origin onto the plane; the component along n needs neither the
/// projection nor the choice of a plane, and the origin's offset along n drops out); for a segment
/// the signed lengths along it. Where they all share the sign of the whole, the projection is the
/// answer; otherwise only the sub-simplices opposite a vertex whose weight has the wrong sign can
/// hold it (the facets the origin lies beyond), searched recursively. The signs decide the Voronoi
/// region before any division, and no sliver needs a separate path.
///
/// Numerical contract: APPROXIMATE. The result is a convex combination of the simplex's points
/// (weights > 0 summing to 1 up to rounding), so |v| is an upper bound of the distance from the
/// origin to the simplex; it is the minimiser up to the rounding of the projection. v is formed
/// from one vertex and the edges from it (s1 + l2 (s2 - s1) + ...), so the weights' rounding, large
/// on slivers, moves v across itself and leaves |v| accurate to a few ulps of the points. A tetrahedron
/// whose volume is within rounding of 0 is treated as flat: its four faces are searched, and the
/// origin is never reported inside it. A triangle whose normal is within rounding of 0 is searched
/// as its three edges, a segment of length 0 as its first point.
/// Thread safety: pure functions.
#pragma once

#include "impact/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// A point of the Minkowski difference A - B with the support points of A and B it came from.
template <class S>
struct SimplexPoint {
  Vec3<S> w, a, b;  // w = a - b
};

/// The closest point found: the indices of the points kept (those with weight > 0), their weights,
/// and the point v = sum of weight * point.
template <class S>
struct SimplexClosest {
  int index[4] = {0, 0, 0, 0};
  S lambda[4] = {S(0), S(0), S(0), S(0)};
  int m = 0;
  Vec3<S> v = Vec3<S>::Zero();
  S vv = std::numeric_limits<S>::infinity();  ///< |v|^2
};

/// The point of segment p[i] p[j] closest to the origin, into r when nearer than r.vv.
template <class S>
inline void sv_segment(const SimplexPoint<S>* p, int i, int j, SimplexClosest<S>& r) {
  const Vec3<S>& s1 = p[i].w;
  const Vec3<S>& s2 = p[j].w;
  const Vec3<S> t = s2 - s1;
  // the weights of the origin's projection onto the line, times |t|^2: signed lengths along t
  const S mu = t.squaredNorm(), c1 = s2.dot(t), c2 = -s1.dot(t);
  if (mu > S(0) && c1 > S(0) && c2 > S(0)) {
    // v in the affine form s1 + l2 t, the weights summing to 1: see sv_triangle
    const S l2 = c2 / mu, l1 = S(1) - l2;
    const Vec3<S> v = s1 + l2 * t;
    const S vv = v.squaredNorm();
    if (vv < r.vv) {
      r.m = 2;
      r.index[0] = i;
      r.index[1] = j;
      r.lambda[0] = l1;
      r.lambda[1] = l2;
      r.v = v;
      r.vv = vv;
    }
    return;
  }
  // a weight is not positive: the end the projection lies beyond
  const int k = c2 > S(0) ? j : i;
  const S vv = p[k].w.squaredNorm();
  if (vv < r.vv) {
    r.m = 1;
    r.index[0] = k;
    r.lambda[0] = S(1);
    r.v = p[k].w;
    r.vv = vv;
  }
}

/// The point of triangle p[i] p[j] p[k] closest to the origin, into r when nearer than r.vv.
template <class S>
inline void sv_triangle(const SimplexPoint<S>* p, int i, int j, int k, SimplexClosest<S>& r) {
  const Vec3<S>& s1 = p[i].w;
  const Vec3<S>& s2 = p[j].w;
  const Vec3<S>& s3 = p[k].w;
  const Vec3<S> e1 = s2 - s1, e2 = s3 - s1, n = e1.cross(e2);
  const S mu = n.squaredNorm();
  // The weights of the origin's projection onto the plane, times |n|^2: the signed volumes
  // det(n, x, y) of the sub-triangles with each vertex in turn replaced by the origin (the
  // component along n of each sub-triangle's area vector; the origin's offset along n drops out).
  // A normal within rounding of 0 (collinear or coincident points): the edges alone.
  const S c1 = n.dot(s2.cross(Vec3<S>(s3 - s2))), c2 = n.dot(e2.cross(s1)), c3 = n.dot(s1.cross(e1));
  if (mu > S(1e-20) * e1.squaredNorm() * e2.squaredNorm() && mu > S(0)) {
    if (c1 > S(0) && c2 > S(0) && c3 > S(0)) {
      // v in the affine form s1 + l2 e1 + l3 e2, not l1 s1 + l2 s2 + l3 s3: each weight carries an
      // error of about eps |s1| |e| / |n| (its determinant cancels down from products of a point
      // and an edge to |n|^2 times the weight), hundreds of ulps on a sliver, and weights that do
      // not sum to 1 move v along itself, changing |v| by that error times |v|: on a disc tilted
      // by 6e-10 over a cap this made a step look farther than the one before and GJK stopped with
      // its gap at 4e-10 of the size. In the affine form the weights' errors move v only along the
      // edges, across itself, and |v| keeps its digits (Ericson's region code computes v so too).
      const S l2 = c2 / mu, l3 = c3 / mu, l1 = S(1) - l2 - l3;
      const Vec3<S> v = s1 + l2 * e1 + l3 * e2;
      const S vv = v.squaredNorm();
      if (vv < r.vv) {
        r.m = 3;
        r.index[0] = i;
        r.index[1] = j;
        r.index[2] = k;
        r.lambda[0] = l1;
        r.lambda[1] = l2;
        r.lambda[2] = l3;
        r.v = v;
        r.vv = vv;
      }
      return;
    }
    // the origin projects beyond the edges opposite the vertices whose weight is not positive
    if (!(c1 > S(0))) sv_segment(p, j, k, r);
    if (!(c2 > S(0))) sv_segment(p, k, i, r);
    if (!(c3 > S(0))) sv_segment(p, i, j, r);
    return;
  }
  sv_segment(p, j, k, r);
  sv_segment(p, k, i, r);
  sv_segment(p, i, j, r);
}

/// The point of the simplex p[0..n).w (n = 1 .. 4) closest to the origin; false when n = 4 and the
/// origin is inside the tetrahedron (or on its boundary, no weight negative), `out` then unset.
template <class S>
inline bool sv_closest(const SimplexPoint<S>* p, int n, SimplexClosest<S>& out) {
  out = SimplexClosest<S>();
  if (n == 1) {
    out.m = 1;
    out.lambda[0] = S(1);
    out.v = p[0].w;
    out.vv = p[0].w.squaredNorm();
    return true;
  }
  if (n == 2) {
    sv_segment(p, 0, 1, out);
    return true;
  }
  if (n == 3) {
    sv_triangle(p, 0, 1, 2, out);
    return true;
  }
  // tetrahedron: the weights are the volumes with each vertex in turn replaced by the origin,
  // over the whole volume
  const Vec3<S>& s1 = p[0].w;
  const Vec3<S> e2 = p[1].w - s1, e3 = p[2].w - s1, e4 = p[3].w - s1;
  const Vec3<S> n34 = e3.cross(e4);
  const S volume = e2.dot(n34);
  // (each from edge vectors and one vertex, not from three vertices: a triple product of points
  // far from the origin would lose the small volume to rounding)
  const Vec3<S>& s2 = p[1].w;
  const S c[4] = {s2.dot(Vec3<S>(p[2].w - s2).cross(Vec3<S>(p[3].w - s2))), -s1.dot(n34), -s1.dot(e4.cross(e2)), -s1.dot(e2.cross(e3))};
  // flat (volume within rounding of 0, as when a face of one shape is parallel to a face of the
  // other): it has no inside, the signs of its weights are noise, so every face is searched
  const S edge = std::max({e2.squaredNorm(), e3.squaredNorm(), e4.squaredNorm()});
  const bool flat = !(std::abs(volume) > S(64) * std::numeric_limits<S>::epsilon() * edge * std::sqrt(edge));
  const S sign = volume >= S(0) ? S(1) : S(-1);
  bool face[4];
  bool inside = !flat;
  for (int q = 0; q < 4; ++q) {
    face[q] = flat || !(sign * c[q] > S(0));
    inside = inside && !face[q];
  }
  if (inside) return false;
  if (face[0]) sv_triangle(p, 1, 2, 3, out);
  if (face[1]) sv_triangle(p, 0, 2, 3, out);
  if (face[2]) sv_triangle(p, 0, 1, 3, out);
  if (face[3]) sv_triangle(p, 0, 1, 2, out);
  return true;
}

}  // namespace impact::detail
