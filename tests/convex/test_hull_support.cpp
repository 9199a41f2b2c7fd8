// SPDX-License-Identifier: MIT
// The hull's support function by hill climbing on its edges (convex/convex_hull.hpp) checked
// against a scan of every vertex: the climb's vertex is as far along the direction as the farthest
// vertex (within rounding), for random, axis-aligned and octant-diagonal directions, directions
// with zero components, flat faces where many vertices tie, scaled and translated point sets, float
// and double. The edge graph is checked against the triangles (each edge both ways, nothing else),
// and the queries on hulls against the same queries answered by the vertex scan (the same hull
// with its edge graph removed).
#include "impact/convex/query.hpp"
#include "support/convex_oracle.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

namespace {

using impact::ConvexHull;
using impact::Vertices;
using impact::test::Rng;

template <class S>
using HsV3 = Eigen::Matrix<S, 3, 1>;

/// Points on an ellipsoid (all of them hull vertices) or in a box (most inside), scaled by `scale`
/// and moved by `shift`.
template <class S>
Vertices<S> hs_points(Rng& rng, int n, bool on_surface, double scale, const Eigen::Vector3d& shift) {
  Vertices<S> p(n, 3);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d x = rng.vec(-1, 1);
    if (on_surface) {
      while (x.norm() < 0.1) x = rng.vec(-1, 1);
      x = x.normalized().cwiseProduct(Eigen::Vector3d(1.0, 0.6, 0.8));
    }
    p.row(i) = (scale * x + shift).template cast<S>().transpose();
  }
  return p;
}

/// Directions that stress the climb: random, the coordinate axes, the octant diagonals, with one or
/// two zero components, tiny and huge magnitudes.
template <class S>
std::vector<HsV3<S>> hs_directions(Rng& rng, int n_random) {
  std::vector<HsV3<S>> d;
  for (int i = 0; i < n_random; ++i) d.push_back(rng.vec(-1, 1).template cast<S>());
  for (int a = 0; a < 3; ++a)
    for (S s : {S(-1), S(1)}) d.push_back(s * HsV3<S>::Unit(a));
  for (int o = 0; o < 8; ++o) d.push_back(HsV3<S>((o & 1) ? 1 : -1, (o & 2) ? 1 : -1, (o & 4) ? 1 : -1));
  for (int i = 0; i < 60; ++i) {
    HsV3<S> x = rng.vec(-1, 1).template cast<S>();
    x[i % 3] = S(0);
    if (i % 2) x[(i + 1) % 3] = S(0);
    d.push_back(x);
  }
  d.push_back(HsV3<S>(S(1e-30), S(-2e-30), S(3e-30)));
  d.push_back(HsV3<S>(S(1e20), S(-2e20), S(3e20)));
  return d;
}

/// The climb against the scan: the support point is a vertex of h and no vertex is farther along d
/// by more than rounding (a few ulps of the largest |v_i d_i| sum).
template <class S>
void hs_check_support(const ConvexHull<S>& h, const std::vector<HsV3<S>>& dirs) {
  for (const HsV3<S>& d : dirs) {
    const HsV3<S> s = impact::support(h, d);
    bool is_vertex = false;
    S best = -std::numeric_limits<S>::infinity(), mag = S(0);
    for (Eigen::Index i = 0; i < h.vertices.rows(); ++i) {
      const HsV3<S> v = h.vertices.row(i).transpose();
      is_vertex = is_vertex || v == s;
      best = std::max(best, v.dot(d));
      mag = std::max(mag, v.cwiseAbs().dot(d.cwiseAbs()));
    }
    EXPECT_TRUE(is_vertex) << "support is not a hull vertex";
    EXPECT_GE(s.dot(d), best - S(8) * std::numeric_limits<S>::epsilon() * mag) << "direction " << d.transpose() << ": a farther vertex exists";
  }
}

