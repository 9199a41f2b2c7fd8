// SPDX-License-Identifier: MIT
// Small deterministic meshes for tests that must not depend on the data folder: random triangle
// soups, n copies of one triangle, and a closed tetrahedron-like blob.
#pragma once

#include "impact/geometry/triangle_mesh.hpp"
#include "support/random.hpp"

namespace impact::test {

/// n random triangles with vertices near random centres in [-extent, extent]^3, each edge about
/// `size` long. Vertices are not shared.
template <class S> TriangleMesh<S> random_soup(int n, std::uint64_t seed, double extent = 1.0, double size = 0.1) {
  Rng rng(seed);
  TriangleMesh<S> m;
  m.V.resize(3 * n, 3);
  m.F.resize(n, 3);
  for (int t = 0; t < n; ++t) {
    const Eigen::Vector3d c = rng.vec(-extent, extent);
    for (int k = 0; k < 3; ++k) {
      m.V.row(3 * t + k) = (c + rng.vec(-size, size)).cast<S>().transpose();
      m.F(t, k) = 3 * t + k;
    }
  }
  return m;
}

/// True when two triangles have the same three vertices, in any order (copies, as the top-down
/// build gathers them in one leaf: bvh/build_top_down.hpp, TriangleCopyOrder).
template <class S> bool same_shape(const Triangle<S>& a, const Triangle<S>& b) {
  const auto in_b = [&](const Vec3<S>& x) { return x == b.a || x == b.b || x == b.c; };
  const auto in_a = [&](const Vec3<S>& x) { return x == a.a || x == a.b || x == a.c; };
  return in_b(a.a) && in_b(a.b) && in_b(a.c) && in_a(b.a) && in_a(b.b) && in_a(b.c);
}

/// n exact copies of the triangle (0, 0, 0), (1, 0, 0), (0, 1, 0), vertices not shared: every
/// node of a hierarchy over them has the same bounds.
template <class S> TriangleMesh<S> coincident_copies(int n) {
  TriangleMesh<S> m;
  m.V.resize(3 * n, 3);
  m.F.resize(n, 3);
  for (int k = 0; k < n; ++k) {
    m.V.row(3 * k) << 0, 0, 0;
    m.V.row(3 * k + 1) << 1, 0, 0;
    m.V.row(3 * k + 2) << 0, 1, 0;
    m.F.row(k) << 3 * k, 3 * k + 1, 3 * k + 2;
  }
  return m;
}

/// n triangles of the kinds that trouble hierarchies, in [-1, 1]^3, vertices not shared, mixed in
/// the order of their index: long slivers (t % 4 == 0: a needle across the box, 1e-6 wide), very
/// unequal sizes (t % 4 == 1: edges 1e-4 to 1 long), coincident centroids (t % 4 == 2: a triangle
/// and its copy turned about their common centroid, two at the same centre), and exact copies
/// of the previous triangle (t % 4 == 3).
template <class S> TriangleMesh<S> degenerate_soup(int n, std::uint64_t seed) {
  Rng rng(seed);
  TriangleMesh<S> m;
  m.V.resize(3 * n, 3);
  m.F.resize(n, 3);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int t = 0; t < n; ++t) {
    Eigen::Vector3d v[3];
    const Eigen::Vector3d c = rng.vec(-0.8, 0.8);
    if (t % 4 == 0) {
      const Eigen::Vector3d e = rng.vec(-1.6, 1.6);
      v[0] = c - 0.5 * e, v[1] = c + 0.5 * e, v[2] = c + Eigen::Vector3d(0, 1e-6, 0);
    } else if (t % 4 == 1) {
      const double size = std::pow(10.0, rng.uniform(-4, 0));
      v[0] = c, v[1] = c + rng.vec(-size, size), v[2] = c + rng.vec(-size, size);
    } else if (t % 4 == 2 && t % 8 == 6) {  // the copy of triangle t - 4 turned about its centroid
      const Eigen::Matrix3d R = Eigen::AngleAxisd(rng.uniform(0.1, 3.0), rng.vec(-1, 1).normalized()).toRotationMatrix();
      for (int k = 0; k < 3; ++k) v[k] = centre + R * (m.V.row(3 * (t - 4) + k).transpose().template cast<double>() - centre);
    } else if (t % 4 == 2) {
      for (auto& x : v) x = c + rng.vec(-0.2, 0.2);
      centre = (v[0] + v[1] + v[2]) / 3.0;
    } else {
      for (int k = 0; k < 3; ++k) v[k] = m.V.row(3 * (t - 1) + k).transpose().template cast<double>();
    }
    for (int k = 0; k < 3; ++k) {
      m.V.row(3 * t + k) = v[k].cast<S>().transpose();
      m.F(t, k) = 3 * t + k;
    }
  }
  return m;
}

}  // namespace impact::test
