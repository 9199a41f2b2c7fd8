// SPDX-License-Identifier: MIT
// WideBvh and its first-hit casts: the structure (every triangle in exactly one leaf, the mesh's
// own coordinates, every float box containing the triangles below it, leaves within leaf_size),
// and the casts against brute force over all triangles written here (the narrow phase's
// watertight test with the t = 0 tie rule on every triangle, the smallest t kept): the same hits
// and the same t up to rounding among near ties, in float and double, for rays in every direction (axis-parallel ones included),
// rays aimed at vertices and edge points of closed meshes (which must hit), degenerate meshes
// (zero-area triangles, coincident triangles, a flat mesh, one triangle), scaled and translated
// copies, and a rigid pose. The SIMD node test gives bit for bit the scalar one's answers.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "support/meshes.hpp"
#include "support/random.hpp"
#include "wide_bvh_checks.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <type_traits>
#include <limits>
#include <vector>

#include "support/sanitizer.hpp"

constexpr int kWideSamples = IMPACT_TEST_SANITIZED ? 4 : 1;

namespace impact {
namespace {

using test::wide::brute_first_t;
using test::wide::check_casts;
using test::wide::check_structure;
using test::wide::expect_first_t;

template <class S> class WideBvhTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(WideBvhTest, Scalars);

TYPED_TEST(WideBvhTest, TorusStructureAndFirstHits) {
  using S = TypeParam;
  const TriangleMesh<S> torus = make_torus<S>(S(1), S(0.4), 32, 16);
  for (int leaf : {1, 4, 7}) {
    WideBvhConfig cfg;
    cfg.leaf_size = leaf;
    const WideBvh<S> w(torus, cfg);
    check_structure(torus, w, leaf);
    const int n = 1500 / kWideSamples;
    EXPECT_GT(check_casts(torus, w, n, 0.1, 7 + std::uint64_t(leaf)), n / 10);
  }
  // collapsing an existing tree (spatial middle split, leaves of 3) keeps the answers
  MeshBvhConfig mcfg;
  mcfg.build.leaf_size = 3;
  const WideBvh<S> from_tree(MeshBvh<Aabb<S>>(torus, mcfg));
  check_structure(torus, from_tree, 4);
  EXPECT_GT(check_casts(torus, from_tree, 500 / kWideSamples, 0.1, 99), 50 / kWideSamples);
}

// A tree deeper than the cast's fixed stack bounds (WideCast::kFixedDepth levels): triangles
// shrinking geometrically toward a point, which the SAH tree peels off one a level. The cast then
// uses the stack with a heap overflow; the answers are brute force's, SIMD and scalar alike.
TEST(WideBvh, DeepTreeCastsLikeBruteForce) {
  const int n = 500;
  Vertices<double> V(3 * n, 3);
  Faces F(n, 3);
  for (int i = 0; i < n; ++i) {
    const double x = std::pow(0.8, i), s = 0.3 * x;
    V.row(3 * i) << x, 0, 0;
    V.row(3 * i + 1) << x, s, 0;
    V.row(3 * i + 2) << x, 0, s;
    F.row(i) << 3 * i, 3 * i + 1, 3 * i + 2;
  }
  const TriangleMesh<double> m(V, F);
  const WideBvh<double> w(m);
  ASSERT_GT(w.depth(), detail::WideCast<double>::kFixedDepth);
  check_structure(m, w, 4);
  // all 400 rays under the sanitizers too: fewer (100) hit no triangle at all (most are tiny)
  EXPECT_GT(check_casts(m, w, 400, 0.5, 17), 0);
  // along the chain: the nearest triangle first, through every level
  for (int i = 0; i < 40; ++i) {
    const double y = std::pow(0.8, 5 * i) * 0.01;
    const Ray<double> ray(Vec3<double>(-1.0, y, y), Vec3<double>(1.0, 0.0, 0.0), 3.0);
    const auto ref = brute_first_t(m, ray);
    const auto fast = ray_mesh_first_hit(w, ray);
    ASSERT_TRUE(ref.has_value() && fast.has_value()) << i;
    EXPECT_EQ(*ref, fast->t) << i;
  }
}

// A double mesh whose coordinates are all floats keeps its triangles as floats (exactly: the
// structure check compares every coordinate), in fewer bytes, with the same casts.
TEST(WideBvh, FloatCoordinatesArePackedExactly) {
  const TriangleMesh<double> exact = make_torus<double>(1.0, 0.4, 24, 12);
  TriangleMesh<double> rounded = exact;
  for (int i = 0; i < rounded.num_vertices(); ++i)
    for (int c = 0; c < 3; ++c) rounded.V(i, c) = double(float(rounded.V(i, c)));
  const WideBvh<double> a(exact), b(rounded);
  EXPECT_FALSE(a.packed());
  EXPECT_TRUE(b.packed());
  EXPECT_FALSE(a.packed_without_repeats());
  EXPECT_TRUE(b.packed_without_repeats());  // (the 8-wide cast's one-block leaf path)
  EXPECT_TRUE(WideBvh<float>(make_torus<float>(1.0f, 0.4f, 8, 4)).packed());
  EXPECT_LT(b.memory_bytes(), a.memory_bytes());
  check_structure(rounded, b, 4);
  EXPECT_GT(check_casts(rounded, b, 600 / kWideSamples, 0.1, 3), 60 / kWideSamples);
}

// Rays aimed at vertices and edge points of closed meshes from outside and inside: a watertight
// cast hits (the ray passes through the surface there), with brute force's t.
TYPED_TEST(WideBvhTest, RaysThroughVerticesAndEdgesOfClosedMeshesHit) {
  using S = TypeParam;
  for (const bool sphere : {true, false}) {
    const TriangleMesh<S> m = sphere ? make_icosphere<S>(S(1), 2) : make_torus<S>(S(1), S(0.4), 24, 12);
    const WideBvh<S> w(m);
    test::Rng rng(5);
    int hits = 0;
    const int n = 1200 / kWideSamples;
    for (int i = 0; i < n; ++i) {
      const int t = static_cast<int>(rng.index(static_cast<std::uint64_t>(m.num_triangles())));
      const Vec3<S> a = m.vertex(m.F(t, i % 3)), b = m.vertex(m.F(t, (i + 1) % 3));
      const Vec3<S> p = i % 2 == 0 ? a : Vec3<S>((a + b) / S(2));  // a vertex, or an edge's midpoint
      // from the centroid side of the surface (inside the sphere) or from far away
      const Vec3<S> o = i % 4 < 2 ? Vec3<S>(p * S(0.5)) : Vec3<S>(p + (rng.vec(-1, 1) * 3.0).template cast<S>());
      const Vec3<S> d = p - o;
      if (d.squaredNorm() == S(0)) continue;
      const Ray<S> ray(o, d, S(2));
      const auto ref = brute_first_t(m, ray);
      const auto fast = ray_mesh_first_hit(w, ray);
      ASSERT_EQ(ref.has_value(), fast.has_value()) << i;
      if (sphere && i % 4 < 2) {
        ASSERT_TRUE(fast.has_value()) << i;  // from inside the sphere, out through p
      }
      if (!fast) continue;
      ++hits;
      expect_first_t(*ref, fast->t, i);
    }
    EXPECT_GT(hits, n / 2);
  }
}

// Degenerate meshes: zero-area triangles (a repeated vertex, three collinear vertices), a stack
// of coincident triangles (every one hit at the same t), a flat mesh (all boxes flat in z), one
// triangle.
TYPED_TEST(WideBvhTest, DegenerateMeshes) {
  using S = TypeParam;
  const std::vector<TriangleMesh<S>> meshes = test::wide::degenerate_meshes<S>();
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const WideBvh<S> w(meshes[k]);
    check_structure(meshes[k], w, 4);
    EXPECT_GT(check_casts(meshes[k], w, 600 / kWideSamples, 0.5, 11 + k), 0) << k;
  }
}

// Scaled and translated copies of a torus (tiny, huge, far from the origin): the same agreement.
TYPED_TEST(WideBvhTest, ScaledAndTranslated) {
  using S = TypeParam;
  const TriangleMesh<S> base = make_torus<S>(S(1), S(0.4), 24, 12);
  for (const auto& [scale, shift] : {std::make_pair(1e-3, 0.0), std::make_pair(1e3, 0.0), std::make_pair(1.0, 1e3), std::make_pair(1e-2, -50.0)}) {
    TriangleMesh<S> m = base;
    for (int i = 0; i < m.num_vertices(); ++i)
      for (int c = 0; c < 3; ++c) m.V(i, c) = S(double(base.V(i, c)) * scale + shift);
    const WideBvh<S> w(m);
    EXPECT_GT(check_casts(m, w, 500 / kWideSamples, 0.1 * scale, 17), 25 / kWideSamples) << scale << " " << shift;
  }
}

// Under a rigid pose: the hit of the plain tree's cast (ray_mesh_first_hit on a MeshBvh).
TYPED_TEST(WideBvhTest, PoseMatchesThePlainTree) {
  using S = TypeParam;
  const TriangleMesh<S> m = make_torus<S>(S(1), S(0.4), 24, 12);
  const WideBvh<S> w(m);
  const MeshBvh<Aabb<S>> plain(m);
  test::Rng rng(23);
  int hits = 0;
  for (int i = 0; i < 600 / kWideSamples; ++i) {
    const RigidTransform<double> pd = test::random_pose(rng, Eigen::Vector3d::Constant(-2), Eigen::Vector3d::Constant(2));
    const RigidTransform<S> pose(pd.R.template cast<S>(), pd.t.template cast<S>());
    const Ray<S> ray((rng.vec(-3, 3)).template cast<S>(), (rng.vec(-1, 1) * 6.0).template cast<S>(), S(1));
    const auto a = ray_mesh_first_hit(w, ray, pose), b = ray_mesh_first_hit(plain, ray, pose);
    ASSERT_EQ(a.has_value(), b.has_value()) << i;
    if (!a) continue;
    ++hits;
    EXPECT_EQ(a->t, b->t) << i;
    EXPECT_LT((a->normal - b->normal).norm(), S(1e-3)) << i;  // the same surface (ties: a neighbour)
  }
  EXPECT_GT(hits, 20 / kWideSamples);
}

// The four-children slab test (SIMD when compiled with it) gives exactly the scalar loop's keys,
// and the scalar keys are ray_box_entry's on each float box.
TYPED_TEST(WideBvhTest, SimdSlabIsTheScalarSlab) {
  using S = TypeParam;
  test::Rng rng(41);
  int hits = 0, misses = 0;
  for (int i = 0; i < 8000 / kWideSamples; ++i) {
    const Vec3<S> o = rng.vec(-1, 1).template cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * 3.0).template cast<S>();
    const Vec3<S> inv = detail::safe_inverse(d);
    WideBvhNode n;
    const int used = 1 + int(rng.index(4));
    for (int c = 0; c < used; ++c) {
      const Eigen::Vector3d m = rng.vec(-1.5, 1.5), h = rng.vec(0.0, 0.8);
      for (int k = 0; k < 3; ++k) n.bounds[2 * k][c] = float(m[k] - h[k]), n.bounds[2 * k + 1][c] = float(m[k] + h[k]);
      n.count[c] = 1;
    }
    const S t_max = i % 3 == 0 ? std::numeric_limits<S>::infinity() : S(rng.uniform() * 2);
    S simd[4], scalar[4];
    const detail::WideSlab<S> slab(o, inv);
    slab.keys(n, t_max, simd, true);
    slab.keys(n, t_max, scalar, false);
    for (int c = 0; c < 4; ++c) {
      if (std::isnan(scalar[c]))
        EXPECT_TRUE(std::isnan(simd[c])) << i << " " << c;
      else
        EXPECT_EQ(simd[c], scalar[c]) << i << " " << c;
      if (c >= used) {  // NaN, or +inf for an infinite ray in float (the cast skips empty slots by their count)
        EXPECT_TRUE(std::isnan(scalar[c]) || scalar[c] == std::numeric_limits<S>::infinity()) << "empty slot entered " << i;
        continue;
      }
      const Aabb<S> box(Vec3<S>(S(n.bounds[0][c]), S(n.bounds[2][c]), S(n.bounds[4][c])), Vec3<S>(S(n.bounds[1][c]), S(n.bounds[3][c]), S(n.bounds[5][c])));
      const auto t = detail::ray_box_entry(o, inv, box, t_max);
      if (t) {
        ++hits;
        EXPECT_EQ(scalar[c], *t) << i << " " << c;
      } else {
        ++misses;
        EXPECT_TRUE(std::isnan(scalar[c])) << i << " " << c;
      }
    }
  }
  EXPECT_GT(hits, 500 / kWideSamples);
  EXPECT_GT(misses, 500 / kWideSamples);
}

