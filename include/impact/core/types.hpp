// SPDX-License-Identifier: MIT
/// \file
/// Eigen aliases on the scalar S used throughout the library. Dimension is always 3.
/// Vertex arrays are n x 3 row-major (one vertex per row), face arrays m x 3 row-major int.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <limits>
#include <type_traits>

namespace impact {

template <class S> using Vec3 = Eigen::Matrix<S, 3, 1>;
template <class S> using Vec2 = Eigen::Matrix<S, 2, 1>;
template <class S> using Mat3 = Eigen::Matrix<S, 3, 3>;
/// n x 3 vertex positions, one vertex per row.
template <class S> using Vertices = Eigen::Matrix<S, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// m x 3 triangle vertex indices, one triangle per row.
using Faces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// The scalar types the library is instantiated and tested with.
template <class S> inline constexpr bool is_supported_scalar_v = std::is_same_v<S, float> || std::is_same_v<S, double>;

/// True when every component is finite (no NaN, no infinity).
template <class Derived> inline bool all_finite(const Eigen::MatrixBase<Derived>& m) {
  // x - x is NaN for both NaN and +-inf, 0 otherwise.
  return ((m - m).array() == (m - m).array()).all();
}

}  // namespace impact
