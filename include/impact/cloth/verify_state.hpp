// SPDX-License-Identifier: MIT
/// \file
/// verify_cloth_state: an exact check of one state of a cloth and its obstacles, independent of
/// the CCD used by the collision step: does any triangle intersect another (cloth against itself,
/// against other cloth components, against obstacles), and how close do non-adjacent primitives
/// come?
///
/// Intersections are EXACT (the library's exact orient3d/orient2d predicates, through
/// triangles_intersect). Adjacent cloth triangles legitimately share a vertex or an edge; they
/// count as intersecting only when they share more:
///  - sharing an edge (v, w): the two triangles are coplanar and fold onto the same side of vw;
///  - sharing one vertex v: the edge opposite v of either triangle meets the other triangle, or
///    an edge (v, a) of one lies in the plane of the other and points into its corner at v.
///    (If two triangles through v share a point p != v, the segment from v through p leaves one of
///    them through one of these edges, so the list is complete.)
/// Triangles with collinear vertices adjacent to others are checked only as non-adjacent pairs
/// are. Obstacles are never checked against each other.
/// The minimum distance between non-adjacent primitives (vertex-face, edge-edge, cloth against
/// cloth and against obstacles) is APPROXIMATE (closest points in double, within rounding), and
/// looked for only up to `distance_cutoff`: beyond it the report says +infinity.
#pragma once

#include "impact/ccd/mesh_ccd.hpp"
#include "impact/cloth/detail/start_intersections.hpp"
#include "impact/cloth/step_options.hpp"
#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/predicates.hpp"
#include "impact/narrow/triangle_triangle.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace impact {

/// Which end of the step the obstacles are taken at.
enum class ObstacleTime { Start, End };

struct ClothVerifyOptions {
  /// Distances are looked for up to this (>= 0); 0 skips the distance part.
  double distance_cutoff = 0;
  /// At most this many intersecting triangle pairs are listed (all are counted).
  std::size_t max_listed = 16;
};

/// Result of verify_cloth_state. Triangle ids: cloth triangles 0..m-1, then each obstacle's.
struct ClothStateReport {
  std::size_t intersections = 0;                          ///< intersecting triangle pairs (exact)
  std::vector<std::pair<std::int32_t, std::int32_t>> intersecting;  ///< the first max_listed of them
  double min_distance = std::numeric_limits<double>::infinity();    ///< non-adjacent primitives, up to the cutoff
  ClothPair closest;                                      ///< the pair at min_distance (global vertex ids)
  std::size_t triangle_pairs = 0;                         ///< pairs examined
};


