// SPDX-License-Identifier: MIT
// Loop oracles of the nearest-first queries: every triangle of a mesh, no hierarchy, each by the
// library's own per-triangle rule (the ray casts' watertight test, the closest points' squared
// distance). A tree's first hit or closest point must give their answer exactly (box trees) or to
// its stated rounding: they check the walks and their pruning, not the per-triangle rules, which
// the narrow-phase tests check against exact arithmetic.
#pragma once

#include "impact/geometry/triangle_mesh.hpp"
#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/ray_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace impact::test {

/// The smallest t of a hit over all triangles and the first row of F hit there; nothing on a miss.
template <class S> std::optional<std::pair<S, int>> loop_first_hit(const TriangleMesh<S>& m, const Ray<S>& ray) {
  PreparedRay<S> pr(ray);
  std::optional<std::pair<S, int>> best;
  for (int t = 0; t < m.num_triangles(); ++t) {
    pr.ray.t_max = best ? best->first : ray.t_max;
    const auto h = detail::ray_mesh_triangle_hit(pr, m.triangle(t));
    if (h && (!best || h->t < best->first)) best = std::make_pair(h->t, t);
  }
  return best;
}

/// The smallest distance from p over all triangles (the narrow phase's closest point, its squared
/// distance raised to the triangle box's: query/closest_point_mesh.hpp).
template <class S> S loop_distance(const TriangleMesh<S>& m, const Vec3<S>& p) {
  S best = std::numeric_limits<S>::infinity();
  for (int t = 0; t < m.num_triangles(); ++t) {
    const Triangle<S> tri = m.triangle(t);
    best = std::min(best, detail::triangle_squared_distance(p, tri, detail::closest_on_triangle(p, tri)));
  }
  return std::sqrt(best);
}

}  // namespace impact::test