// The float node test (detail::WideFloatSlab): SIMD and scalar give the same keys and entered
// children bit for bit; a child is entered whenever the double slab test (WideSlab, exact against
// ray_box_entry) enters it before the bound, and its key is never above the double entry (the
// traversal's pruning stays exact). Origins off the float grid, short and long segments, boxes
// at several scales.
TYPED_TEST(WideBvhTest, FloatSlabIsConservative) {
  using S = TypeParam;
  test::Rng rng(43);
  int entered = 0, missed = 0;
  for (int i = 0; i < 8000 / kWideSamples; ++i) {
    const double scale = std::ldexp(1.0, int(rng.integer(40)));
    const Vec3<S> o = (rng.vec(-1, 1) * scale).template cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * 3.0 * scale).template cast<S>();
    const Vec3<S> inv = detail::safe_inverse(d);
    const detail::WideFloatSlab<S> fs(o, inv, S(4 * scale));
    if (!fs.usable()) continue;
    WideBvhNode n;
    const int used = 1 + int(rng.index(4));
    for (int c = 0; c < used; ++c) {
      const Eigen::Vector3d m = rng.vec(-1.5, 1.5) * scale, h = rng.vec(0.0, i % 5 == 0 ? 1e-6 : 0.8) * scale;
      for (int k = 0; k < 3; ++k) n.bounds[2 * k][c] = float(m[k] - h[k]), n.bounds[2 * k + 1][c] = float(m[k] + h[k]);
      n.count[c] = 1;
    }
    const S t_max = i % 3 == 0 ? std::numeric_limits<S>::infinity() : S(rng.uniform() * 2);
    const float bound = i % 2 ? std::numeric_limits<float>::infinity() : float(rng.uniform() * 1.5);
    const float exit = detail::WideFloatSlab<S>::round_up(double(t_max));
    float simd[4], scalar[4];
    const int ms = fs.entered(n, exit, bound, simd, true), mc = fs.entered(n, exit, bound, scalar, false);
    ASSERT_EQ(ms, mc) << i;
    S exact[4];
    detail::WideSlab<S>(o, inv).keys(n, t_max, exact, false);
    for (int c = 0; c < 4; ++c) {
      if ((mc >> c) & 1) {
        EXPECT_EQ(simd[c], scalar[c]) << i << " " << c;
      }
      if (c >= used) {
        EXPECT_FALSE((mc >> c) & 1) << "empty slot entered " << i;
        continue;
      }
      if (exact[c] <= S(bound)) {  // WideSlab enters before the bound: so must the float test, no later
        ++entered;
        ASSERT_TRUE((mc >> c) & 1) << i << " " << c;
        EXPECT_LE(S(scalar[c]), exact[c]) << i << " " << c;
      } else {
        missed += (mc >> c) & 1 ? 0 : 1;
      }
    }
  }
  EXPECT_GT(entered, 500 / kWideSamples);
  EXPECT_GT(missed, 500 / kWideSamples);  // it prunes too
}

