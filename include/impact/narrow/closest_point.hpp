// SPDX-License-Identifier: MIT
/// \file
/// Closest points: point–segment, point–triangle (with barycentrics and the feature reached),
/// segment–segment.
///
/// Numerical contract: APPROXIMATE (plain floating point in S), but robust: every result is a point
/// of the closed primitive (parameters are clamped to their ranges), so a reported distance is never
/// below the true one by more than rounding, and degenerate inputs (zero-length segments, parallel
/// and collinear segments, triangles with collinear or coincident vertices) take explicit branches
/// without division by zero. Region classification of the triangle follows the Voronoi-region
/// method of Ericson, Real-Time Collision Detection, section 5.1.5.
#pragma once

#include "impact/geometry/ray.hpp"
#include "impact/geometry/triangle.hpp"

#include <algorithm>
#include <cstdint>

namespace impact {

/// The feature of a triangle on which a closest point lies.
/// (Same enumerators, in the same order, as query/closest_point_mesh.hpp's TriangleFeatureId, so that the two
/// can be unified.)
enum class TriangleFeatureId : std::uint8_t { Face, VertexA, VertexB, VertexC, EdgeAB, EdgeBC, EdgeCA };

/// Closest point of a triangle to a query point.
template <class S> struct TriangleClosestPoint {
  Vec3<S> point;        ///< the closest point of the closed triangle
  Vec3<S> barycentric;  ///< weights of (a, b, c): point = x a + y b + z c, each in [0, 1], sum 1
  TriangleFeatureId feature = TriangleFeatureId::Face;
  S squared_distance = S(0);
};

/// Closest point of a segment to a query point.
template <class S> struct SegmentClosestPoint {
  Vec3<S> point;
  S t = S(0);  ///< parameter in [0, 1]: point = p + t (q - p)
  S squared_distance = S(0);
};

/// Closest pair of points of two segments.
template <class S> struct SegmentSegmentClosestPoints {
  Vec3<S> point_a, point_b;
  S s = S(0), t = S(0);  ///< parameters in [0, 1] on a and b
  S squared_distance = S(0);
};

/// Closest point of the closed segment to x. A zero-length segment gives its point (t = 0).
template <class S> inline SegmentClosestPoint<S> closest_point_on_segment(const Vec3<S>& x, const Segment<S>& seg) {
  const Vec3<S> d = seg.q - seg.p;
  const S dd = d.squaredNorm();
  S t = S(0);
  if (dd > S(0)) t = std::clamp((x - seg.p).dot(d) / dd, S(0), S(1));
  SegmentClosestPoint<S> r;
  r.t = t;
  r.point = seg.p + t * d;
  r.squared_distance = (x - r.point).squaredNorm();
  return r;
}

namespace detail {

template <class S> inline TriangleClosestPoint<S> make_tcp(const Vec3<S>& x, const Vec3<S>& point, S wa, S wb, S wc, TriangleFeatureId f) {
  TriangleClosestPoint<S> r;
  r.point = point;
  r.barycentric = Vec3<S>(wa, wb, wc);
  r.feature = f;
  r.squared_distance = (x - point).squaredNorm();
  return r;
}

/// Degenerate (or numerically flat) triangle: the best of its three edges.
template <class S> inline TriangleClosestPoint<S> closest_point_on_triangle_edges(const Vec3<S>& x, const Triangle<S>& tri) {
  TriangleClosestPoint<S> best;
  best.squared_distance = std::numeric_limits<S>::infinity();
  const TriangleFeatureId edge[3] = {TriangleFeatureId::EdgeAB, TriangleFeatureId::EdgeBC, TriangleFeatureId::EdgeCA};
  const TriangleFeatureId vert[3] = {TriangleFeatureId::VertexA, TriangleFeatureId::VertexB, TriangleFeatureId::VertexC};
  for (int e = 0; e < 3; ++e) {
    const int i = e, j = (e + 1) % 3;
    const auto c = closest_point_on_segment(x, Segment<S>(tri[i], tri[j]));
    if (c.squared_distance < best.squared_distance) {
      Vec3<S> w = Vec3<S>::Zero();
      w[i] = S(1) - c.t;
      w[j] = c.t;
      const TriangleFeatureId f = c.t <= S(0) ? vert[i] : (c.t >= S(1) ? vert[j] : edge[e]);
      best = make_tcp(x, c.point, w[0], w[1], w[2], f);
    }
  }
  return best;
}

/// Slivers and degenerate triangles: the face when the projection is inside, else the best edge.
template <class S> inline TriangleClosestPoint<S> closest_point_on_sliver(const Vec3<S>& x, const Triangle<S>& tri) {
  const Vec3<S> ab = tri.b - tri.a, ac = tri.c - tri.a, n = ab.cross(ac);
  const S nn = n.squaredNorm();
  if (nn > S(0)) {
    const Vec3<S> q = x - (n.dot(x - tri.a) / nn) * n, aq = q - tri.a;
    const S wb = n.dot(aq.cross(ac)) / nn, wc = n.dot(ab.cross(aq)) / nn, wa = S(1) - wb - wc;
    if (wa >= S(0) && wb >= S(0) && wc >= S(0)) return make_tcp(x, Vec3<S>(wa * tri.a + wb * tri.b + wc * tri.c), wa, wb, wc, TriangleFeatureId::Face);
  }
  return closest_point_on_triangle_edges(x, tri);
}

}  // namespace detail

/// Closest point of the closed triangle to x, its barycentric weights and the feature (vertex,
/// edge, or face interior) it lies on. Degenerate triangles (collinear or coincident vertices) are
/// handled as the segment or point they are; the feature then names the edge or vertex used.
template <class S> inline TriangleClosestPoint<S> closest_point_on_triangle(const Vec3<S>& x, const Triangle<S>& tri) {
  using F = TriangleFeatureId;
  const Vec3<S>&a = tri.a, &b = tri.b, &c = tri.c;
  const Vec3<S> ab = b - a, ac = c - a;
  // slivers (sine of the angle at a below 1e-2) and degenerate triangles: the robust path, as the
  // region tests below lose accuracy there
  if (ab.cross(ac).squaredNorm() <= S(1e-4) * ab.squaredNorm() * ac.squaredNorm()) return detail::closest_point_on_sliver(x, tri);
  const Vec3<S> ap = x - a;
  const S d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= S(0) && d2 <= S(0)) return detail::make_tcp(x, a, S(1), S(0), S(0), F::VertexA);
  const Vec3<S> bp = x - b;
  const S d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= S(0) && d4 <= d3) return detail::make_tcp(x, b, S(0), S(1), S(0), F::VertexB);
  const S vc = d1 * d4 - d3 * d2;
  if (vc <= S(0) && d1 >= S(0) && d3 <= S(0)) {
    const S den = d1 - d3;
    const S v = den > S(0) ? std::clamp(d1 / den, S(0), S(1)) : S(0);
    return detail::make_tcp(x, Vec3<S>(a + v * ab), S(1) - v, v, S(0), F::EdgeAB);
  }
  const Vec3<S> cp = x - c;
  const S d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= S(0) && d5 <= d6) return detail::make_tcp(x, c, S(0), S(0), S(1), F::VertexC);
  const S vb = d5 * d2 - d1 * d6;
  if (vb <= S(0) && d2 >= S(0) && d6 <= S(0)) {
    const S den = d2 - d6;
    const S w = den > S(0) ? std::clamp(d2 / den, S(0), S(1)) : S(0);
    return detail::make_tcp(x, Vec3<S>(a + w * ac), S(1) - w, S(0), w, F::EdgeCA);
  }
  const S va = d3 * d6 - d5 * d4;
  if (va <= S(0) && d4 - d3 >= S(0) && d5 - d6 >= S(0)) {
    const S den = (d4 - d3) + (d5 - d6);
    const S w = den > S(0) ? std::clamp((d4 - d3) / den, S(0), S(1)) : S(0);
    return detail::make_tcp(x, Vec3<S>(b + w * (c - b)), S(0), S(1) - w, w, F::EdgeBC);
  }
  const S den = va + vb + vc;
  if (!(den > S(0))) return detail::closest_point_on_sliver(x, tri);
  const S v = vb / den, w = vc / den;
  if (!(v >= S(0) && w >= S(0) && v + w <= S(1))) return detail::closest_point_on_sliver(x, tri);
  return detail::make_tcp(x, Vec3<S>(a + v * ab + w * ac), S(1) - v - w, v, w, F::Face);
}

