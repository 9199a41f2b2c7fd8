// SPDX-License-Identifier: MIT
/// \file
/// Closest point on a triangle mesh (a MeshBvh under a rigid transform) to a query point, by a
/// nearest-first traversal whose key is the squared distance from the point to each node's BV.
/// Returns the point, the triangle (row of F), the feature of that triangle the point lies on
/// (face interior, one of its edges or one of its vertices), the distance and a normal.
///
/// Numerical contract: approximate to rounding. The closest point on each triangle follows the
/// Voronoi-region method (Ericson, Real-Time Collision Detection, 5.1.5); the feature reported is
/// the region the query fell in. Node keys are exact lower bounds up to rounding, so the result
/// is the nearest triangle up to ties (equal distances at shared edges and vertices return one of
/// the triangles that share them).
#pragma once

#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/geometry/transform.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

namespace impact {

/// The feature of a triangle (a, b, c) a closest point lies on. Edge k joins vertex k and vertex
/// (k + 1) % 3 (EdgeAB, EdgeBC, EdgeCA).
enum class TriangleFeature : std::uint8_t { Face, VertexA, VertexB, VertexC, EdgeAB, EdgeBC, EdgeCA };

/// True for the three vertex features.
inline bool is_vertex(TriangleFeature f) { return f == TriangleFeature::VertexA || f == TriangleFeature::VertexB || f == TriangleFeature::VertexC; }
/// True for the three edge features.
inline bool is_edge(TriangleFeature f) { return f == TriangleFeature::EdgeAB || f == TriangleFeature::EdgeBC || f == TriangleFeature::EdgeCA; }
/// Local index (0..2) of a vertex feature, or of an edge feature's first vertex.
inline int feature_index(TriangleFeature f) {
  switch (f) {
    case TriangleFeature::VertexA: case TriangleFeature::EdgeAB: return 0;
    case TriangleFeature::VertexB: case TriangleFeature::EdgeBC: return 1;
    case TriangleFeature::VertexC: case TriangleFeature::EdgeCA: return 2;
    default: return -1;
  }
}

/// Closest point on one triangle: the point, its barycentric weights and the feature.
template <class S> struct TrianglePoint {
  Vec3<S> point = Vec3<S>::Zero();
  Vec3<S> barycentric = Vec3<S>::Zero();
  TriangleFeature feature = TriangleFeature::Face;
};

namespace detail {

/// Closest point on triangle t to p by Voronoi regions (Ericson 5.1.5). Degenerate triangles end
/// in an edge or vertex region.
template <class S> inline TrianglePoint<S> closest_on_triangle(const Vec3<S>& p, const Triangle<S>& t) {
  TrianglePoint<S> r;
  const Vec3<S> ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const S d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= S(0) && d2 <= S(0)) return {t.a, {S(1), S(0), S(0)}, TriangleFeature::VertexA};
  const Vec3<S> bp = p - t.b;
  const S d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= S(0) && d4 <= d3) return {t.b, {S(0), S(1), S(0)}, TriangleFeature::VertexB};
  const S vc = d1 * d4 - d3 * d2;
  if (vc <= S(0) && d1 >= S(0) && d3 <= S(0)) {
    const S v = d1 / (d1 - d3);
    return {t.a + v * ab, {S(1) - v, v, S(0)}, TriangleFeature::EdgeAB};
  }
  const Vec3<S> cp = p - t.c;
  const S d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= S(0) && d5 <= d6) return {t.c, {S(0), S(0), S(1)}, TriangleFeature::VertexC};
  const S vb = d5 * d2 - d1 * d6;
  if (vb <= S(0) && d2 >= S(0) && d6 <= S(0)) {
    const S w = d2 / (d2 - d6);
    return {t.a + w * ac, {S(1) - w, S(0), w}, TriangleFeature::EdgeCA};
  }
  const S va = d3 * d6 - d5 * d4;
  if (va <= S(0) && (d4 - d3) >= S(0) && (d5 - d6) >= S(0)) {
    const S w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {t.b + w * (t.c - t.b), {S(0), S(1) - w, w}, TriangleFeature::EdgeBC};
  }
  const S denom = va + vb + vc;
  if (!(denom > S(0)) && !(denom < S(0))) return {t.a, {S(1), S(0), S(0)}, TriangleFeature::VertexA};
  const S v = vb / denom, w = vc / denom;
  r.point = t.a + ab * v + ac * w;
  r.barycentric = {S(1) - v - w, v, w};
  r.feature = TriangleFeature::Face;
  return r;
}