#if defined(__SSE2__)
/// The block test of a leaf against the watertight test on each lane's triangle, with the band
/// bound of the block's box (as the casts set it for the tree's box): in double the lanes it
/// passes are the triangles the test hits and the lanes near an edge (LaneValues::near: those
/// with an edge function within the bound, which the scalar test decides); in float a superset
/// of the hits; with AVX (when the CPU has it) as with SSE2; in double the passed lanes' values
/// not near an edge give the test's t, barycentrics and side. The scalar test with the bound
/// gives what it gives without (every triangle's own band), bit for bit. Returns the lanes it
/// rejects.
template <class S, class T> int check_block(const WideTriangleBlock<T>& b, const Ray<S>& ray, int count, int* near_count = nullptr) {
  Vec3<S> lo = Vec3<S>::Constant(std::numeric_limits<S>::infinity()), hi = -lo;
  for (int c = 0; c < count; ++c)
    for (int v = 0; v < 3; ++v) {
      const Vec3<S> p(S(b.v[3 * v][c]), S(b.v[3 * v + 1][c]), S(b.v[3 * v + 2][c]));
      lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    }
  PreparedRay<S> pr(ray);
  pr.bound_band(lo, hi);
  const PreparedRay<S> unbounded(ray);
  detail::BlockTest<S> bt, sse;
  bt.set(pr);  // AVX when the CPU has it (double)
  sse.set(pr, false);
  bt.bound_plane(lo, hi), sse.bound_plane(lo, hi);  // the depth's bound for origins in a plane, as the casts set it
  typename detail::BlockTest<S>::LaneValues values, sse_values;
  const int todo = bt.candidates(b, count, ray.t_max, &values);
  EXPECT_EQ(todo, sse.candidates(b, count, ray.t_max, &sse_values));  // the same bits
  int skipped = 0;
  for (int c = 0; c < count; ++c) {
    auto at = [&](int v) { return Vec3<S>(S(b.v[3 * v][c]), S(b.v[3 * v + 1][c]), S(b.v[3 * v + 2][c])); };
    const Triangle<S> t{at(0), at(1), at(2)};
    const auto with_bound = intersect_ray_triangle(pr, t), without = intersect_ray_triangle(unbounded, t);
    EXPECT_EQ(with_bound.has_value(), without.has_value()) << "lane " << c;
    if (with_bound && without) {
      EXPECT_EQ(with_bound->t, without->t);
      EXPECT_EQ(with_bound->u, without->u);
      EXPECT_EQ(with_bound->w, without->w);
    }
    const bool hit = with_bound.has_value(), passed = (todo >> c) & 1;
    const bool near = todo && std::is_same_v<S, double> && ((values.near >> c) & 1);
    if (near_count) *near_count += near ? 1 : 0;
    if (std::is_same_v<S, double> && todo) {
      EXPECT_EQ(values.near, sse_values.near);
    }
    if (near) {
      EXPECT_TRUE(passed) << "lane " << c;
    } else if (std::is_same_v<S, double>) {
      EXPECT_EQ(passed, hit) << "lane " << c;
      if (passed && hit) {  // the lane's values give the test's hit values, AVX and SSE2 alike
        const auto h = intersect_ray_triangle(pr, t);
        const S inv_det = S(1) / values.det[c];
        EXPECT_EQ(h->t, std::min(S(values.tt[c] * inv_det), ray.t_max)) << "lane " << c;
        EXPECT_EQ(h->u, S(values.eu[c] * inv_det)) << "lane " << c;
        EXPECT_EQ(h->v, S(values.ev[c] * inv_det)) << "lane " << c;
        EXPECT_EQ(h->w, S(values.ew[c] * inv_det)) << "lane " << c;
        EXPECT_EQ(h->front, values.det[c] > S(0)) << "lane " << c;
        EXPECT_EQ(values.det[c], sse_values.det[c]) << "lane " << c;
        EXPECT_EQ(values.tt[c], sse_values.tt[c]) << "lane " << c;
      }
    } else if (!passed) {
      EXPECT_FALSE(hit) << "skipped a hit, lane " << c;
    }
    skipped += passed ? 0 : 1;
  }
  EXPECT_EQ(todo >> count, 0);
#if defined(IMPACT_BLOCK_TEST_AVX)
  if constexpr (std::is_same_v<S, double>) {
    // the lanes decided and finished at once (hits_avx, set up by set_ray): exactly the lanes the
    // narrow-phase rule of the cast hits (detail::ray_mesh_triangle_hit: the box entry, the t = 0
    // rule), with its t, barycentrics and side bit for bit
    const Vec3<S> inv = detail::safe_inverse(ray.direction);
    if (detail::wide_avx_available() && inv.allFinite()) {
      detail::BlockTest<S> lanes_test;
      lanes_test.set_ray(ray.origin, ray.direction, inv);
      lanes_test.bound_band(lo, hi);
      typename detail::BlockTest<S>::LaneHits h;
      const int hit_lanes = lanes_test.hits_avx(b, count, ray.t_max, h);
      EXPECT_EQ(hit_lanes & h.near, 0);
      if (todo) {
        EXPECT_EQ(h.near, values.near);  // the same bound and lanes as set(pr)
      }
      for (int c = 0; c < count; ++c) {
        auto at = [&](int v) { return Vec3<S>(S(b.v[3 * v][c]), S(b.v[3 * v + 1][c]), S(b.v[3 * v + 2][c])); };
        const auto r = detail::ray_mesh_triangle_hit(pr, inv, Triangle<S>{at(0), at(1), at(2)});
        if ((h.near >> c) & 1) continue;  // left to the scalar rule
        EXPECT_EQ((hit_lanes >> c) & 1, r ? 1 : 0) << "lane " << c;
        if (r && ((hit_lanes >> c) & 1)) {
          EXPECT_EQ(h.t[c], r->t) << "lane " << c;
          EXPECT_EQ(S(h.eu[c] * h.inv_det[c]), r->u) << "lane " << c;
          EXPECT_EQ(S(h.ev[c] * h.inv_det[c]), r->v) << "lane " << c;
          EXPECT_EQ(S(h.ew[c] * h.inv_det[c]), r->w) << "lane " << c;
          EXPECT_EQ(h.det[c] > S(0), r->front) << "lane " << c;
        }
      }
      EXPECT_EQ(hit_lanes >> count, 0);
      EXPECT_EQ(h.near >> count, 0);
    }
  }
#endif
  return skipped;
}

