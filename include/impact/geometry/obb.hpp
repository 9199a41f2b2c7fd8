// SPDX-License-Identifier: MIT
/// \file
/// Obb: an oriented box (centre, orthonormal axes as the columns of a rotation, half extents) and
/// its separating-axis overlap test. An Aabb of one tree seen from another tree's frame is an Obb,
/// so this is also the test behind AABB trees under a relative rigid transform.
#pragma once

#include "impact/core/next_float.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/aabb.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace impact {

template <class S> struct Obb {
  Vec3<S> center = Vec3<S>::Zero();
  Mat3<S> axes = Mat3<S>::Identity();  ///< columns are the box axes (a rotation)
  Vec3<S> half = Vec3<S>::Zero();      ///< half extents along the axes, >= 0
  /// As a bounding volume only: every point the box was fitted around lies within `radius` of
  /// `center` (fit_obb measures it), so the volume bounded is the box cut by that ball, and the
  /// pair tests reject on the two balls before the 15 axes (ObbPairFrame). Infinity (the
  /// default, and for boxes used as shapes) means no ball: the box alone.
  S radius = std::numeric_limits<S>::infinity();
};

/// Separating-axis test of two boxes given in one frame: box A (axes Ra, half extents ea, centre
/// ca) and box B. Conservative in floating point: a small relative padding of |R| guards the
/// edge-edge axes against rounding when edges are nearly parallel, so it never reports a miss for
/// touching or overlapping boxes (it may accept boxes that are apart by a few ulps).
/// `slack` >= 0 is added to every axis's sum of projected radii: callers pass a bound of the
/// rounding in R and tb (see BvTraits<Obb>::overlap), which makes the test conservative for
/// boxes far from the origin too. `axis_pad` >= 0 is added to every |R_ij|: callers whose R is
/// off its true value by up to that much per entry pass it (ObbPairFrame). `cap_a`, `cap_b`
/// (infinite by default) bound each volume's extent on the six face axes, per unit of the axis's
/// length (at most 1 + axis_pad for these axes): a volume that is a box cut by a ball of radius r
/// about its centre extends at most r from it on any unit axis, so on those axes its projected
/// radius is the lesser of the box's and r (Obb::radius; ObbPairFrame passes the padded radii).
/// The edge axes keep the boxes' radii (capping them too cost more than the pairs it rejected).
/// `EdgeAxes` (1 to 3): the edge axes tested are a_i x b_j for i, j < EdgeAxes only. Leaving axes
/// out is conservative (the test may accept more pairs, never reject one that overlaps). fit_obb
/// orders a box's axes by decreasing spread, so for the boxes of a mesh's surface patches axes 0
/// and 1 lie along the patch and 2 is near its normal: with EdgeAxes = 2 the four crossings of
/// the in-plane axes stay, which reject 913 of the 1,032 pairs the nine rejected in the bunny's
/// boolean queries (docs/collide.md), for 4 of the 9 axes' cost.
/// Complexity: at most 6 + EdgeAxes^2 axis tests.
template <class S, int EdgeAxes = 3>
inline bool obb_overlap(const Vec3<S>& ea, const Mat3<S>& R, const Vec3<S>& tb, const Vec3<S>& eb, S slack = S(0), S axis_pad = S(0),
                        S cap_a = std::numeric_limits<S>::infinity(), S cap_b = std::numeric_limits<S>::infinity()) {
  // Everything in A's local frame: B's axes are the columns of R, its centre is tb. Plain scalar
  // arithmetic on copies: Eigen's packets on 3-vectors cost more than they save here.
  const S pad = S(64) * std::numeric_limits<S>::epsilon() + axis_pad;
  const S a[3] = {ea[0], ea[1], ea[2]}, b[3] = {eb[0], eb[1], eb[2]}, t[3] = {tb[0], tb[1], tb[2]};
  S r[3][3], q[3][3];  // R and |R| + pad
  // A's face axes
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      r[i][j] = R(i, j);
      q[i][j] = std::abs(r[i][j]) + pad;
    }
    if (std::abs(t[i]) > a[i] + std::min(q[i][0] * b[0] + q[i][1] * b[1] + q[i][2] * b[2], cap_b) + slack) return false;
  }
  // B's face axes
  for (int j = 0; j < 3; ++j)
    if (std::abs(r[0][j] * t[0] + r[1][j] * t[1] + r[2][j] * t[2]) > std::min(q[0][j] * a[0] + q[1][j] * a[1] + q[2][j] * a[2], cap_a) + b[j] + slack)
      return false;
  // edge-edge axes a_i x b_j
  static_assert(EdgeAxes >= 1 && EdgeAxes <= 3, "obb_overlap: EdgeAxes is 1, 2 or 3");
  for (int i = 0; i < EdgeAxes; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < EdgeAxes; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const S ra = a[i1] * q[i2][j] + a[i2] * q[i1][j];
      const S rb = b[j1] * q[i][j2] + b[j2] * q[i][j1];
      const S d = t[i2] * r[i1][j] - t[i1] * r[i2][j];
      if (std::abs(d) > ra + rb + slack) return false;
    }
  }
  return true;
}