template <class S>
void hs_random_hulls() {
  Rng rng(std::is_same_v<S, float> ? 71 : 72);
  const int n_dirs = IMPACT_TEST_SANITIZED ? 300 : 2000;
  for (int n : {12, 13, 20, 40, 100, 400}) {
    for (int surface = 0; surface < 2; ++surface) {
      for (const auto& [scale, shift] : {std::pair<double, Eigen::Vector3d>{1.0, Eigen::Vector3d::Zero()},
                                         std::pair<double, Eigen::Vector3d>{1e-3, Eigen::Vector3d(0.2, -0.1, 0.3)},
                                         std::pair<double, Eigen::Vector3d>{1e3, Eigen::Vector3d(-4e3, 2e3, 1e3)}}) {
        const Vertices<S> p = hs_points<S>(rng, n, surface == 1, scale, shift);
        const ConvexHull<S> h = impact::convex_hull(p);
        SCOPED_TRACE(testing::Message() << n << " points, surface " << surface << ", scale " << scale << ", " << h.vertices.rows()
                                        << " vertices");
        if (h.vertices.rows() >= impact::kHullClimbMinVertices) {
          EXPECT_FALSE(h.neighbors.empty());
        } else {
          EXPECT_TRUE(h.neighbors.empty());
        }
        hs_check_support(h, hs_directions<S>(rng, n_dirs));
      }
    }
  }
}

TEST(HullSupport, ClimbFindsTheFarthestVertexDouble) { hs_random_hulls<double>(); }
TEST(HullSupport, ClimbFindsTheFarthestVertexFloat) { hs_random_hulls<float>(); }

// A prism over a regular 48-gon: its caps are flat faces of 48 vertices each, so along +-z all 48
// tie, and along a side normal two do; the climb must end on a farthest one from every start.
template <class S>
void hs_flat_faces() {
  const int m = 48;
  Vertices<S> p(2 * m, 3);
  for (int i = 0; i < m; ++i) {
    const double a = 2 * M_PI * i / m;
    p.row(i) = HsV3<S>(S(std::cos(a)), S(std::sin(a)), S(-0.5)).transpose();
    p.row(m + i) = HsV3<S>(S(std::cos(a)), S(std::sin(a)), S(0.5)).transpose();
  }
  const ConvexHull<S> h = impact::convex_hull(p);
  ASSERT_EQ(h.vertices.rows(), 2 * m);
  ASSERT_FALSE(h.neighbors.empty());
  Rng rng(73);
  std::vector<HsV3<S>> dirs = hs_directions<S>(rng, 500);
  for (int i = 0; i < m; ++i) {
    const double a = 2 * M_PI * (i + 0.5) / m;  // a side face's normal: two vertices tie
    dirs.push_back(HsV3<S>(S(std::cos(a)), S(std::sin(a)), S(0)));
    dirs.push_back(HsV3<S>(S(std::cos(a)), S(std::sin(a)), S(1e-7)));  // nearly a tie with the cap
    dirs.push_back(HsV3<S>(S(1e-7 * std::cos(a)), S(1e-7 * std::sin(a)), S(-1)));
  }
  hs_check_support(h, dirs);
}

TEST(HullSupport, TiesOnFlatFacesDouble) { hs_flat_faces<double>(); }
TEST(HullSupport, TiesOnFlatFacesFloat) { hs_flat_faces<float>(); }