// The block test of a leaf's four triangles gives the watertight test's decisions (double: exactly;
// float: never skipping a hit): random triangles around the ray, degenerate ones (a repeated
// vertex, collinear vertices), rays through a vertex or an edge point of a triangle (exactly, on a
// float grid), rays nearly parallel to a triangle's plane or grazing it, origins off the float grid
// and (double) coordinates off it, hits near t_max and behind the origin, at coordinates from
// 1e-30 to 1e30 (products overflow or underflow there in float).
TYPED_TEST(WideBvhTest, BlockTestDecidesAsTheScalarTest) {
  using S = TypeParam;
  test::Rng rng(47);
  int skipped = 0, lanes = 0, near = 0;
  for (int i = 0; i < 20000 / kWideSamples; ++i) {
    const double scale = i % 10 == 9 ? (i % 20 == 9 ? 1e-30 : 1e30) : std::ldexp(1.0, int(rng.integer(20)));
    const double grid = std::ldexp(scale, -12);
    auto snap = [&](double x) { return double(float(std::nearbyint(x / grid) * grid)); };
    WideTriangleBlock<float> packed{};
    WideTriangleBlock<S> full{};  // S: off the float grid when i % 3 == 0
    const bool off_grid = std::is_same_v<S, double> && i % 3 == 0;
    const int count = 1 + int(rng.index(4));
    Eigen::Vector3d first[3];
    for (int c = 0; c < count; ++c) {
      const Eigen::Vector3d centre = rng.vec(-1, 1) * scale;
      Eigen::Vector3d p[3];
      for (int v = 0; v < 3; ++v) p[v] = centre + rng.vec(-0.5, 0.5) * scale * (i % 7 == 0 ? 1e-3 : 1.0);
      if (i % 13 == 0 && c == count - 1) p[2] = i % 26 == 0 ? p[0] : Eigen::Vector3d((p[0] + p[1]) / 2.0);  // degenerate
      for (int v = 0; v < 3; ++v)
        for (int k = 0; k < 3; ++k) {
          packed.v[3 * v + k][c] = float(snap(p[v][k]));
          full.v[3 * v + k][c] = off_grid ? S(p[v][k]) : S(packed.v[3 * v + k][c]);
        }
      if (c == 0)
        for (int v = 0; v < 3; ++v) first[v] = Eigen::Vector3d(double(full.v[3 * v][0]), double(full.v[3 * v + 1][0]), double(full.v[3 * v + 2][0]));
    }
    // the target: a vertex, an edge point on the grid, an inner point of the first triangle
    const int kind = int(rng.index(4));
    Eigen::Vector3d target = first[0];
    if (kind == 1) {
      for (int k = 0; k < 3; ++k) target[k] = snap(first[0][k] + 0.5 * (first[1][k] - first[0][k]));
    } else if (kind >= 2) {
      target = (first[0] + first[1] + first[2]) / 3.0;
    }
    Eigen::Vector3d o = target + rng.vec(-2, 2) * scale;
    if (i % 11 == 0) {  // nearly in the first triangle's plane
      const Eigen::Vector3d nrm = (first[1] - first[0]).cross(first[2] - first[0]);
      const Eigen::Vector3d e = first[1] - first[0];
      if (nrm.squaredNorm() > 0) o = target - 2.0 * e + nrm.normalized() * (1e-6 * scale * rng.uniform(-1, 1));
    }
    if (std::is_same_v<S, float> || i % 3 != 0) {
      for (int k = 0; k < 3; ++k) o[k] = snap(o[k]);  // on the grid (double: also off it)
    }
    const Eigen::Vector3d d = target - o;
    if (d.squaredNorm() == 0 || !std::isfinite(d.squaredNorm())) continue;
    const double t_max = i % 5 == 0 ? rng.uniform(0.99, 1.01) : i % 5 == 1 ? std::numeric_limits<double>::infinity() : 2.0;
    const Ray<S> ray(o.template cast<S>(), d.template cast<S>(), S(t_max));
    if (ray.direction.squaredNorm() == S(0)) continue;
    skipped += check_block(packed, ray, count, &near);
    if (std::is_same_v<S, double>) skipped += check_block(full, ray, count, &near);
    lanes += std::is_same_v<S, double> ? 2 * count : count;
  }
  EXPECT_GT(skipped, lanes / 4);  // the clear misses are rejected
  if (std::is_same_v<S, double>) {  // the rays through vertices and edge points: some lanes near an edge, most not
    EXPECT_GT(near, 100 / kWideSamples);
    EXPECT_LT(near, lanes / 4);
  }
}

