// SPDX-License-Identifier: MIT
// Checks shared by the WideBvh tests (4- and 8-wide): brute force over all triangles written here
// (the narrow phase's per-triangle rule, the smallest t), the structure of a tree (every triangle
// in exactly one leaf, the mesh's own coordinates, boxes containing their triangles, leaf blocks),
// and random casts against brute force and against each other's paths.
#pragma once

#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "impact/query/wide_fused_slab.hpp"
#include "support/meshes.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cfloat>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace impact {
namespace test {
namespace wide {

/// The cast's t against brute force's smallest t: exactly equal (a node's entry is a lower bound of
/// its triangles' t, not only up to rounding; see detail::ray_mesh_triangle_hit).
template <class S> inline void expect_first_t(S ref, S got, int i) { EXPECT_EQ(ref, got) << i; }

/// Brute force: every triangle of the mesh by the library's per-triangle rule (the watertight test,
/// the t = 0 tie rule, t never below the entry into the triangle's box), the smallest t (nullopt
/// when none is hit).
template <class S> inline std::optional<S> brute_first_t(const TriangleMesh<S>& m, const Ray<S>& ray, std::vector<int>* at_t = nullptr) {
  const PreparedRay<S> pr(ray);
  std::optional<S> best;
  for (int t = 0; t < m.num_triangles(); ++t) {
    const auto h = detail::ray_mesh_triangle_hit(pr, m.triangle(t));
    if (!h) continue;
    if (!best || h->t < *best) best = h->t;
  }
  if (at_t && best)
    for (int t = 0; t < m.num_triangles(); ++t) {
      const auto h = detail::ray_mesh_triangle_hit(pr, m.triangle(t));
      if (h && h->t == *best) at_t->push_back(t);
    }
  return best;
}

template <class S, int W> void check_structure(const TriangleMesh<S>& m, const WideBvh<S, W>& w, int leaf_size) {
  ASSERT_EQ(w.num_triangles(), m.num_triangles());
  ASSERT_EQ(w.box()[3], 0.0);
  ASSERT_EQ(w.box()[7], 0.0);
  std::vector<int> seen(static_cast<std::size_t>(m.num_triangles()), 0);
  for (std::int32_t k = 0; k < w.num_triangles(); ++k) {
    const int id = w.triangle_id(k);
    ASSERT_GE(id, 0);
    ASSERT_LT(id, m.num_triangles());
    ++seen[static_cast<std::size_t>(id)];
    const Triangle<S> t = m.triangle(id);
    ASSERT_EQ(w.triangle(k).a, t.a);  // the mesh's own coordinates
    ASSERT_EQ(w.triangle(k).b, t.b);
    ASSERT_EQ(w.triangle(k).c, t.c);
  }
  for (int s : seen) ASSERT_EQ(s, 1);
  // every leaf-order position lies in exactly one leaf; every box holds its subtree's vertices
  std::vector<int> covered(static_cast<std::size_t>(w.num_triangles()), 0);
  struct Item {
    std::int32_t node;
    float lo[3], hi[3];
  };
  std::vector<Item> stack{{0, {-FLT_MAX, -FLT_MAX, -FLT_MAX}, {FLT_MAX, FLT_MAX, FLT_MAX}}};
  auto inside = [](const Vec3<S>& p, const float (&lo)[3], const float (&hi)[3]) {
    for (int k = 0; k < 3; ++k)
      if (double(p[k]) < double(lo[k]) || double(p[k]) > double(hi[k])) return false;
    return true;
  };
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const WideBvhNodeN<W>& n = w.nodes()[static_cast<std::size_t>(it.node)];
    int children = 0;
    for (int c = 0; c < W; ++c) {
      if (n.count[c] < 0) continue;
      ++children;
      Item child{n.first[c], {}, {}};
      for (int k = 0; k < 3; ++k) child.lo[k] = n.bounds[2 * k][c], child.hi[k] = n.bounds[2 * k + 1][c];
      for (std::size_t k = 0; k < 3; ++k) {  // within the tree's box (the AVX cast's reach relies on it)
        ASSERT_LE(w.box()[k], double(child.lo[k]));
        ASSERT_GE(w.box()[4 + k], double(child.hi[k]));
      }
      if (n.count[c] > 0) {
        // a leaf's blocks: its triangles lane by lane in leaf order, zeros in the unused lanes
        const std::int32_t block = n.first[c], first = w.block_first(block), blocks = (n.count[c] + 3) / 4;
        ASSERT_GE(block, 0);
        ASSERT_LE(block + blocks, w.num_blocks());
        for (std::int32_t q = 0; q < 4 * blocks; ++q) {
          const Triangle<S> t = w.block_triangle(block + q / 4, q % 4);
          if (q % 4 == 0) {
            ASSERT_EQ(w.block_first(block + q / 4), first + q);
          }
          if (q < n.count[c]) {
            ASSERT_TRUE(t.a == w.triangle(first + q).a && t.b == w.triangle(first + q).b && t.c == w.triangle(first + q).c) << q;
            ASSERT_EQ(w.block_triangle_id(block + q / 4, q % 4), w.triangle_id(first + q)) << q;  // the block's row of F
          } else {
            ASSERT_TRUE(t.a.isZero() && t.b.isZero() && t.c.isZero()) << q;
            ASSERT_EQ(w.block_triangle_id(block + q / 4, q % 4), -1) << q;
          }
        }
        // larger leaves hold copies of one triangle only (a leaf of the source tree)
        for (std::int32_t k = first + 1; n.count[c] > leaf_size && k < first + n.count[c]; ++k)
          ASSERT_TRUE(same_shape(w.triangle(k), w.triangle(first)));
        ASSERT_FALSE(w.repeats_previous(first));  // marks stay within a leaf
        for (std::int32_t k = first; k < first + n.count[c]; ++k) {
          if (w.repeats_previous(k)) {
            ASSERT_EQ(w.triangle(k).a, w.triangle(k - 1).a);
            ASSERT_EQ(w.triangle(k).b, w.triangle(k - 1).b);
            ASSERT_EQ(w.triangle(k).c, w.triangle(k - 1).c);
          }
          ++covered[static_cast<std::size_t>(k)];
          const Triangle<S>& t = w.triangle(k);
          ASSERT_TRUE(inside(t.a, child.lo, child.hi) && inside(t.b, child.lo, child.hi) && inside(t.c, child.lo, child.hi));
          ASSERT_TRUE(inside(t.a, it.lo, it.hi) && inside(t.b, it.lo, it.hi) && inside(t.c, it.lo, it.hi));
        }
      } else {
        ASSERT_GT(n.first[c], it.node);  // children after parents: no cycles
        stack.push_back(child);
      }
    }
    ASSERT_GE(children, 1);
  }
  for (int c : covered) ASSERT_EQ(c, 1);
}

/// Random rays and segments near the mesh's triangles: the wide cast against brute force, and its
/// paths against each other: the default one (SIMD; for W = 8 the AVX loop when the CPU has AVX and
/// FMA), SSE only (W = 8: two halves of four), and the scalar node test and leaf loop, with the same
/// t; the same triangle and barycentrics as the scalar loop with the same node test (the AVX loop's
/// rounds otherwise than the SSE one's, so among triangles at the same t either may come first).
/// Returns the number of hits.
template <class S, int W> int check_casts(const TriangleMesh<S>& m, const WideBvh<S, W>& w, int n, double scale, std::uint64_t seed) {
  Rng rng(seed);
  int hits = 0;
  const RigidTransform<S>* no_pose = nullptr;
  for (int i = 0; i < n; ++i) {
    const Triangle<S> t = m.triangle(static_cast<int>(rng.index(static_cast<std::uint64_t>(m.num_triangles()))));
    const Vec3<S> o = t.centroid() + (rng.vec(-1, 1) * scale).template cast<S>();
    Vec3<S> d = (rng.vec(-1, 1) * (i % 7 == 0 ? 20 * scale : scale)).template cast<S>();
    if (i % 13 == 0) d[i % 3] = S(0);        // in a coordinate plane (1 / d infinite on an axis)
    if (i % 17 == 0) d[(i + 1) % 3] = S(0);  // along a coordinate axis, with the case above
    if (d.squaredNorm() == S(0)) continue;
    const Ray<S> ray(o, d, i % 11 == 0 ? std::numeric_limits<S>::infinity() : S(1));
    const auto ref = brute_first_t(m, ray);
    const auto fast = ray_mesh_first_hit(w, ray);
    const auto sse = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, nullptr, true, false);
    const auto scalar = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, nullptr, false);
    const auto same = detail::ray_wide_first_hit_unchecked(w, ray, no_pose, nullptr, false, false, detail::wide_fma_available());
    EXPECT_EQ(ref.has_value(), fast.has_value()) << i;
    EXPECT_EQ(fast.has_value(), scalar.has_value()) << i;
    EXPECT_EQ(fast.has_value(), sse.has_value()) << i;
    EXPECT_EQ(fast.has_value(), same.has_value()) << i;
    if (!ref || !fast || !scalar || !sse || !same) continue;
    ++hits;
    expect_first_t(*ref, fast->t, i);
    EXPECT_EQ(fast->t, scalar->t) << i;
    EXPECT_EQ(fast->t, sse->t) << i;
    EXPECT_EQ(fast->t, same->t) << i;
    EXPECT_EQ(fast->triangle, same->triangle) << i;
    EXPECT_EQ(sse->triangle, scalar->triangle) << i;
    // the hit values of the block test's lanes (double) are the scalar test's, bit for bit
    EXPECT_EQ(fast->barycentric, same->barycentric) << i;
    EXPECT_EQ(sse->barycentric, scalar->barycentric) << i;
    // the reported triangle is hit at the reported t, with the reported barycentrics
    const auto h = detail::ray_mesh_triangle_hit(PreparedRay<S>(ray), m.triangle(fast->triangle));
    EXPECT_TRUE(h && h->t == fast->t) << i;
    if (h) {
      EXPECT_EQ(Vec3<S>(h->u, h->v, h->w), fast->barycentric) << i;
    }
  }
  return hits;
}