/// The axis-aligned box around an oriented box, rounded outwards: it holds every point centre +
/// axes h, |h_i| <= half_i, of the stored box exactly (the radii |axes| half are grown by a bound of
/// their rounding, each corner moved one float further out). The ray and closest-point queries of
/// OBB trees key their pruning on it (query/ray_mesh.hpp, query/closest_point_mesh.hpp). An empty
/// box (a negative extent) gives an empty Aabb.
template <class S> inline Aabb<S> bounding_aabb(const Obb<S>& b) {
  if ((b.half.array() < S(0)).any()) return Aabb<S>();
  // three non-negative products and two sums: within 3 ulps of the exact radius, below it at worst
  const Vec3<S> r = (b.axes.cwiseAbs() * b.half) * (S(1) + S(8) * std::numeric_limits<S>::epsilon());
  Aabb<S> box;
  for (int i = 0; i < 3; ++i) {
    // fl(c - r) is the float nearest c - r: the next float below it is below c - r (likewise above)
    box.min[i] = next_down(b.center[i] - r[i]);
    box.max[i] = next_up(b.center[i] + r[i]);
  }
  return box;
}

/// True when the line o + t d (t any real) meets the box grown by `margin` + a bound of the
/// rounding of the test, which works in the box's frame: it never returns false for a line that
/// passes within `margin` of the box, or within rounding of it (up to 32 ulps of the sizes
/// involved: the offset |o - centre|, the extents, the centre's coordinates). A zero direction
/// gives the point test. Conservative, not exact: callers use it to reject, never to order.
template <class S> inline bool line_meets_obb(const Vec3<S>& o, const Vec3<S>& d, const Obb<S>& b, S margin = S(0)) {
  const Vec3<S> oc = o - b.center;
  const Vec3<S> lo = b.axes.transpose() * oc, ld = b.axes.transpose() * d;
  const S scale = oc.cwiseAbs().sum() + b.half.sum() + b.center.cwiseAbs().sum() + margin;
  const S pad = margin + S(32) * std::numeric_limits<S>::epsilon() * scale + std::numeric_limits<S>::denorm_min();
  S t0 = -std::numeric_limits<S>::infinity(), t1 = std::numeric_limits<S>::infinity();
  for (int i = 0; i < 3; ++i) {
    const S h = b.half[i] + pad;
    if (ld[i] == S(0)) {
      if (std::abs(lo[i]) > h) return false;
      continue;
    }
    S a = (-h - lo[i]) / ld[i], c = (h - lo[i]) / ld[i];
    if (a > c) std::swap(a, c);
    t0 = a > t0 ? a : t0;
    t1 = c < t1 ? c : t1;
    if (t0 > t1) return false;
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
