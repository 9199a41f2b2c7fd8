// SPDX-License-Identifier: MIT
/// \file
/// Closest point on a triangle mesh (a MeshBvh under a rigid transform) to a query point, by a
/// nearest-first traversal whose key is the squared distance from the point to each node's BV.
/// Returns the point, the triangle (row of F), the feature of that triangle the point lies on
/// (face interior, one of its edges or one of its vertices), the distance and a normal.
///
/// Numerical contract: approximate to rounding. The closest point on each triangle is the narrow
/// phase's (narrow/closest_point.hpp: Voronoi regions after Ericson, Real-Time Collision
/// Detection, 5.1.5, robust on slivers); the feature reported is the region the query fell in. A
/// triangle's squared distance is never taken below the squared distance to its bounding box, and
/// node keys are computed the same way on boxes holding those boxes, so they are lower bounds of
/// the computed values, not only up to rounding: with a box tree the result's distance is exactly
/// the smallest of a loop over every triangle, and its triangle one of those at that distance
/// (equal distances at shared edges and vertices return one of the triangles that share them).
/// Oriented-box trees key each node on the larger of the distance to the box's axis-aligned hull
/// (computed as for boxes: exact) and the distance to the box itself lowered by a bound of its
/// rounding and of the narrow phase's (its closest point lies on the closed triangle up to a few
/// ulps of the coordinates): the same exact answer as box trees. Sphere trees use the distance to
/// each sphere, a lower bound up to its own rounding.
/// Cost limit: k coincident copies of a triangle near the query cost O(k) unless their box's
/// distance equals the triangle's (box trees): no node test can tell that a node adds nothing.
#pragma once

#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/core/next_float.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/narrow/closest_point.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>

namespace impact {

/// The feature of a triangle (a, b, c) a closest point lies on: the narrow phase's
/// TriangleFeatureId (Face, VertexA..C, EdgeAB, EdgeBC, EdgeCA; edge k joins vertex k and
/// vertex (k + 1) % 3).
using TriangleFeature = TriangleFeatureId;

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

/// Closest point on triangle t to p (the narrow phase's closest_point_on_triangle: Voronoi
/// regions, explicit branches for slivers and degenerate triangles).
template <class S> inline TrianglePoint<S> closest_on_triangle(const Vec3<S>& p, const Triangle<S>& t) {
  const TriangleClosestPoint<S> c = closest_point_on_triangle(p, t);
  return {c.point, c.barycentric, c.feature};
}

/// Squared distance from p to a box (0 inside), computed so that it is monotone in the box: for
/// boxes A inside B, the computed value for B is <= the one for A (each coordinate difference, its
/// square and their sum are rounded monotonically).
template <class S> inline S squared_distance_to_bv(const Vec3<S>& p, const Aabb<S>& b) {
  const Vec3<S> q = p.cwiseMax(b.min).cwiseMin(b.max);
  const Vec3<S> e = p - q;
  return (e[0] * e[0] + e[1] * e[1]) + e[2] * e[2];
}
/// Squared distance from p to a sphere (0 inside), rounded: a lower bound of the distance to what
/// it holds up to rounding.
template <class S> inline S squared_distance_to_bv(const Vec3<S>& p, const Sphere<S>& s) {
  const S d = (p - s.center).norm() - s.radius;
  return d > S(0) ? d * d : S(0);
}

/// Squared distance from p to an oriented box, a lower bound of the computed value of every
/// triangle inside it (triangle_squared_distance): the larger of the monotone distance to its hull
/// (bounding_aabb holds the triangles' boxes) and the distance to the box itself, measured in the
/// box's frame with each axis's excess shrunk by 64 ulps of the sizes involved (|p|, the centre,
/// the extents: the rounding of the local coordinates and of the narrow phase's closest point,
/// which lies on its closed triangle up to a few ulps of the coordinates) and the sum lowered by
/// 16 ulps (the rounding of the squares and of the triangle's own squared distance).
template <class S> inline S squared_distance_to_bv(const Vec3<S>& p, const Obb<S>& b) {
  const S hull = squared_distance_to_bv(p, bounding_aabb(b));
  const Vec3<S> oc = p - b.center;
  const Vec3<S> l = b.axes.transpose() * oc;
  const S scale = oc.cwiseAbs().sum() + p.cwiseAbs().sum() + b.center.cwiseAbs().sum() + b.half.sum();
  const S pad = S(64) * std::numeric_limits<S>::epsilon() * scale;
  S d2 = S(0);
  for (int i = 0; i < 3; ++i) {
    const S e = std::abs(l[i]) - b.half[i] - pad;
    if (e > S(0)) d2 += e * e;
  }
  d2 *= S(1) - S(16) * std::numeric_limits<S>::epsilon();
  return d2 > hull ? d2 : hull;
}

/// Squared distance from p to triangle t's closest point (tp), raised to the squared distance to
/// the triangle's bounding box when rounding put it below that. The box's value is never above
/// the key of any box node holding the triangle (squared_distance_to_bv is monotone), so a node
/// whose key is >= the best squared distance found cannot hold a closer triangle: pruning it is
/// exact, and the tree's answer is the brute-force loop's minimum.
template <class S> inline S triangle_squared_distance(const Vec3<S>& p, const Triangle<S>& t, const TrianglePoint<S>& tp) {
  const S d2 = (p - tp.point).squaredNorm();
  const S box = squared_distance_to_bv(p, Aabb<S>(t.a.cwiseMin(t.b).cwiseMin(t.c), t.a.cwiseMax(t.b).cwiseMax(t.c)));
  return d2 < box ? box : d2;
}

}  // namespace detail