/// Degenerate meshes for the casts: a torus with a repeated-vertex triangle and a segment, 40
/// coincident triangles, one triangle, and 80 random triangles of a flat point set.
template <class S> std::vector<TriangleMesh<S>> degenerate_meshes() {
  std::vector<TriangleMesh<S>> meshes;
  {
    const TriangleMesh<S> grid = make_torus<S>(S(1), S(0.4), 12, 6);
    const int nv = grid.num_vertices();
    Vertices<S> V(nv + 2, 3);
    V.topRows(nv) = grid.V;
    V.row(nv) << S(0), S(0), S(0);
    V.row(nv + 1) << S(2), S(0), S(0);
    Faces F(grid.num_triangles() + 2, 3);
    F.topRows(grid.num_triangles()) = grid.F;
    F.row(grid.num_triangles()) << 0, 0, 1;                 // a repeated vertex
    F.row(grid.num_triangles() + 1) << nv, nv + 1, nv + 1;  // a segment
    meshes.emplace_back(V, F);
  }
  {
    Vertices<S> V(3, 3);
    V << S(0), S(0), S(0), S(1), S(0), S(0), S(0), S(1), S(0);
    Faces F(40, 3);
    for (int t = 0; t < 40; ++t) F.row(t) << 0, 1, 2;  // coincident
    meshes.emplace_back(V, F);
    meshes.emplace_back(V, Faces(F.topRows(1)));  // one triangle
  }
  {
    test::Rng rng(3);
    Vertices<S> V(60, 3);
    for (int i = 0; i < 60; ++i) V.row(i) << S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), S(0);  // flat
    Faces F(80, 3);
    for (int t = 0; t < 80; ++t) F.row(t) << int(rng.index(60)), int(rng.index(60)), int(rng.index(60));
    meshes.emplace_back(V, F);
  }
  return meshes;
}

}  // namespace wide
}  // namespace test
}  // namespace impact