/// Closest pair of points of the closed segments a and b. Zero-length segments are points; for
/// parallel (and collinear) segments one of the equally close pairs is returned.
template <class S> inline SegmentSegmentClosestPoints<S> closest_points_segment_segment(const Segment<S>& a, const Segment<S>& b) {
  const Vec3<S> d1 = a.q - a.p, d2 = b.q - b.p, r = a.p - b.p;
  const S aa = d1.squaredNorm(), ee = d2.squaredNorm(), f = d2.dot(r);
  S s = S(0), t = S(0);
  if (aa <= S(0) && ee <= S(0)) {
    // two points
  } else if (aa <= S(0)) {
    t = std::clamp(f / ee, S(0), S(1));
  } else {
    const S c = d1.dot(r);
    if (ee <= S(0)) {
      s = std::clamp(-c / aa, S(0), S(1));
    } else {
      const S bb = d1.dot(d2);
      const S den = aa * ee - bb * bb;
      // parallel within rounding: any s works for the line pair; start from s = 0
      s = den > S(16) * std::numeric_limits<S>::epsilon() * aa * ee ? std::clamp((bb * f - c * ee) / den, S(0), S(1)) : S(0);
      t = (bb * s + f) / ee;
      if (t < S(0)) {
        t = S(0);
        s = std::clamp(-c / aa, S(0), S(1));
      } else if (t > S(1)) {
        t = S(1);
        s = std::clamp((bb - c) / aa, S(0), S(1));
      }
    }
  }
  SegmentSegmentClosestPoints<S> out;
  out.s = s;
  out.t = t;
  out.point_a = a.p + s * d1;
  out.point_b = b.p + t * d2;
  out.squared_distance = (out.point_a - out.point_b).squaredNorm();
  return out;
}

}  // namespace impact
