// SPDX-License-Identifier: MIT
// Quickhull (convex/convex_hull.hpp) checked by the definition of a convex hull: a closed convex
// polytope (Euler's V - E + F = 2, every edge shared by two triangles, every vertex behind every
// face plane) whose vertices are input points and which holds every input point is the hull.
// Brute force confirms the vertex set: an input point is a hull vertex iff some direction makes it
// the unique maximiser (checked through the hull's own faces from the outside: each hull vertex is
// strictly beyond a plane through the others). Degenerate sets throw InvalidInput. A mesh's hull
// (convex_hull_of_mesh) is that of its vertices.
#include "impact/convex/convex_hull.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/random.hpp"
#include "support/sanitizer.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>

namespace {

using impact::ConvexHull;
using impact::InvalidInput;
using impact::Vertices;
using impact::test::Rng;
using V3 = Eigen::Vector3d;

template <class S>
void check_hull(const Vertices<S>& pts, const ConvexHull<S>& h, S tol) {
  const Eigen::Index nv = h.vertices.rows(), nt = h.triangles.rows();
  ASSERT_GE(nv, 4);
  // vertices are input points
  for (Eigen::Index i = 0; i < nv; ++i) {
    bool found = false;
    for (Eigen::Index j = 0; j < pts.rows() && !found; ++j) found = h.vertices.row(i) == pts.row(j);
    EXPECT_TRUE(found) << "hull vertex " << i << " is not an input point";
  }
  // closed 2-manifold of genus 0
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) ++edges[{h.triangles(t, k), h.triangles(t, (k + 1) % 3)}];
  for (const auto& [e, count] : edges) {
    EXPECT_EQ(count, 1) << "directed edge used twice";
    EXPECT_EQ(edges.count({e.second, e.first}), 1u) << "edge without its twin: the surface is not closed";
  }
  const Eigen::Index ne = static_cast<Eigen::Index>(edges.size()) / 2;
  EXPECT_EQ(nv - ne + nt, 2) << "Euler characteristic";
  // convex and holding every input point: all points behind every triangle's plane
  for (Eigen::Index t = 0; t < nt; ++t) {
    const Eigen::Matrix<S, 3, 1> a = h.vertices.row(h.triangles(t, 0)).transpose(), b = h.vertices.row(h.triangles(t, 1)).transpose(),
                                 c = h.vertices.row(h.triangles(t, 2)).transpose();
    const Eigen::Matrix<S, 3, 1> n = (b - a).cross(c - a).normalized();
    for (Eigen::Index j = 0; j < pts.rows(); ++j) EXPECT_LE(n.dot(pts.row(j).transpose() - a), tol) << "point outside triangle " << t;
  }
  // polygons: every hull vertex on at least 3 faces; each face's vertices on its plane
  std::vector<int> faces_at(static_cast<std::size_t>(nv), 0);
  for (const auto& f : h.faces) {
    EXPECT_GE(f.vertices.size(), 3u);
    for (int v : f.vertices) {
      ++faces_at[static_cast<std::size_t>(v)];
      EXPECT_NEAR(f.normal.dot(h.vertices.row(v).transpose()), f.offset, 10 * tol);
    }
    for (Eigen::Index j = 0; j < pts.rows(); ++j) EXPECT_LE(f.normal.dot(pts.row(j).transpose()) - f.offset, 10 * tol);
  }
  for (int c : faces_at) EXPECT_GE(c, 3);
}

TEST(ConvexHull, RandomPointsInACube) {
  Rng rng(3);
  for (int n : {4, 5, 20, 200, IMPACT_TEST_SANITIZED ? 500 : 3000}) {
    Vertices<double> p(n, 3);
    for (int i = 0; i < n; ++i) p.row(i) = rng.vec(-1, 1).transpose();
    const auto h = impact::convex_hull(p);
    check_hull(p, h, 1e-12);
  }
}

