// SPDX-License-Identifier: MIT
// Rays aimed exactly at vertices and at points of edges, on every cast path, against an exact
// oracle (issue 14: 0 wrong answers on the bench's edges set). The paths: the scalar watertight
// test over all triangles, MeshBvh (box, sphere and OBB trees), CompactBvh, KdTree, WideBvh (SIMD
// with AVX when the CPU has it, SSE2, the scalar loop) and WideBvh8 (its AVX loop when the CPU has
// it, the loop without). And the per-ray bound of the edge functions' bands that the box and
// sphere MeshBvh casts take from their root against every triangle's band.
// The oracle, written here on the library's exact orientation predicates of points: the segment
// o -> e = o + t_max d (computed exactly in double; a ray where it is not exact is left out)
// crosses the closed triangle abc when o and e are not strictly on one side of its plane, not
// both in it, and the segment's line has no two opposite strict orientations against the edges
// (a line through an edge or a vertex crosses); the first crossing's t in long double. Every path
// must hit exactly when the oracle has a crossing, report a triangle the oracle says is crossed,
// at the oracle's first t (to rounding). Meshes: an icosphere and a torus rounded to a float grid,
// scaled by powers of two (2^-20 to 2^17) and translated, and (with IMPACT_DATA_DIR) the bunny;
// origins near and 2^8 mesh sizes away; grazes at silhouette vertices (a ray through a vertex,
// tangent to a convex surface); float and double. Then watertightness off the grid (double): a
// closed mesh with vertices of full 53-bit mantissas, rays from inside through its vertices and
// edge points hit on every path.
#include "impact/bvh/compact_bvh.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/narrow/predicates.hpp"
#include "impact/query/kd_tree.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/ray_wide_bvh.hpp"
#include "support/data.hpp"
#include "support/obj_reader.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace impact {
namespace {

constexpr int kExactEdgeSamples = IMPACT_TEST_SANITIZED ? 4 : 1;

template <class S> class RayExactEdges : public ::testing::Test {};
using RayExactEdgeScalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(RayExactEdges, RayExactEdgeScalars);

/// The oracle's verdict on one triangle: crossed or not (exact), and where (a fraction of the
/// segment, long double).
template <class S> bool oracle_crosses(const Triangle<S>& tri, const Vec3<double>& o, const Vec3<double>& e, long double& at) {
  const Vec3<double> a = tri.a.template cast<double>(), b = tri.b.template cast<double>(), c = tri.c.template cast<double>();
  const int so = orient3d(a, b, c, o), se = orient3d(a, b, c, e);
  if ((so == se && so != 0) || (so == 0 && se == 0)) return false;
  const int s0 = orient3d(o, e, a, b), s1 = orient3d(o, e, b, c), s2 = orient3d(o, e, c, a);
  if ((s0 < 0 || s1 < 0 || s2 < 0) && (s0 > 0 || s1 > 0 || s2 > 0)) return false;
  using L = long double;
  const Vec3<L> al = a.cast<L>(), ol = o.cast<L>(), n = (b.cast<L>() - al).cross(c.cast<L>() - al);
  at = n.dot(al - ol) / n.dot(e.cast<L>() - ol);
  return true;
}

/// The oracle's first crossing of the segment o -> e: nullopt when none (fraction of the segment).
template <class S> std::optional<long double> oracle_first(const TriangleMesh<S>& m, const Vec3<double>& o, const Vec3<double>& e) {
  const Vec3<double> lo = o.cwiseMin(e), hi = o.cwiseMax(e);
  std::optional<long double> best;
  for (int k = 0; k < m.num_triangles(); ++k) {
    const Triangle<S> t = m.triangle(k);
    const Vec3<double> a = t.a.template cast<double>(), b = t.b.template cast<double>(), c = t.c.template cast<double>();
    if ((a.cwiseMax(b).cwiseMax(c).array() < lo.array()).any() || (a.cwiseMin(b).cwiseMin(c).array() > hi.array()).any()) continue;  // boxes apart
    long double at = 0;
    if (oracle_crosses(t, o, e, at) && (!best || at < *best)) best = at;
  }
  return best;
}

/// A cast path's answer: t and the mesh's triangle (row of F).
template <class S> struct PathHit {
  S t;
  int triangle;
};

/// Every cast path over one mesh, built once.
template <class S> struct AllPaths {
  const TriangleMesh<S>& mesh;
  MeshBvh<Aabb<S>> bvh;
  MeshBvh<Sphere<S>> spheres;
  MeshBvh<Obb<S>> obbs;
  CompactBvh compact;
  KdTree<S> kd;
  WideBvh<S, 4> wide;
  WideBvh<S, 8> wide8;
  explicit AllPaths(const TriangleMesh<S>& m) : mesh(m), bvh(m), spheres(m), obbs(m), compact(bvh.tree()), kd(m), wide(m), wide8(m) {}

  std::vector<std::pair<std::string, std::function<std::optional<PathHit<S>>(const Ray<S>&)>>> paths() const {
    using R = std::optional<PathHit<S>>;
    const RigidTransform<S>* const kNoPose = nullptr;
    auto from = [](const auto& h) { return h ? R(PathHit<S>{h->t, h->triangle}) : R(); };
    return {
        {"scalar", [this](const Ray<S>& ray) {
           const PreparedRay<S> pr(ray);
           R best;
           for (int k = 0; k < mesh.num_triangles(); ++k) {
             const auto h = detail::ray_mesh_triangle_hit(pr, mesh.triangle(k));
             if (h && (!best || h->t < best->t)) best = PathHit<S>{h->t, k};
           }
           return best;
         }},
        {"MeshBvh", [this, from](const Ray<S>& ray) { return from(ray_mesh_first_hit(bvh, ray)); }},
        {"MeshBvh sphere", [this, from](const Ray<S>& ray) { return from(ray_mesh_first_hit(spheres, ray)); }},
        {"MeshBvh OBB", [this, from](const Ray<S>& ray) { return from(ray_mesh_first_hit(obbs, ray)); }},
        {"CompactBvh", [this, from](const Ray<S>& ray) { return from(ray_mesh_first_hit(bvh, compact, ray)); }},
        {"KdTree", [this, from](const Ray<S>& ray) { return from(kd.first_hit(ray)); }},
        {"WideBvh", [this, from](const Ray<S>& ray) { return from(ray_mesh_first_hit(wide, ray)); }},
        {"WideBvh SSE2", [this, from, kNoPose](const Ray<S>& ray) { return from(detail::ray_wide_first_hit_unchecked(wide, ray, kNoPose, nullptr, true, false)); }},
        {"WideBvh scalar", [this, from, kNoPose](const Ray<S>& ray) { return from(detail::ray_wide_first_hit_unchecked(wide, ray, kNoPose, nullptr, false)); }},
        {"WideBvh8", [this, from](const Ray<S>& ray) { return from(ray_mesh_first_hit(wide8, ray)); }},
        {"WideBvh8 no AVX", [this, from, kNoPose](const Ray<S>& ray) { return from(detail::ray_wide_first_hit_unchecked(wide8, ray, kNoPose, nullptr, true, false)); }},
    };
  }
};

/// Checks every path on the ray (o, d, t_max) against the oracle; false (nothing checked) when
/// o + t_max d is not exact in double. `crossings` counts the rays the oracle has crossing.
template <class S> bool check_ray(const AllPaths<S>& all, const Ray<S>& ray, int& crossings, const char* what) {
  const Vec3<double> o = ray.origin.template cast<double>(), d = ray.direction.template cast<double>();
  Vec3<double> e;
  for (int k = 0; k < 3; ++k) {
    double x, y;
    detail::expansion::two_sum(o[k], double(ray.t_max) * d[k], x, y);  // (t_max: a power of two)
    if (y != 0.0) return false;
    e[k] = x;
  }
  const auto ref = oracle_first(all.mesh, o, e);
  crossings += ref ? 1 : 0;
  const double tol = std::is_same_v<S, float> ? 1e-4 : 1e-9;
  for (const auto& [name, cast] : all.paths()) {
    const auto h = cast(ray);
    EXPECT_EQ(h.has_value(), ref.has_value()) << name << ", " << what << ": " << (ref ? "missed" : "extra") << " (o " << o.transpose() << ", d "
                                              << d.transpose() << ")";
    if (!h || !ref) continue;
    long double at = 0;
    EXPECT_TRUE(oracle_crosses(all.mesh.triangle(h->triangle), o, e, at)) << name << ", " << what << ": a triangle the segment does not cross";
    EXPECT_NEAR(double(h->t) / double(ray.t_max), double(*ref), tol) << name << ", " << what << ": not the first crossing";
  }
  return true;
}

/// The mesh rounded to float (the bench's grid), scaled by 2^k and moved by `shift` first.
template <class S> TriangleMesh<S> on_float_grid(const TriangleMesh<double>& m, int k, const Eigen::Vector3d& shift) {
  Vertices<S> v(m.V.rows(), 3);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    for (int c = 0; c < 3; ++c) v(i, c) = S(float(std::ldexp(m.V(i, c), k) + shift[c]));
  return TriangleMesh<S>(v, m.F);
}

/// Rays at the vertices and edge points of `m` (closed), from around it, from far away, and
/// tangent at vertices: every path against the oracle. Returns the rays checked.
template <class S> int check_mesh(const TriangleMesh<S>& m, std::uint64_t seed, int n) {
  const AllPaths<S> all(m);
  test::Rng rng(seed);
  Vec3<S> lo = m.vertex(0), hi = lo;
  for (int i = 1; i < m.num_vertices(); ++i) lo = lo.cwiseMin(m.vertex(i)), hi = hi.cwiseMax(m.vertex(i));
  const double size = double((hi - lo).maxCoeff());
  int checked = 0, crossings = 0, left_out = 0;
  for (int i = 0; i < n; ++i) {
    const int t = static_cast<int>(rng.index(static_cast<std::uint64_t>(m.num_triangles())));
    const int kind = i % 4;  // a vertex, an edge point, a graze at a vertex, a vertex from far away
    const Vec3<S> a = m.vertex(m.F(t, i % 3)), b = m.vertex(m.F(t, (i + 1) % 3));
    Vec3<S> target = a;
    if (kind == 1) {  // a point of the edge: exact in double (a dyadic fraction of it), rounded in float
      const double f = double(1 + rng.index(15)) / 16.0;
      target = (a.template cast<double>() + f * (b - a).template cast<double>()).template cast<S>();
    }
    Eigen::Vector3d offset = rng.vec(-1, 1).normalized() * (kind == 3 ? 256.0 : 1.5) * size;
    if (kind == 2) {  // tangent to the surface at the vertex: perpendicular to its faces' mean normal
      Eigen::Vector3d nrm = Eigen::Vector3d::Zero();
      for (int f = 0; f < m.num_triangles(); ++f)
        for (int c = 0; c < 3; ++c)
          if (m.F(f, c) == m.F(t, i % 3)) nrm += m.triangle(f).normal().template cast<double>();
      offset = offset - offset.dot(nrm.normalized()) * nrm.normalized();
    }
    Vec3<S> o;
    for (int c = 0; c < 3; ++c) o[c] = S(float(double(target[c]) + offset[c]));  // on the float grid
    const Vec3<S> d = target - o;
    if (d.squaredNorm() == S(0)) continue;
    const char* what = kind == 0 ? "vertex" : kind == 1 ? "edge point" : kind == 2 ? "graze at a vertex" : "vertex from far away";
    if (check_ray(all, Ray<S>(o, d, S(2)), crossings, what)) {
      ++checked;
    } else {
      ++left_out;
    }
  }
  EXPECT_LT(left_out, n / 10);
  EXPECT_GT(crossings, checked / 2);  // (grazes at concave vertices may cross nothing)
  return checked;
}

TYPED_TEST(RayExactEdges, GeneratedMeshesOnEveryPathAgainstTheOracle) {
  using S = TypeParam;
  const TriangleMesh<double> shapes[2] = {make_icosphere<double>(1.0, 2), make_torus<double>(1.0, 0.4, 24, 12)};
  int checked = 0;
  std::uint64_t seed = 1;
  for (const auto& shape : shapes)
    for (const int k : {0, -20, 17}) {
      const Eigen::Vector3d shift = k == 0 ? Eigen::Vector3d(0, 0, 0) : Eigen::Vector3d(std::ldexp(3.0, k), -std::ldexp(5.0, k), std::ldexp(1.5, k));
      const TriangleMesh<S> m = on_float_grid<S>(shape, k, shift);
      checked += check_mesh(m, seed++, 240 / kExactEdgeSamples);
    }
  EXPECT_GT(checked, 1000 / kExactEdgeSamples);
}

TYPED_TEST(RayExactEdges, BunnyOnEveryPathAgainstTheOracle) {
  using S = TypeParam;
  IMPACT_REQUIRE_DATA(path, "meshes/stanford-bunny.obj");
  const TriangleMesh<double> bunny = test::read_obj<double>(path);
  // the bench's placement: the box's lower corner moved to D = 1 (a power of two), rounded to float
  Eigen::Vector3d lo = bunny.V.row(0).transpose();
  for (Eigen::Index i = 1; i < bunny.V.rows(); ++i) lo = lo.cwiseMin(Eigen::Vector3d(bunny.V.row(i).transpose()));
  EXPECT_GT(check_mesh(on_float_grid<S>(bunny, 0, Eigen::Vector3d::Constant(1.0) - lo), 77, 120 / kExactEdgeSamples), 90 / kExactEdgeSamples);
}

/// The band bound a MeshBvh cast sets from its tree's root (detail::bound_band_by_tree) is finite
/// and at least every triangle's own computed band (the one intersect_ray_triangle_near_edges
/// compares with), for rays from near and far.
template <class BV, class S> void check_band_bound(const TriangleMesh<S>& m, test::Rng& rng) {
  const MeshBvh<BV> tree(m);
  Vec3<S> lo = m.vertex(0), hi = lo;
  for (int i = 1; i < m.num_vertices(); ++i) lo = lo.cwiseMin(m.vertex(i)), hi = hi.cwiseMax(m.vertex(i));
  const Eigen::Vector3d mid = ((lo + hi) / S(2)).template cast<double>();
  const double size = double((hi - lo).maxCoeff());
  int tight = 0;
  for (int i = 0; i < 40; ++i) {
    const Vec3<S> o = (mid + rng.vec(-1, 1) * (i % 2 ? 256.0 : 0.8) * size).template cast<S>();
    const Vec3<S> d = rng.vec(-1, 1).template cast<S>();
    PreparedRay<S> pr(Ray<S>(o, d, S(1)));
    detail::bound_band_by_tree(pr, tree);
    ASSERT_TRUE(std::isfinite(pr.band)) << BvTraits<BV>::name;
    S largest = S(0);
    for (int k = 0; k < m.num_triangles(); ++k) {
      const Triangle<S> t = m.triangle(k);
      S m_[3][2];
      const Vec3<S>* v[3] = {&t.a, &t.b, &t.c};
      for (int j = 0; j < 3; ++j) detail::edge_magnitudes(pr, Vec3<S>(*v[j] - o), m_[j][0], m_[j][1]);
      for (int j = 0; j < 3; ++j) {  // the edges (b, c), (c, a), (a, b)
        const int p = (j + 2) % 3, q = (j + 1) % 3;
        const S band = detail::edge_band(m_[p][0], m_[p][1], m_[q][0], m_[q][1]);
        EXPECT_LE(band, pr.band) << BvTraits<BV>::name << ", triangle " << k;
        largest = std::max(largest, band);
      }
    }
    tight += pr.band <= S(64) * largest ? 1 : 0;  // a bound, not a vacuous one
  }
  EXPECT_GT(tight, 30) << BvTraits<BV>::name;
}

TYPED_TEST(RayExactEdges, MeshBvhBandBoundFromTheRoot) {
  using S = TypeParam;
  test::Rng rng(5);
  const TriangleMesh<double> shapes[2] = {make_icosphere<double>(1.0, 2), make_torus<double>(1.0, 0.4, 24, 12)};
  for (const auto& shape : shapes)
    for (const int k : {0, -20, 17}) {
      const Eigen::Vector3d shift = k == 0 ? Eigen::Vector3d(0, 0, 0) : Eigen::Vector3d(std::ldexp(3.0, k), -std::ldexp(5.0, k), std::ldexp(1.5, k));
      const TriangleMesh<S> m = on_float_grid<S>(shape, k, shift);
      check_band_bound<Aabb<S>>(m, rng);
      check_band_bound<Sphere<S>>(m, rng);
    }
}

// Off the float grid (double): a closed mesh whose vertices have full 53-bit mantissas, rays from a
// point inside through its vertices and edge midpoints (exact) and on: each crosses the surface,
// so every path hits (no leak at a seam), at the scalar test's t.
TEST(RayExactEdges, WatertightOffTheGrid) {
  test::Rng rng(91);
  TriangleMesh<double> m = make_icosphere<double>(1.0, 2);
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) m.V.row(i) *= rng.uniform(0.9, 1.1);  // star-shaped about the origin
  m.V.rowwise() += Eigen::RowVector3d(0.1234567891234567, -3.3333333333333335, 7.123456789012345);
  const AllPaths<double> all(m);
  const Vec3<double> centre = Vec3<double>(0.1234567891234567, -3.3333333333333335, 7.123456789012345) + rng.vec(-0.05, 0.05);
  int rays = 0;
  for (int i = 0; i < 400 / kExactEdgeSamples; ++i) {
    const int t = static_cast<int>(rng.index(static_cast<std::uint64_t>(m.num_triangles())));
    const Vec3<double> a = m.vertex(m.F(t, i % 3)), b = m.vertex(m.F(t, (i + 1) % 3));
    const Vec3<double> target = i % 2 == 0 ? a : Vec3<double>((a + b) * 0.5);
    const Ray<double> ray(centre, target - centre, 2.0);
    std::optional<double> ref;
    for (const auto& [name, cast] : all.paths()) {
      const auto h = cast(ray);
      ASSERT_TRUE(h.has_value()) << name << ": a ray from inside leaked out at a " << (i % 2 == 0 ? "vertex" : "edge");
      if (!ref) ref = h->t;
      EXPECT_EQ(h->t, *ref) << name;
    }
    ++rays;
  }
  EXPECT_EQ(rays, 400 / kExactEdgeSamples);
}

}  // namespace
}  // namespace impact