// The block test's frame as the AVX cast sets it up (BlockTest::set_ray, without jumps) is
// PreparedRay's where the direction's largest magnitude is shared by two or three components (the
// first such axis) and the frame's x and y swap (a negative component along it): rays with such
// directions, in each of the eight sign combinations, through four triangles around a point;
// check_block compares the lanes' values with the scalar test's bit for bit.
// From a point exactly on the surface, every cast path of the 4- and 8-wide trees (AVX, SSE2 and
// scalar leaves) hits the triangle there at t = 0 exactly when the ray enters its front, and reports
// nothing when the ray leaves it, also when the ray's dominant axis is not the normal's (before, the
// leaf tests took the depth's rounded sign: about a quarter of such rays into the front were missed
// and a quarter of those leaving it reported at a t of a few ulps, as the scalar test did; audit of
// 2026-12-07). Planes through the origin with small integer normals, points on them exact.
TYPED_TEST(WideBvhTest, SurfaceStartsInEveryDirection) {
  using S = TypeParam;
  test::Rng rng(91);
  const Vec3<S> normals[] = {Vec3<S>(0, 0, 1), Vec3<S>(1, 2, 4), Vec3<S>(-3, 1, 2), Vec3<S>(1, -4, 8)};
  int oblique = 0, rays = 0;
  for (const Vec3<S>& n : normals) {
    // a 4 x 4 grid in the plane n . x = 0 (z from x and y: multiples of 1/8, exact in float)
    TriangleMesh<S> m = make_grid<S>(4, 4, S(2));
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V(i, 2) = -(n.x() * m.V(i, 0) + n.y() * m.V(i, 1)) / n.z();
    const WideBvh<S, 4> w4(m);
    const WideBvh<S, 8> w8(m);
    for (int k = 0; k < 1500; ++k) {
      // a point of the surface: x, y multiples of 2^-10 (z then exact; some on edges)
      const S x = S(std::ldexp(double(rng.integer(900)), -10)), y = S(std::ldexp(double(rng.integer(900)), -10));
      const Vec3<S> o(x, y, -(n.x() * x + n.y() * y) / n.z());
      Vec3<S> d = rng.vec(-1, 1).template cast<S>();
      const S along = d.dot(n) / n.norm();
      if (!(std::abs(along) > S(1e-2))) continue;
      Eigen::Index kd = 0, kn = 0;
      d.cwiseAbs().maxCoeff(&kd);
      n.cwiseAbs().maxCoeff(&kn);
      oblique += kd != kn ? 1 : 0;
      const bool into_front = along < 0;  // the grid's triangles face +n (make_grid: +z)
      ++rays;
      for (int path = 0; path < 3; ++path) {
        const bool simd = path < 2, avx = path == 0;
        const Ray<S> ray(o, d, S(1));
        for (const auto& h : {detail::ray_wide_cast(w4, ray, o, d, static_cast<const RigidTransform<S>*>(nullptr), nullptr, simd, avx),
                              detail::ray_wide_cast(w8, ray, o, d, static_cast<const RigidTransform<S>*>(nullptr), nullptr, simd, avx)}) {
          if (into_front) {
            ASSERT_TRUE(h.has_value()) << "path " << path << " from (" << o.transpose() << ") along (" << d.transpose() << ")";
            EXPECT_EQ(h->t, S(0)) << "path " << path;
            EXPECT_TRUE(h->front_face) << "path " << path;
          } else {
            EXPECT_FALSE(h.has_value()) << "path " << path << " from (" << o.transpose() << ") along (" << d.transpose() << ") t " << h->t;
          }
        }
      }
    }
  }
  EXPECT_GT(rays, 4000);
  EXPECT_GT(oblique, rays / 4);
}

// The depth's error bound for an origin in a triangle's plane (detail::box_plane_bound: a hit
// lane with a finite depth above it skips the in-plane test): blocks of four triangles in planes
// through the ray's origin (exact: small integer slopes, grid offsets around the origin, scales
// 2^-40 to 2^40, some moved far off), random directions; every finite depth tt the block test
// computes (SSE2: its values are written for every lane of a half that passes one) lies within the
// bound of the block's box. The largest ratio found is above 2^-20: a bound 2^20 times smaller
// would fail here, and in the casts below.
TEST(WideBvh, PlaneBoundCoversInPlaneDepths) {
  test::Rng rng(61);
  double worst = 0.0;
  int lanes = 0;
  for (int i = 0; i < 20000 / kWideSamples; ++i) {
    const double scale = std::ldexp(1.0, int(rng.integer(40))), grid = std::ldexp(scale, -6);
    // the origin on the grid, sometimes 2^20 scales away from 0
    const double far = i % 4 == 3 ? std::ldexp(scale, 20) : 0.0;
    const Eigen::Vector3d o(far + grid * double(rng.integer(64)), grid * double(rng.integer(64)), -far + grid * double(rng.integer(64)));
    WideTriangleBlock<double> block{};
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int c = 0; c < 4; ++c) {
      // the plane z - o_z = (p (x - o_x) + q (y - o_y)) / 8 through o, one a lane
      const double p = double(rng.integer(16)), q = double(rng.integer(16));
      const int axis = int(rng.index(3));  // the plane's steep axis
      for (int v = 0; v < 3; ++v) {
        const double gx = double(rng.integer(64)), gy = double(rng.integer(64));
        Eigen::Vector3d off(grid * gx, grid * gy, grid * (p * gx + q * gy) / 8.0);
        std::swap(off[2], off[axis]);
        const Eigen::Vector3d vertex = o + off;
        for (int k = 0; k < 3; ++k) block.v[3 * v + k][c] = vertex[k];
        lo = lo.cwiseMin(vertex), hi = hi.cwiseMax(vertex);
      }
    }
    const Ray<double> ray(o, rng.vec(-1, 1), 4.0 * scale);
    if (ray.direction.squaredNorm() == 0.0) continue;
    detail::BlockTest<double> bt;
    bt.set(PreparedRay<double>(ray), false);
    bt.bound_band(lo, hi);
    const double bound = bt.plane_bound();
    ASSERT_TRUE(bound > 0.0 && bound < std::numeric_limits<double>::infinity());
    detail::BlockTest<double>::LaneValues values;
    for (double& t : values.tt) t = std::numeric_limits<double>::quiet_NaN();
    bt.candidates(block, 4, ray.t_max, &values);
    for (int c = 0; c < 4; ++c) {
      if (!std::isfinite(values.tt[c])) continue;  // (not written)
      ++lanes;
      ASSERT_LE(std::abs(values.tt[c]), bound) << "lane " << c << " of block " << i;
      worst = std::max(worst, std::abs(values.tt[c]) / bound);
    }
  }
  EXPECT_GT(lanes, 10000 / kWideSamples);
  EXPECT_GT(worst, 0x1p-20);
  EXPECT_LE(worst, 1.0);
}

