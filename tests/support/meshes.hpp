// SPDX-License-Identifier: MIT
// Small deterministic meshes for tests that must not depend on the data folder: random triangle
// soups, and a closed tetrahedron-like blob.
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

}  // namespace impact::test