/// Checks the cloth at positions `x` (triangles F) against itself and the obstacles at `when`.
/// Throws InvalidInput on bad arrays (as cloth_collision_step would). O((n + pairs) log n).
template <class S>
ClothStateReport verify_cloth_state(const Faces& F, const Vertices<S>& x, const ClothObstacles<S>& obstacles, ObstacleTime when = ObstacleTime::End,
                                    const ClothVerifyOptions& opt = {}) {
  validate_mesh(x, F, "verify_cloth_state (cloth)");
  if (!(opt.distance_cutoff >= 0) || !std::isfinite(opt.distance_cutoff)) throw InvalidInput("verify_cloth_state: distance_cutoff must be finite and >= 0");
  // Combined static arrays: the cloth, then every obstacle at the chosen time.
  Eigen::Index nv = x.rows(), nf = F.rows();
  for (const auto& r : obstacles.rigid) {
    if (!r.mesh) throw InvalidInput("verify_cloth_state: rigid obstacle without a mesh");
    validate_mesh(r.mesh->V, r.mesh->F, "verify_cloth_state (rigid obstacle)");
    nv += r.mesh->V.rows(), nf += r.mesh->F.rows();
  }
  for (const auto& k : obstacles.kinematic) {
    if (!k.x0 || !k.x1 || !k.faces) throw InvalidInput("verify_cloth_state: kinematic obstacle with a missing array");
    validate_mesh(when == ObstacleTime::End ? *k.x1 : *k.x0, *k.faces, "verify_cloth_state (kinematic obstacle)");
    nv += k.x0->rows(), nf += k.faces->rows();
  }
  Vertices<S> X(nv, 3);
  Faces FF(nf, 3);
  std::vector<std::uint8_t> obst(static_cast<std::size_t>(nf), 1);
  X.topRows(x.rows()) = x;
  FF.topRows(F.rows()) = F;
  for (Eigen::Index i = 0; i < F.rows(); ++i) obst[static_cast<std::size_t>(i)] = 0;
  Eigen::Index vo = x.rows(), fo = F.rows();
  for (const auto& r : obstacles.rigid) {
    const auto& pose = when == ObstacleTime::End ? r.pose1 : r.pose0;
    for (Eigen::Index i = 0; i < r.mesh->V.rows(); ++i) X.row(vo + i) = pose.apply(Vec3<S>(r.mesh->V.row(i).transpose())).transpose();
    FF.middleRows(fo, r.mesh->F.rows()) = r.mesh->F.array() + static_cast<int>(vo);
    vo += r.mesh->V.rows(), fo += r.mesh->F.rows();
  }
  for (const auto& k : obstacles.kinematic) {
    X.middleRows(vo, k.x0->rows()) = when == ObstacleTime::End ? *k.x1 : *k.x0;
    FF.middleRows(fo, k.faces->rows()) = k.faces->array() + static_cast<int>(vo);
    vo += k.x0->rows(), fo += k.faces->rows();
  }
  if (!all_finite(X)) throw InvalidInput("verify_cloth_state: a NaN or infinite coordinate");

  const MeshMotion<S> m{&X, &X, &FF};
  const auto tree = SweptMeshBvh<S>::build(m, opt.distance_cutoff);
  ClothStateReport rep;
  auto V = [&](std::int32_t v) { return Vec3<S>(X.row(v).transpose()); };
  auto Vd = [&](std::int32_t v) { return Vec3<double>(X.row(v).transpose().template cast<double>()); };
  auto consider = [&](double d, bool ee, std::int32_t a, std::int32_t b, std::int32_t c, std::int32_t e) {
    if (d < rep.min_distance && d <= opt.distance_cutoff) {
      rep.min_distance = d;
      rep.closest.edge_edge = ee;
      rep.closest.v[0] = a, rep.closest.v[1] = b, rep.closest.v[2] = c, rep.closest.v[3] = e;
    }
  };
  traverse_self(
      tree.tree, [](const Aabb<S>& p, const Aabb<S>& q) { return overlap(p, q); },
      [&](std::int32_t ta, std::int32_t tb) {
        if (obst[static_cast<std::size_t>(ta)] && obst[static_cast<std::size_t>(tb)]) return true;
        ++rep.triangle_pairs;
        const int ia[3] = {FF(ta, 0), FF(ta, 1), FF(ta, 2)}, ib[3] = {FF(tb, 0), FF(tb, 1), FF(tb, 2)};
        const Vec3<S> A[3] = {V(ia[0]), V(ia[1]), V(ia[2])}, B[3] = {V(ib[0]), V(ib[1]), V(ib[2])};
        bool shared = false;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) shared = shared || ia[i] == ib[j];
        const bool hit = shared ? detail::cloth::adjacent_pair_intersects(A, B, ia, ib)
                                : triangles_intersect(Triangle<S>(A[0], A[1], A[2]), Triangle<S>(B[0], B[1], B[2]));
        if (hit) {
          if (rep.intersecting.size() < opt.max_listed) rep.intersecting.push_back({ta, tb});
          ++rep.intersections;
        }
        if (opt.distance_cutoff > 0) {
          auto in = [](const int* t, int v) { return t[0] == v || t[1] == v || t[2] == v; };
          for (int k = 0; k < 3; ++k) {
            if (!in(ib, ia[k])) {
              const auto r = closest_point_on_triangle(Vd(ia[k]), Triangle<double>(Vd(ib[0]), Vd(ib[1]), Vd(ib[2])));
              consider(std::sqrt(r.squared_distance), false, ia[k], ib[0], ib[1], ib[2]);
            }
            if (!in(ia, ib[k])) {
              const auto r = closest_point_on_triangle(Vd(ib[k]), Triangle<double>(Vd(ia[0]), Vd(ia[1]), Vd(ia[2])));
              consider(std::sqrt(r.squared_distance), false, ib[k], ia[0], ia[1], ia[2]);
            }
          }
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
              const int a0 = ia[i], a1 = ia[(i + 1) % 3], b0 = ib[j], b1 = ib[(j + 1) % 3];
              if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;
              const auto r = closest_points_segment_segment(Segment<double>(Vd(a0), Vd(a1)), Segment<double>(Vd(b0), Vd(b1)));
              consider(std::sqrt(r.squared_distance), true, a0, a1, b0, b1);
            }
        }
        return true;
      });
  return rep;
}

}  // namespace impact