// A ray from a point of a mesh of one triangle (so the tree's box, on which the depth's bound for
// origins in the plane is built, is the triangle's own), on every cast path of the 4- and 8-wide
// trees: from a point exactly on it, hit at t = 0 exactly into the front and nothing away from it
// (a depth bound too small would let the depth's rounding decide: misses and t of a few ulps);
// from points a few ulps off its plane, brute force's answer (the lanes' depth then decides where
// it is above the bound). Tilted planes, scaled and moved copies, exact coordinates.
TYPED_TEST(WideBvhTest, SurfaceStartsOnOneTriangle) {
  using S = TypeParam;
  test::Rng rng(92);
  const Vec3<S> normals[] = {Vec3<S>(0, 0, 1), Vec3<S>(1, 2, 4), Vec3<S>(-3, 1, 2), Vec3<S>(1, -4, 8)};
  int rays = 0, off_plane = 0;
  for (int copy = 0; copy < 8; ++copy) {
    const Vec3<S>& n = normals[copy % 4];
    const S scale = S(std::ldexp(1.0, int(rng.integer(20)))), shift = copy < 4 ? S(0) : S(std::ldexp(1.0, 6)) * scale;
    auto on_plane = [&](S x, S y) { return Vec3<S>(shift + scale * x, scale * y, scale * (-(n.x() * x + n.y() * y) / n.z()) - shift); };
    Vertices<S> V(3, 3);
    V.row(0) = on_plane(S(0), S(0)).transpose();
    V.row(1) = on_plane(S(1), S(0)).transpose();
    V.row(2) = on_plane(S(0), S(1)).transpose();
    Faces F(1, 3);
    F.row(0) << 0, 1, 2;
    const TriangleMesh<S> m(V, F);
    const WideBvh<S, 4> w4(m);
    const WideBvh<S, 8> w8(m);
    for (int k = 0; k < 800 / kWideSamples; ++k) {
      // a point of the triangle: x, y multiples of 2^-10, x + y <= 1 (some on its edges)
      S x = S(std::ldexp(double(rng.index(1025)), -10)), y = S(std::ldexp(double(rng.index(1025)), -10));
      if (x + y > S(1)) x = S(1) - x, y = S(1) - y;
      Vec3<S> o = on_plane(x, y);
      const int ulps = k % 3 == 2 ? int(rng.integer(3)) : 0;  // a third of them moved off the plane by up to 3 ulps in z
      for (int u = 0; u < std::abs(ulps); ++u) o.z() = std::nextafter(o.z(), ulps > 0 ? std::numeric_limits<S>::max() : -std::numeric_limits<S>::max());
      const Vec3<S> d = rng.vec(-1, 1).template cast<S>();
      const S along = d.dot(n) / n.norm();
      if (!(std::abs(along) > S(1e-2))) continue;
      const Ray<S> ray(o, d, S(2) * scale);
      ++rays;
      off_plane += ulps != 0 ? 1 : 0;
      const std::optional<S> ref = test::wide::brute_first_t(m, ray);
      if (ulps == 0) {
        ASSERT_EQ(ref.has_value(), along < 0);  // the rule (brute force's): into the front at t = 0, none away
        if (ref) {
          ASSERT_EQ(*ref, S(0));
        }
      }
      for (int path = 0; path < 3; ++path) {
        const bool simd = path < 2, avx = path == 0;
        for (const auto& h : {detail::ray_wide_cast(w4, ray, o, d, static_cast<const RigidTransform<S>*>(nullptr), nullptr, simd, avx),
                              detail::ray_wide_cast(w8, ray, o, d, static_cast<const RigidTransform<S>*>(nullptr), nullptr, simd, avx)}) {
          ASSERT_EQ(h.has_value(), ref.has_value()) << "path " << path << " from (" << o.transpose() << ") along (" << d.transpose() << "), ulps " << ulps;
          if (h) {
            EXPECT_EQ(h->t, *ref) << "path " << path << ", ulps " << ulps;
          }
        }
      }
    }
  }
  EXPECT_GT(rays, 4000 / kWideSamples);
  EXPECT_GT(off_plane, rays / 5);
}

TEST(WideBvh, BlockTestFrameAtTiedDirections) {
  test::Rng rng(53);
  const Eigen::Vector3d p(0.25, -0.5, 0.75);
  WideTriangleBlock<double> block{};
  for (int c = 0; c < 4; ++c) {  // the triangle (p + u, p + v, p - u - v): its centroid is p
    const Eigen::Vector3d u = rng.vec(-1, 1), v = rng.vec(-1, 1);
    const Eigen::Vector3d vertex[3] = {p + u, p + v, p - u - v};
    for (int k = 0; k < 9; ++k) block.v[k][c] = vertex[k / 3][k % 3];
  }
  const double magnitudes[][3] = {{1, 1, 1}, {1, 1, 0.5}, {1, 0.5, 1}, {0.5, 1, 1}, {2, 2, 1}, {1, 2, 2}, {2, 1, 2}};
  int rejected = 0;
  for (const auto& m : magnitudes) {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Vector3d d;
      for (int k = 0; k < 3; ++k) d[k] = (signs >> k) & 1 ? -m[k] : m[k];
      rejected += check_block(block, Ray<double>(p - 1.5 * d, d, 2.0), 4);
    }
  }
  EXPECT_LT(rejected, 7 * 8);  // most lanes are hit (so their values are compared)
}
#endif