/// Options of closest_point_on_mesh.
template <class S> struct ClosestPointOptions {
  /// Only points closer than this are searched for; farther ones give no result. Bounding the
  /// search makes the query cheap for points far from the surface. >= 0 or +infinity (NaN and
  /// negative values throw InvalidInput).
  S max_distance = std::numeric_limits<S>::infinity();
};

/// Counters of one closest-point query, for benchmarks: node (BV distance) and triangle tests.
struct ClosestPointStats {
  std::size_t node_tests = 0, triangle_tests = 0;
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

namespace detail {

/// closest_point_on_mesh without the argument checks, for callers that validated them once
/// (the particle step, the distance grid's build).
template <class BV>
std::optional<ClosestPointMeshResult<typename BvTraits<BV>::Scalar>> closest_point_on_mesh_unchecked(
    const MeshBvh<BV>& mesh, const Vec3<typename BvTraits<BV>::Scalar>& query, const RigidTransform<typename BvTraits<BV>::Scalar>& pose,
    const ClosestPointOptions<typename BvTraits<BV>::Scalar>& options, ClosestPointStats* stats = nullptr) {
  using S = typename BvTraits<BV>::Scalar;
  const Vec3<S> p = pose.R.transpose() * (query - pose.t);
  S best = options.max_distance < std::numeric_limits<S>::infinity() ? options.max_distance * options.max_distance
                                                                      : std::numeric_limits<S>::infinity();
  std::int32_t best_leaf = -1;
  TrianglePoint<S> best_tp;
  // Once a triangle is found only a strictly closer one replaces it, so nodes at the distance
  // found are pruned too (bound just below it): without that, a mesh whose triangles are all at
  // the same distance (coincident vertices) had every node and triangle visited. Exact, not up to
  // rounding: a node's key never exceeds its triangles' values (triangle_squared_distance; for
  // oriented boxes, see squared_distance_to_bv).
  // Sphere trees: a sphere's distance is a lower bound up to its own rounding only (a triangle's
  // vertex can lie on the sphere), and it is below its triangles' anyway: they prune only nodes
  // strictly farther than best.
  S limit = best;
  auto bound = [&]() { return limit; };
  traverse_nearest(
      mesh.tree(),
      [&](const BV& bv) -> std::optional<S> {
        if (stats) ++stats->node_tests;
        const S d2 = detail::squared_distance_to_bv(p, bv);
        if (d2 > bound()) return std::nullopt;
        return d2;
      },
      bound,
      [&](std::int32_t k) {
        if (mesh.repeats_previous(k)) return true;  // the same distance as the triangle before it: never strictly better
        if (stats) ++stats->triangle_tests;
        const Triangle<S> tri = mesh.triangle(k);
        const TrianglePoint<S> tp = detail::closest_on_triangle(p, tri);
        const S d2 = detail::triangle_squared_distance(p, tri, tp);
        if (d2 < best || (best_leaf < 0 && d2 <= best)) {
          best = d2;
          best_leaf = k;
          best_tp = tp;
          if constexpr (detail::exact_query_keys<BV>)
            limit = next_down(best);
          else
            limit = best;
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

}  // namespace detail

/// Closest point on the mesh (placed by `pose`) to `query`, or nothing when the mesh is farther
/// than options.max_distance. Cost O(log n) typical. Throws InvalidInput for a query not finite
/// or beyond CoordinateRange (core/validate.hpp), a pose that is not rigid (validate_pose) or options.max_distance NaN or negative.
/// `stats`, when given, is incremented by the query's node and triangle tests.
template <class BV>
std::optional<ClosestPointMeshResult<typename BvTraits<BV>::Scalar>> closest_point_on_mesh(
    const MeshBvh<BV>& mesh, const Vec3<typename BvTraits<BV>::Scalar>& query,
    const RigidTransform<typename BvTraits<BV>::Scalar>& pose = {}, const ClosestPointOptions<typename BvTraits<BV>::Scalar>& options = {},
    ClosestPointStats* stats = nullptr) {
  constexpr const char* where = "closest_point_on_mesh";
  validate_coordinates(query, where, "query");
  validate_pose(pose, where);
  validate_nonnegative_or_inf(options.max_distance, where, "options.max_distance");
  return detail::closest_point_on_mesh_unchecked(mesh, query, pose, options, stats);
}

}  // namespace impact