TEST(HullSupport, EdgeGraphIsTheTrianglesEdges) {
  Rng rng(74);
  for (int n : {12, 30, 200}) {
    const ConvexHull<double> h = impact::convex_hull(hs_points<double>(rng, n, true, 1.0, Eigen::Vector3d::Zero()));
    const int nv = static_cast<int>(h.vertices.rows());
    ASSERT_EQ(static_cast<int>(h.neighbor_start.size()), nv + 1);
    std::set<std::pair<int, int>> from_triangles, from_graph;
    for (Eigen::Index t = 0; t < h.triangles.rows(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int u = h.triangles(t, k), w = h.triangles(t, (k + 1) % 3);
        from_triangles.insert({u, w});
        from_triangles.insert({w, u});
      }
    for (int v = 0; v < nv; ++v) {
      EXPECT_GE(h.neighbor_start[static_cast<std::size_t>(v) + 1] - h.neighbor_start[static_cast<std::size_t>(v)], 3);
      for (int k = h.neighbor_start[static_cast<std::size_t>(v)]; k < h.neighbor_start[static_cast<std::size_t>(v) + 1]; ++k)
        EXPECT_TRUE(from_graph.insert({v, h.neighbors[static_cast<std::size_t>(k)]}).second) << "neighbour listed twice";
    }
    EXPECT_EQ(from_graph, from_triangles);
    for (int o = 0; o < 8; ++o) {
      const Eigen::Vector3d d((o & 1) ? 1 : -1, (o & 2) ? 1 : -1, (o & 4) ? 1 : -1);
      EXPECT_DOUBLE_EQ(h.vertices.row(h.octant_vertex[static_cast<std::size_t>(o)]).dot(d), (h.vertices * d).maxCoeff());
    }
  }
  // under the threshold: no graph, the scan answers
  const ConvexHull<double> small = impact::convex_hull(hs_points<double>(rng, impact::kHullClimbMinVertices - 1, true, 1.0, Eigen::Vector3d::Zero()));
  EXPECT_TRUE(small.neighbors.empty());
  EXPECT_TRUE(small.neighbor_start.empty());
  hs_check_support(small, hs_directions<double>(rng, 200));
}

/// The queries on hulls with the climb against the same queries on a copy of the hulls without
/// the edge graph (the vertex scan): the same booleans where the pair is clear of touching, and
/// depths, normals and distances within the solvers' tolerance.
template <class S, class A>
void hs_queries_match_scan(const A& a, const ConvexHull<S>& hull, int n_poses, std::uint64_t seed, S tol) {
  ConvexHull<S> scan = hull;
  scan.neighbors.clear();
  scan.neighbor_start.clear();
  const double reach = 0.9 * double(impact::shape_size(a) + impact::shape_size(hull));
  const auto poses = impact::test::convex_poses(n_poses, reach, seed);
  const S size = std::max(impact::shape_size(a), impact::shape_size(hull));
  int hits = 0, separated = 0;
  for (const auto& [pa_d, pb_d] : poses) {
    const impact::RigidTransform<S> pa = pa_d.template cast<S>(), pb = pb_d.template cast<S>();
    const auto d0 = impact::convex_distance(a, pa, scan, pb), d1 = impact::convex_distance(a, pa, hull, pb);
    const auto c0 = impact::convex_penetration(a, pa, scan, pb), c1 = impact::convex_penetration(a, pa, hull, pb);
    const bool b1 = impact::convex_intersect(a, pa, hull, pb);
    if (!d0.intersecting && d0.distance > tol * size) {
      ++separated;
      EXPECT_FALSE(d1.intersecting);
      EXPECT_FALSE(b1);
      EXPECT_FALSE(c1.intersecting);
      EXPECT_NEAR(d1.distance, d0.distance, tol * size);
    }
    if (c0.intersecting && c0.depth > tol * size) {
      ++hits;
      EXPECT_TRUE(c1.intersecting);
      EXPECT_TRUE(b1);
      EXPECT_TRUE(d1.intersecting);
      EXPECT_NEAR(c1.depth, c0.depth, tol * size);
    }
  }
  EXPECT_GT(hits, n_poses / 10);
  EXPECT_GT(separated, n_poses / 10);
}

template <class S>
void hs_queries() {
  Rng rng(75);
  const int n_poses = IMPACT_TEST_SANITIZED ? 60 : 400;
  const S tol = std::is_same_v<S, float> ? S(2e-3) : S(1e-8);
  const ConvexHull<S> hull = impact::convex_hull(hs_points<S>(rng, 40, true, 0.5, Eigen::Vector3d::Zero()));
  const ConvexHull<S> other = impact::convex_hull(hs_points<S>(rng, 100, false, 0.4, Eigen::Vector3d(0.05, 0, 0)));
  ASSERT_FALSE(hull.neighbors.empty());
  ASSERT_FALSE(other.neighbors.empty());
  hs_queries_match_scan(other, hull, n_poses, 1, tol);
  hs_queries_match_scan(impact::Box<S>(HsV3<S>(S(0.4), S(0.3), S(0.5))), hull, n_poses, 2, tol);
  hs_queries_match_scan(impact::Sphere<S>(HsV3<S>::Zero(), S(0.5)), hull, n_poses, 3, tol);
  hs_queries_match_scan(impact::Capsule<S>(S(0.3), S(0.6)), hull, n_poses, 4, tol);
  hs_queries_match_scan(impact::Cylinder<S>(S(0.4), S(0.5)), hull, n_poses, 5, tol);
  hs_queries_match_scan(impact::Cone<S>(S(0.5), S(0.6)), hull, n_poses, 6, tol);
}

TEST(HullSupport, QueriesMatchTheVertexScanDouble) { hs_queries<double>(); }
TEST(HullSupport, QueriesMatchTheVertexScanFloat) { hs_queries<float>(); }

}  // namespace