// The float slab at large magnitudes: origins up to 2^59, off the float grid by up to 2^35,
// boxes near them
// (the absolute part e of the padding up to 2^39), directions from 2^-20 to 2^20: still
// conservative against WideSlab, and never entering an empty slot (no count check: the inverted
// box must give an empty interval however large e is while the ray is usable).
TYPED_TEST(WideBvhTest, FloatSlabAtLargeMagnitudes) {
  using S = TypeParam;
  test::Rng rng(53);
  int entered = 0, usable = 0;
  for (int i = 0; i < 4000 / kWideSamples; ++i) {
    const double scale = std::ldexp(1.0, 20 + int(rng.integer(40)));  // 2^20 .. 2^59
    const Vec3<S> o = (rng.vec(-1, 1) * scale).template cast<S>();
    const Vec3<S> d = (rng.vec(-1, 1) * std::ldexp(1.0, int(rng.integer(41)) - 20) * scale).template cast<S>();
    const Vec3<S> inv = detail::safe_inverse(d);
    const detail::WideFloatSlab<S> fs(o, inv, S(2 * scale));
    if (!fs.usable()) continue;
    ++usable;
    WideBvhNode n;  // slots 2 and 3 stay empty
    for (int c = 0; c < 2; ++c) {  // boxes near the origin at every scale down to 2^-24 of it (its rounding matters)
      const double near = std::ldexp(scale, -int(rng.integer(25)));
      const Eigen::Vector3d m = o.template cast<double>() + rng.vec(-1, 1) * near, h = rng.vec(0.0, 0.5) * near;
      for (int k = 0; k < 3; ++k) n.bounds[2 * k][c] = float(m[k] - h[k]), n.bounds[2 * k + 1][c] = float(m[k] + h[k]);
      n.count[c] = 1;
    }
    const S t_max = i % 2 ? std::numeric_limits<S>::infinity() : S(rng.uniform() * 4);
    float simd[4], scalar[4];
    const int ms = fs.entered(n, detail::float_round_up(double(t_max)), std::numeric_limits<float>::infinity(), simd, true);
    const int mc = fs.entered(n, detail::float_round_up(double(t_max)), std::numeric_limits<float>::infinity(), scalar, false);
    ASSERT_EQ(ms, mc) << i;
    EXPECT_EQ(mc & 12, 0) << "empty slot entered " << i;
    S exact[4];
    detail::WideSlab<S>(o, inv).keys(n, t_max, exact, false);
    for (int c = 0; c < 2; ++c) {
      if (exact[c] <= t_max) {
        ++entered;
        ASSERT_TRUE((mc >> c) & 1) << i << " " << c;
        EXPECT_LE(S(scalar[c]), exact[c]) << i << " " << c;
      }
    }
  }
  EXPECT_GT(usable, 2000 / kWideSamples);
  EXPECT_GT(entered, 200 / kWideSamples);
}

// float_round_up / float_round_down / float_bounds (the float node test's bounds) against a reference by
// nextafter: the nearest float on the right side, at zero, subnormals, the float range's ends;
// the bounds after a hit (float_hit_bounds: the same floats as rounding best and next_down(best))
// and the tie bound under best - 4 (best 2^-19 + e).
TEST(WideBvh, FloatRoundingHelpers) {
  test::Rng rng(59);
  auto up = [](double x) {
    float f = static_cast<float>(x);
    if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
  };
  std::vector<double> xs = {0.0, -0.0, 1.0, -1.0, 0x1p-149, -0x1p-149, 0x1p-150, -0x1p-150, 0x1p-160, -0x1p-160, double(FLT_MAX),
                            -double(FLT_MAX), 1e300, -1e300, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                            1.0 + 0x1p-30, 1.0 - 0x1p-30, -1.0 + 0x1p-30, 0x1.fffffffp127, -0x1.fffffffp127};
  for (int i = 0; i < 20000; ++i) xs.push_back(std::ldexp(rng.uniform(-1, 1), int(rng.integer(320)) - 160));
  for (const double x : xs) {
    const float u = detail::float_round_up(x), dn = detail::float_round_down(x);
    const float ru = up(x), rd = -up(-x);
    EXPECT_TRUE(u == ru && std::signbit(u) == std::signbit(ru)) << x;
    EXPECT_TRUE(dn == rd && std::signbit(dn) == std::signbit(rd)) << x;
    EXPECT_GE(double(u), x) << x;
    EXPECT_LE(double(dn), x) << x;
    // float_bounds (the cast's bounds of t_max, from one rounding): both at once, the same bits
    float bd = 0.0f, bu = 0.0f;
    detail::float_bounds(x, bd, bu);
    EXPECT_TRUE(bu == ru && std::signbit(bu) == std::signbit(ru)) << x;
    EXPECT_TRUE(bd == rd && std::signbit(bd) == std::signbit(rd)) << x;
    // the bound after a hit, next_down(best), is tested against std::nextafter in tests/core
    const double rnd = std::nextafter(x, -std::numeric_limits<double>::infinity());
    if (std::signbit(x) && x != 0.0) continue;  // (a hit's t: +0, -0 or positive)
    float hu = 0.0f, hb = 0.0f;
    detail::float_hit_bounds(x, hu, hb);
    const float rb = -up(-rnd);  // the largest float below x
    EXPECT_TRUE(hu == ru) << x;  // (+0 or -0 for x = -0)
    EXPECT_TRUE(hb == rb && std::signbit(hb) == std::signbit(rb)) << x;
    if (!(x <= double(FLT_MAX))) continue;
    for (const float e : {0x1p-100f, static_cast<float>(0x1p-20 * x) + 0x1p-100f, static_cast<float>(x) + 0x1p-100f}) {
      const long double tie = detail::float_tie_bound(hb, e);
      EXPECT_LE(tie, static_cast<long double>(x) - 4.0L * (static_cast<long double>(x) * 0x1p-19L + e)) << x << " " << e;
    }
  }
}

