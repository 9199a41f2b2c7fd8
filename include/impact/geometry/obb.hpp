// SPDX-License-Identifier: MIT
/// \file
/// Obb: an oriented box (centre, orthonormal axes as the columns of a rotation, half extents) and
/// its separating-axis overlap test. An Aabb of one tree seen from another tree's frame is an Obb,
/// so this is also the test behind AABB trees under a relative rigid transform.
#pragma once

#include "impact/core/types.hpp"

#include <cmath>

namespace impact {

template <class S> struct Obb {
  Vec3<S> center = Vec3<S>::Zero();
  Mat3<S> axes = Mat3<S>::Identity();  ///< columns are the box axes (a rotation)
  Vec3<S> half = Vec3<S>::Zero();      ///< half extents along the axes, >= 0
};

/// Separating-axis test of two boxes given in one frame: box A (axes Ra, half extents ea, centre
/// ca) and box B. Conservative in floating point: a small relative padding of |R| guards the
/// edge-edge axes against rounding when edges are nearly parallel, so it never reports a miss for
/// touching or overlapping boxes (it may accept boxes that are apart by a few ulps).
/// `slack` >= 0 is added to every axis's sum of projected radii: callers pass a bound of the
/// rounding in R and tb (see BvTraits<Obb>::overlap), which makes the test conservative for
/// boxes far from the origin too. Complexity: at most 15 axis tests.
template <class S>
inline bool obb_overlap(const Vec3<S>& ea, const Mat3<S>& R, const Vec3<S>& tb, const Vec3<S>& eb, S slack = S(0)) {
  // Everything in A's local frame: B's axes are the columns of R, its centre is tb.
  const S pad = S(64) * std::numeric_limits<S>::epsilon();
  Mat3<S> absR = R.cwiseAbs().array() + pad;
  // A's face axes
  for (int i = 0; i < 3; ++i)
    if (std::abs(tb[i]) > ea[i] + absR.row(i).dot(eb) + slack) return false;
  // B's face axes
  for (int j = 0; j < 3; ++j)
    if (std::abs(R.col(j).dot(tb)) > absR.col(j).dot(ea) + eb[j] + slack) return false;
  // edge-edge axes a_i x b_j
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const S ra = ea[i1] * absR(i2, j) + ea[i2] * absR(i1, j);
      const S rb = eb[j1] * absR(i, j2) + eb[j2] * absR(i, j1);
      const S d = tb[i2] * R(i1, j) - tb[i1] * R(i2, j);
      if (std::abs(d) > ra + rb + slack) return false;
    }
  }
  return true;
}

/// True when the two closed boxes share a point (conservative by a few ulps, see obb_overlap).
template <class S> inline bool overlap(const Obb<S>& a, const Obb<S>& b) {
  const Mat3<S> R = a.axes.transpose() * b.axes;
  const Vec3<S> t = a.axes.transpose() * (b.center - a.center);
  return obb_overlap<S>(a.half, R, t, b.half);
}

}  // namespace impact
