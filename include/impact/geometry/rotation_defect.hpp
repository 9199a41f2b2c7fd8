// SPDX-License-Identifier: MIT
/// \file
/// How far a matrix that passed validate_pose can be from a rotation. validate_pose accepts R with
/// R^T R - I within rotation_tolerance (a rotation rounded to float passes in double), and the
/// narrow phase moves vertices by that very R, so every node test that bounds a moved volume must
/// bound its image under R, a slightly stretched or skewed copy, not under the nearest rotation.
#pragma once

#include "impact/core/types.hpp"

#include <cmath>
#include <limits>

namespace impact {

/// A bound g >= |M^T M - I|_2 that holds for the exact M^T M although it is computed in S: each
/// entry of the computed M^T M - I is within gamma_4 (sum_k |M_ki| |M_kj| + 1) of its value, and
/// the 2-norm is at most the sum of the entries' magnitudes. For M = U (I + F) with U orthonormal
/// and F symmetric (the polar decomposition), |F|_2 <= g when g <= 1/2, so M x lies within
/// g |x| of U x, and every column of M has a norm within g of 1.
template <class S> S rotation_defect_bound(const Mat3<S>& M) {
  constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
  // G is symmetric: its diagonal and twice its upper triangle, from the columns' dot products
  const Vec3<S> c0 = M.col(0), c1 = M.col(1), c2 = M.col(2);
  const S n0 = c0.squaredNorm(), n1 = c1.squaredNorm(), n2 = c2.squaredNorm();
  const S sum = std::abs(n0 - S(1)) + std::abs(n1 - S(1)) + std::abs(n2 - S(1)) +
                S(2) * (std::abs(c0.dot(c1)) + std::abs(c0.dot(c2)) + std::abs(c1.dot(c2)));
  return sum * (S(1) + S(16) * u) + S(16) * u * (n0 + n1 + n2 + S(3));
}

}  // namespace impact