// The casts' quick argument check (detail::ray_in_range) accepts exactly the rays validate_ray
// accepts: finite, within CoordinateRange, the direction not too short, t_max >= 0 or +inf.
TYPED_TEST(WideBvhTest, RayInRangeIsValidateRay) {
  using S = TypeParam;
  test::Rng rng(61);
  const S specials[] = {S(0), -S(0), S(1), S(-3), std::numeric_limits<S>::infinity(), -std::numeric_limits<S>::infinity(),
                        std::numeric_limits<S>::quiet_NaN(), CoordinateRange<S>::max, -CoordinateRange<S>::max,
                        S(2) * CoordinateRange<S>::max, CoordinateRange<S>::min_scale, CoordinateRange<S>::min_scale / S(2),
                        -CoordinateRange<S>::min_scale, std::numeric_limits<S>::denorm_min()};
  const int ns = static_cast<int>(sizeof(specials) / sizeof(specials[0]));
  int accepted = 0, rejected = 0;
  for (int i = 0; i < 20000; ++i) {
    auto value = [&] { return rng.index(3) == 0 ? specials[rng.index(static_cast<std::uint64_t>(ns))] : S(rng.uniform(-2, 2)); };
    Ray<S> ray(Vec3<S>(value(), value(), value()), Vec3<S>(value(), value(), value()), value());
    if (i % 2 == 0) ray.origin = Vec3<S>(S(rng.uniform(-1, 1)), S(rng.uniform(-1, 1)), value());
    if (i % 3 == 0) ray.t_max = S(rng.uniform(0, 2));
    bool throws = false;
    try {
      validate_ray(ray, "test");
    } catch (const InvalidInput&) {
      throws = true;
    }
    EXPECT_EQ(detail::ray_in_range(ray), !throws) << i;
    ++(throws ? rejected : accepted);
  }
  EXPECT_GT(accepted, 1000);
  EXPECT_GT(rejected, 1000);
}

// Directions far from unit length at the public casts: shorter than CoordinateRange::min_scale in
// their largest component (squared norms would underflow) they get InvalidInput; huge ones, up to
// CoordinateRange::max, give brute force's t over every triangle on the ray with the direction
// scaled back by the power of two (exactly; t scaled likewise), through the wide and binary trees.
// (The unchecked casts of particles' legs, which take the short ones: tests/response/test_short_legs.cpp.)
TYPED_TEST(WideBvhTest, TinyAndHugeDirections) {
  using S = TypeParam;
  const TriangleMesh<S> m = make_torus<S>(S(1), S(0.4), 24, 12);
  const WideBvh<S> w(m);
  const MeshBvh<Aabb<S>> mb(m);
  const CompactBvh cb(mb.tree());
  test::Rng rng(83);
  int hits = 0;
  const int big = std::is_same_v<S, float> ? 28 : 200;  // max = 2^big
  for (int i = 0; i < 60; ++i) {
    const Vec3<S> o = (rng.vec(-1.5, 1.5)).template cast<S>();
    const Vec3<S> u = (rng.vec(-1, 1)).template cast<S>();
    if (u.cwiseAbs().maxCoeff() < S(0.25)) continue;
    const Vec3<S> tiny(std::ldexp(u[0], -big - 3), std::ldexp(u[1], -big - 3), std::ldexp(u[2], -big - 3));  // below min_scale
    EXPECT_THROW(ray_mesh_first_hit(w, Ray<S>(o, tiny, S(1))), InvalidInput);
    EXPECT_THROW(ray_mesh_first_hit(mb, Ray<S>(o, tiny, S(1))), InvalidInput);
    EXPECT_THROW(ray_mesh_first_hit(mb, cb, Ray<S>(o, tiny)), InvalidInput);
    const Vec3<S> h(std::ldexp(u[0], big), std::ldexp(u[1], big), std::ldexp(u[2], big));  // at most max
    const auto ref = brute_first_t(m, Ray<S>(o, u, S(2)));
    const Ray<S> ray(o, h, std::ldexp(S(2), -big));
    const auto a = ray_mesh_first_hit(w, ray);
    const auto b = ray_mesh_first_hit(mb, ray);
    const auto c = ray_mesh_first_hit(mb, cb, ray);
    ASSERT_EQ(ref.has_value(), a.has_value()) << i;
    ASSERT_EQ(ref.has_value(), b.has_value()) << i;
    ASSERT_EQ(ref.has_value(), c.has_value()) << i;
    EXPECT_THROW(ray_mesh_first_hit(w, Ray<S>(o, S(8) * h, S(1))), InvalidInput);  // beyond max
    if (!ref) continue;
    ++hits;
    EXPECT_EQ(a->t, std::ldexp(*ref, -big)) << i;
    EXPECT_EQ(b->t, std::ldexp(*ref, -big)) << i;
    EXPECT_EQ(c->t, std::ldexp(*ref, -big)) << i;
  }
  EXPECT_GT(hits, 5);
}

TEST(WideBvh, InvalidInput) {
  const TriangleMesh<double> m = make_torus<double>(1.0, 0.4, 8, 4);
  WideBvhConfig bad;
  bad.leaf_size = 0;
  EXPECT_THROW(WideBvh<double>(m, bad), InvalidInput);
  bad = {};
  bad.sah_bins = 1;
  EXPECT_THROW(WideBvh<double>(m, bad), InvalidInput);
  TriangleMesh<double> broken = m;
  broken.F(0, 1) = broken.num_vertices();  // index out of range
  EXPECT_THROW(WideBvh<double>{broken}, InvalidInput);
  broken = m;
  broken.V(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(WideBvh<double>{broken}, InvalidInput);
  const WideBvh<double> w(m);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ray_mesh_first_hit(w, Ray<double>(Vec3<double>(nan, 0, 0), Vec3<double>(1, 0, 0), 1.0)), InvalidInput);
  EXPECT_THROW(ray_mesh_first_hit(w, Ray<double>(Vec3<double>(0, 0, 0), Vec3<double>(0, 0, 0), 1.0)), InvalidInput);
  EXPECT_THROW(ray_mesh_first_hit(w, Ray<double>(Vec3<double>(0, 0, 0), Vec3<double>(1, 0, 0), -1.0)), InvalidInput);
  RigidTransform<double> scaled;
  scaled.R *= 2.0;
  EXPECT_THROW(ray_mesh_first_hit(w, Ray<double>(Vec3<double>(0, 0, 0), Vec3<double>(1, 0, 0), 1.0), scaled), InvalidInput);
}

}  // namespace
}  // namespace impact