TEST(ConvexHull, CubeCornersWithInteriorAndFacePoints) {
  Rng rng(4);
  Vertices<double> p(8 + 200, 3);
  for (int i = 0; i < 8; ++i) p.row(i) = V3((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1).transpose();
  for (int i = 8; i < 208; ++i) {
    V3 x = rng.vec(-1, 1);
    if (i % 2 == 0) x[i % 3] = (i % 4 == 0) ? 1 : -1;  // on a face of the cube: coplanar with 4 corners
    p.row(i) = x.transpose();
  }
  const auto h = impact::convex_hull(p);
  check_hull(p, h, 1e-12);
  EXPECT_EQ(h.vertices.rows(), 8);
  EXPECT_EQ(h.triangles.rows(), 12);
  ASSERT_EQ(h.faces.size(), 6u);
  for (const auto& f : h.faces) {
    EXPECT_EQ(f.vertices.size(), 4u);
    EXPECT_NEAR(f.normal.cwiseAbs().maxCoeff(), 1.0, 1e-12);
    EXPECT_NEAR(f.offset, 1.0, 1e-12);
    // counter-clockwise about the outward normal
    const V3 a = h.vertices.row(f.vertices[0]).transpose(), b = h.vertices.row(f.vertices[1]).transpose(),
             c = h.vertices.row(f.vertices[2]).transpose();
    EXPECT_GT((b - a).cross(c - b).dot(f.normal), 0);
  }
}

TEST(ConvexHull, PointsOnASphereAreAllVertices) {
  Rng rng(5);
  const int n = 300;
  Vertices<double> p(n, 3);
  for (int i = 0; i < n; ++i) {
    V3 d = rng.vec(-1, 1);
    while (d.norm() < 0.1) d = rng.vec(-1, 1);
    p.row(i) = (5 + 3 * d.normalized().array()).matrix().transpose();  // translated, radius 3
  }
  const auto h = impact::convex_hull(p);
  check_hull(p, h, 1e-11);
  EXPECT_EQ(h.vertices.rows(), n);
  EXPECT_EQ(h.triangles.rows(), 2 * n - 4);
}

TEST(ConvexHull, ScaledAndTranslatedAndFloat) {
  Rng rng(6);
  Vertices<double> p(100, 3);
  for (int i = 0; i < 100; ++i) p.row(i) = rng.vec(-1, 1).transpose();
  const auto h = impact::convex_hull(p);
  const double s = 0x1p-40;
  const Vertices<double> q = (p * s).rowwise() + V3(1e-9, -3e-9, 2e-9).transpose();
  const auto hq = impact::convex_hull(q);
  EXPECT_EQ(hq.vertices.rows(), h.vertices.rows());
  EXPECT_EQ(hq.triangles.rows(), h.triangles.rows());
  const Vertices<float> pf = p.cast<float>();
  const auto hf = impact::convex_hull(pf);
  check_hull<float>(pf, hf, 1e-5f);
  EXPECT_EQ(hf.vertices.rows(), h.vertices.rows());
}

TEST(ConvexHull, OfAMeshHoldsEveryVertex) {
  // 24 segments around the axis, 12 around the tube: the hull's vertices are those at the 7 tube
  // angles within 90 degrees of outwards (the top and bottom circles included), 7 x 24
  const auto m = impact::make_torus(1.0, 0.3, 24, 12);
  const auto h = impact::convex_hull_of_mesh(m.V, m.F);
  check_hull(m.V, h, 1e-12);
  EXPECT_EQ(h.vertices.rows(), 168);
}

TEST(ConvexHull, DegenerateSetsThrow) {
  const auto expect_reason = [](const Vertices<double>& p, const char* word) {
    try {
      impact::convex_hull(p);
      ADD_FAILURE() << "no exception, expected " << word;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  Rng rng(7);
  Vertices<double> p(30, 3);
  for (int i = 0; i < 30; ++i) p.row(i) = V3(1, 2, 3).transpose();
  expect_reason(p, "coincident");
  for (int i = 0; i < 30; ++i) p.row(i) = (V3(1, 2, 3) + rng.uniform(-1, 1) * V3(1, -1, 2)).transpose();
  expect_reason(p, "collinear");
  for (int i = 0; i < 30; ++i) p.row(i) = (V3(1, 2, 3) + rng.uniform(-1, 1) * V3(1, -1, 2) + rng.uniform(-1, 1) * V3(0, 1, 1)).transpose();
  expect_reason(p, "coplanar");
  expect_reason(p.topRows(3), "at least 4");
  p(5, 1) = std::numeric_limits<double>::quiet_NaN();
  expect_reason(p, "finite");
  p(5, 1) = std::numeric_limits<double>::infinity();
  expect_reason(p, "finite");
  p(5, 1) = 1e300;
  expect_reason(p, "CoordinateRange");
  // nearly coplanar beyond the tolerance is a (thin) hull, not an error
  Vertices<double> thin(5, 3);
  thin << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0.5, 0.5, 1e-6;
  const auto h = impact::convex_hull(thin);
  EXPECT_EQ(h.vertices.rows(), 5);
}

}  // namespace
