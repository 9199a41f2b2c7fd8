// SPDX-License-Identifier: MIT
// Small test scenes for the cloth collision step: layers of grid cloth, moving quads as obstacles.
#pragma once

#include "impact/cloth/collision_step.hpp"
#include "impact/geometry/mesh_generators.hpp"

#include <random>
#include <vector>

namespace cloth_test {

/// K stacked copies of an n x n grid of side 1 at heights z[k] (one cloth with K components).
template <class S>
impact::TriangleMesh<S> layers(int n, const std::vector<double>& z) {
  const auto g = impact::make_grid<S>(n, n, S(1));
  impact::TriangleMesh<S> m;
  const auto nv = g.V.rows(), nf = g.F.rows();
  const auto K = static_cast<Eigen::Index>(z.size());
  m.V.resize(K * nv, 3);
  m.F.resize(K * nf, 3);
  for (Eigen::Index k = 0; k < K; ++k) {
    m.V.middleRows(k * nv, nv) = g.V;
    m.V.middleRows(k * nv, nv).col(2).array() += S(z[std::size_t(k)]);
    m.F.middleRows(k * nf, nf) = g.F.array() + int(k * nv);
  }
  return m;
}

/// A horizontal square (two triangles) of half-side r at height z.
template <class S>
impact::Vertices<S> quad(double r, double z) {
  impact::Vertices<S> V(4, 3);
  V << S(-r), S(-r), S(z), S(r), S(-r), S(z), S(r), S(r), S(z), S(-r), S(r), S(z);
  return V;
}
inline impact::Faces quad_faces() { return (impact::Faces(2, 3) << 0, 1, 2, 0, 2, 3).finished(); }

}  // namespace cloth_test
