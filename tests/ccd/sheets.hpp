// SPDX-License-Identifier: MIT
// Grid sheets for the mesh CCD tests (test_mesh_ccd.cpp and its concurrent twin
// test_mesh_ccd_threads.cpp): an n x n sheet of side 1 and a random jitter of its vertices.
#pragma once

#include "impact/core/types.hpp"

#include <random>

namespace impact::test {

template <class S>
struct Sheet {
  Vertices<S> V;
  Faces F;
};

/// An n x n grid sheet in the plane z = z0, side 1, offset by (ox, oy).
template <class S>
Sheet<S> sheet(int n, S z0, S ox = S(0), S oy = S(0)) {
  Sheet<S> m;
  m.V.resize(n * n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) m.V.row(i * n + j) << ox + S(i) / S(n - 1), oy + S(j) / S(n - 1), z0;
  m.F.resize(2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      const int a = i * n + j, b = a + 1, c = a + n, d = c + 1;
      m.F.row(f++) << a, c, b;
      m.F.row(f++) << b, c, d;
    }
  return m;
}

/// V with every coordinate moved by amount times a uniform number in [-1, 1), then z moved by dz.
template <class S, class A, class D>
Vertices<S> jitter(const Vertices<S>& V, std::mt19937& rng, A amount, D dz) {
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Vertices<S> W = V;
  for (Eigen::Index i = 0; i < W.rows(); ++i) {
    for (int k = 0; k < 3; ++k) W(i, k) += S(amount * U(rng));
    W(i, 2) += S(dz);
  }
  return W;
}

}  // namespace impact::test
