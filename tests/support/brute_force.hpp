// SPDX-License-Identifier: MIT
// Brute-force oracles: every triangle pair, no hierarchy. They use the same exact triangle test as
// the library, so a difference isolates the hierarchy and its traversal.
#pragma once

#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle_mesh.hpp"
#include "impact/narrow/triangle_triangle.hpp"

#include <algorithm>
#include <utility>
#include <vector>

namespace impact::test {

/// All (row a, row b) pairs of intersecting triangles, b moved into a's frame as the library does.
template <class S>
std::vector<std::pair<int, int>> brute_force_pairs(const TriangleMesh<S>& a, const RigidTransform<S>& pa, const TriangleMesh<S>& b,
                                                   const RigidTransform<S>& pb) {
  const RigidTransform<S> x = relative_transform(pa, pb);
  std::vector<Triangle<S>> tb(static_cast<std::size_t>(b.num_triangles()));
  for (int j = 0; j < b.num_triangles(); ++j) {
    const Triangle<S> t = b.triangle(j);
    tb[static_cast<std::size_t>(j)] = Triangle<S>(x.apply(t.a), x.apply(t.b), x.apply(t.c));
  }
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < a.num_triangles(); ++i) {
    const Triangle<S> ta = a.triangle(i);
    for (int j = 0; j < b.num_triangles(); ++j)
      if (triangles_intersect(ta, tb[static_cast<std::size_t>(j)])) out.emplace_back(i, j);
  }
  return out;
}

/// All (i, j), i < j, pairs of intersecting triangles of one mesh that share no vertex index.
template <class S> std::vector<std::pair<int, int>> brute_force_self_pairs(const TriangleMesh<S>& m) {
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < m.num_triangles(); ++i)
    for (int j = i + 1; j < m.num_triangles(); ++j) {
      bool adjacent = false;
      for (int u = 0; u < 3; ++u)
        for (int v = 0; v < 3; ++v) adjacent = adjacent || m.F(i, u) == m.F(j, v);
      if (!adjacent && triangles_intersect(m.triangle(i), m.triangle(j))) out.emplace_back(i, j);
    }
  return out;
}

template <class P> std::vector<P> sorted(std::vector<P> v) {
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace impact::test
