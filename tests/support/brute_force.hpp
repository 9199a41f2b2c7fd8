// SPDX-License-Identifier: MIT
// Brute-force oracles: every triangle pair, no hierarchy, and no code of the library's narrow phase:
// each pair is decided by the tests' own exact arithmetic (exact_triangle.hpp), after an exact
// closed-box prefilter (triangles whose coordinate boxes are apart cannot touch), so the library's
// touching semantics are checked at mesh level too, not only its traversal.
#pragma once

#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle_mesh.hpp"
#include "support/exact_triangle.hpp"

#include <algorithm>
#include <utility>
#include <vector>

namespace impact::test {

/// B's triangles moved into A's frame exactly as the library's mesh queries do (one rounding).
template <class S> std::vector<Triangle<S>> moved_triangles(const TriangleMesh<S>& b, const RigidTransform<S>& b_to_a) {
  std::vector<Triangle<S>> tb(static_cast<std::size_t>(b.num_triangles()));
  for (int j = 0; j < b.num_triangles(); ++j) {
    const Triangle<S> t = b.triangle(j);
    tb[static_cast<std::size_t>(j)] = Triangle<S>(b_to_a.apply(t.a), b_to_a.apply(t.b), b_to_a.apply(t.c));
  }
  return tb;
}

/// Exact: the closed coordinate boxes of the two triangles share a point (comparisons only).
template <class S> bool boxes_touch(const Triangle<S>& x, const Triangle<S>& y) {
  for (int i = 0; i < 3; ++i) {
    const S xmin = std::min({x.a[i], x.b[i], x.c[i]}), xmax = std::max({x.a[i], x.b[i], x.c[i]});
    const S ymin = std::min({y.a[i], y.b[i], y.c[i]}), ymax = std::max({y.a[i], y.b[i], y.c[i]});
    if (xmax < ymin || ymax < xmin) return false;
  }
  return true;
}

/// Sorted (row a, row b) pairs of intersecting (or touching) triangles, B's triangles moved into A's
/// frame as the library does, each pair decided exactly.
template <class S>
std::vector<std::pair<int, int>> brute_force_pairs(const TriangleMesh<S>& a, const RigidTransform<S>& pa, const TriangleMesh<S>& b,
                                                   const RigidTransform<S>& pb) {
  const auto tb = moved_triangles(b, relative_transform(pa, pb));
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < a.num_triangles(); ++i) {
    const Triangle<S> ta = a.triangle(i);
    for (int j = 0; j < b.num_triangles(); ++j) {
      const Triangle<S>& t = tb[static_cast<std::size_t>(j)];
      if (boxes_touch(ta, t) && triangles_intersect_exact(ta, t)) out.emplace_back(i, j);
    }
  }
  return out;
}

/// Sorted (i, j), i < j, pairs of intersecting (or touching) triangles of one mesh that share no
/// vertex index, each pair decided exactly.
template <class S> std::vector<std::pair<int, int>> brute_force_self_pairs(const TriangleMesh<S>& m) {
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < m.num_triangles(); ++i)
    for (int j = i + 1; j < m.num_triangles(); ++j) {
      bool adjacent = false;
      for (int u = 0; u < 3; ++u)
        for (int v = 0; v < 3; ++v) adjacent = adjacent || m.F(i, u) == m.F(j, v);
      if (adjacent) continue;
      const Triangle<S> ti = m.triangle(i), tj = m.triangle(j);
      if (boxes_touch(ti, tj) && triangles_intersect_exact(ti, tj)) out.emplace_back(i, j);
    }
  return out;
}

template <class P> std::vector<P> sorted(std::vector<P> v) {
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace impact::test