/// Squared distance from p to a BV (0 inside); a lower bound of the distance to what it holds.
template <class S> inline S squared_distance_to_bv(const Vec3<S>& p, const Aabb<S>& b) {
  const Vec3<S> q = p.cwiseMax(b.min).cwiseMin(b.max);
  return (p - q).squaredNorm();
}
template <class S> inline S squared_distance_to_bv(const Vec3<S>& p, const Sphere<S>& s) {
  const S d = (p - s.center).norm() - s.radius;
  return d > S(0) ? d * d : S(0);
}

}  // namespace detail

/// Options of closest_point_on_mesh.
template <class S> struct ClosestPointOptions {
  /// Only points closer than this are searched for; farther ones give no result. Bounding the
  /// search makes the query cheap for points far from the surface.
  S max_distance = std::numeric_limits<S>::infinity();
};

/// Closest point on a mesh, in the world frame.
template <class S> struct ClosestPointMeshResult {
  Vec3<S> point = Vec3<S>::Zero();        ///< closest point on the surface
  std::int32_t triangle = -1;             ///< row of the mesh's F
  std::int32_t leaf_index = -1;           ///< leaf position (MeshBvh::triangle(leaf_index))
  TriangleFeature feature = TriangleFeature::Face;
  Vec3<S> barycentric = Vec3<S>::Zero();  ///< weights of the triangle's a, b, c
  S distance = S(0);                      ///< |query - point|
  /// Unit normal: the triangle's wound normal when the point is on the face interior or the
  /// query lies on the surface; otherwise (edges and vertices) the direction from the surface
  /// point to the query point.
  Vec3<S> normal = Vec3<S>::Zero();
};

/// Closest point on the mesh (placed by `pose`) to `query`, or nothing when the mesh is farther
/// than options.max_distance. Cost O(log n) typical.
template <class BV>
std::optional<ClosestPointMeshResult<typename BvTraits<BV>::Scalar>> closest_point_on_mesh(
    const MeshBvh<BV>& mesh, const Vec3<typename BvTraits<BV>::Scalar>& query,
    const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {}, const ClosestPointOptions<typename BvTraits<BV>::Scalar>& options = {}) {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> p = pose.R.transpose() * (query - pose.t);
  S best = options.max_distance < std::numeric_limits<S>::infinity() ? options.max_distance * options.max_distance
                                                                      : std::numeric_limits<S>::infinity();
  std::int32_t best_leaf = -1;
  TrianglePoint<S> best_tp;
  traverse_nearest(
      mesh.tree(),
      [&](const BV& bv) -> std::optional<S> {
        const S d2 = detail::squared_distance_to_bv(p, bv);
        if (d2 > best) return std::nullopt;
        return d2;
      },
      [&]() { return best; },
      [&](std::int32_t k) {
        const TrianglePoint<S> tp = detail::closest_on_triangle(p, mesh.triangle(k));
        const S d2 = (p - tp.point).squaredNorm();
        if (d2 < best || (best_leaf < 0 && d2 <= best)) {
          best = d2;
          best_leaf = k;
          best_tp = tp;
        }
        return true;
      });
  if (best_leaf < 0) return std::nullopt;
  ClosestPointMeshResult<S> r;
  r.leaf_index = best_leaf;
  r.triangle = mesh.triangle_id(best_leaf);
  r.feature = best_tp.feature;
  r.barycentric = best_tp.barycentric;
  r.distance = std::sqrt(best);
  r.point = pose.apply(best_tp.point);
  const Vec3<S> diff = p - best_tp.point;
  const S dn = diff.norm();
  Vec3<S> n = mesh.triangle(best_leaf).normal();
  if (best_tp.feature != TriangleFeature::Face && dn > S(0)) n = diff / dn;
  r.normal = pose.R * n;
  return r;
}

}  // namespace impact
