// SPDX-License-Identifier: MIT
/// \file
/// ObbSlabs: the extent of a point set along the ten diagonal directions of an oriented box's
/// axes (a_i + a_j, a_i - a_j for the three pairs, a_0 +- a_1 +- a_2), stored with the box it was
/// measured in. With the box's own three face directions that is a 26-sided polytope (a k-DOP
/// in the box's frame) around the points, tighter than the box at its corners and edges. A mesh
/// tree keeps one around the whole mesh (MeshBvh::root_slabs) so that the root pair of two
/// oriented-box trees can also be separated along these directions: the node test of the mesh
/// queries tries them on the root pair only, after the 15 axes of the two boxes fail (the bunny
/// against itself, the bench's 1,000 poses: 504 -> 616 decided at the roots, docs/collide.md).
///
/// The directions are combinations with coefficients -1, 0, 1 of the box's axes, so along each
/// the other box's projection is a sum of entries of R = A^T X B that the 15-axis test has
/// computed already: about a dozen operations per direction and per side, no products.
#pragma once

#include "impact/core/types.hpp"
#include "impact/geometry/obb.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact {

/// The ten diagonal directions, as coefficients of the box's axes (columns of Obb::axes): six
/// with two non-zero coefficients, then four with three.
inline constexpr int kObbSlabDirections = 10;
inline constexpr int kObbSlabCoefficients[kObbSlabDirections][3] = {{1, 1, 0},  {1, -1, 0}, {1, 0, 1},  {1, 0, -1}, {0, 1, 1},
                                                                    {0, 1, -1}, {1, 1, 1},  {1, 1, -1}, {1, -1, 1}, {1, -1, -1}};
/// Non-zero coefficients of direction m (2 or 3): the length of the direction is about the
/// square root of it, and every rounding bound of a per-axis quantity is taken that many times.
constexpr int obb_slab_terms(int m) { return m < 6 ? 2 : 3; }

/// Slabs of a point set along the diagonal directions d_m = sum_i c_mi a_i of a box's axes a_i:
/// every point p had lo[m] <= d_m . (p - center) <= hi[m], for the exact values of the stored
/// axes and centre (the measured values are rounded outwards by a bound of their rounding). The
/// directions are not unit: their lengths are sqrt(2) and sqrt(3) within the axes' rounding.
/// `valid` false (the default, and for trees of other BVs) means no slabs: nothing is separated.
template <class S> struct ObbSlabs {
  Vec3<S> center = Vec3<S>::Zero();
  Mat3<S> axes = Mat3<S>::Identity();
  std::array<S, kObbSlabDirections> lo{}, hi{};
  bool valid = false;
};

/// The slabs of n points (rows of a row-major n x 3 array, as Vertices<S>) in the frame of `box`
/// (its centre and axes; its extents are not used). Conservative: each computed extent is widened
/// by 64 u (2 or 3 terms) (|p|_inf + |c|_inf) (u the unit roundoff; the rounding of p - c, of the
/// three dot products with axes of 1-norm at most sqrt(3) (1 + 4u), and of the sum of two or three
/// of them is below 16 u times that), so the exact d_m . (p - c) lies within [lo, hi]. n = 0 or a
/// non-finite coordinate gives invalid slabs. O(n).
template <class S> ObbSlabs<S> fit_obb_slabs(const Obb<S>& box, const S* points, std::size_t n) {
  ObbSlabs<S> s;
  s.center = box.center;
  s.axes = box.axes;
  if (n == 0) return s;
  constexpr S inf = std::numeric_limits<S>::infinity();
  s.lo.fill(inf);
  s.hi.fill(-inf);
  S scale = 0;  // largest |p|_inf
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3<S> p(points[3 * k], points[3 * k + 1], points[3 * k + 2]);
    if (!p.allFinite()) return ObbSlabs<S>();  // min and max would pass a NaN by
    scale = std::max(scale, p.cwiseAbs().maxCoeff());
    const Vec3<S> q = box.axes.transpose() * (p - box.center);
    for (int m = 0; m < kObbSlabDirections; ++m) {
      const int* c = kObbSlabCoefficients[m];
      const S v = S(c[0]) * q[0] + S(c[1]) * q[1] + S(c[2]) * q[2];
      s.lo[static_cast<std::size_t>(m)] = std::min(s.lo[static_cast<std::size_t>(m)], v);
      s.hi[static_cast<std::size_t>(m)] = std::max(s.hi[static_cast<std::size_t>(m)], v);
    }
  }
  constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
  const S base = S(64) * u * (scale + box.center.cwiseAbs().maxCoeff());
  for (int m = 0; m < kObbSlabDirections; ++m) {
    const S pad = base * S(obb_slab_terms(m)) * (S(1) + S(8) * u);
    s.lo[static_cast<std::size_t>(m)] -= pad;
    s.hi[static_cast<std::size_t>(m)] += pad;
  }
  s.valid = std::isfinite(base) && box.center.allFinite() && box.axes.allFinite();
  return s;
}

/// Separation of two volumes given in A's box frame as the 15-axis test sees them (obb_overlap):
/// A's box (half extents ea) and B's (axes the columns of R, centre tb, half extents eb), each
/// volume's extent on a direction of length L capped by cap * L (its ball), along the diagonal
/// directions of `slabs_a` (A's axes, whose points lie in those slabs; null: none) and of
/// `slabs_b` (B's axes; null: none). `slack` and `axis_pad` as for obb_overlap: bounds of the
/// rounding of every unit axis's projections and of every entry of R; `spread_b` bounds how far
/// the points of B the slabs were measured on have moved from a rigid image (X's defect times
/// B's size). Each of them is taken once per non-zero coefficient of a direction. Conservative:
/// true only when the volumes are apart along one of the directions, the slabs of a volume holding
/// its points. About 15 operations per direction and side, no products beyond R^T tb.
template <class S>
inline bool obb_slabs_separate(const Vec3<S>& ea, const Mat3<S>& R, const Vec3<S>& tb, const Vec3<S>& eb, S slack, S axis_pad, S cap_a,
                               S cap_b, S spread_b, const ObbSlabs<S>* slabs_a, const ObbSlabs<S>* slabs_b) {
  const S pad = S(64) * std::numeric_limits<S>::epsilon() + axis_pad;
  // the directions' lengths, rounded up: sqrt(2), sqrt(3) (the axes are orthonormal within rounding)
  const S up = S(1) + S(64) * std::numeric_limits<S>::epsilon();
  const S len2 = S(1.4142135623730951) * up, len3 = S(1.7320508075688772) * up;
  // Written out direction by direction (kObbSlabCoefficients' order): with the coefficients as
  // data the loops cost about 1,300 instructions a call, written out under 300.
  if (slabs_a) {
    // along d = sum_i c_i a_i: B's centre at sum_i c_i tb_i, its radius sum_j eb_j |sum_i c_i R_ij|
    // (each |R_ij| off by at most pad, each tb_i by slack)
    const Vec3<S> r0 = R.row(0).transpose(), r1 = R.row(1).transpose(), r2 = R.row(2).transpose();
    const S pad_b = pad * eb.sum();
    const S cap2 = cap_b * len2, cap3 = cap_b * len3;
    const S grow2 = S(2) * (pad_b + slack), grow3 = S(3) * (pad_b + slack);
    const auto apart = [&](const Vec3<S>& v, S centre, S cap, S grow, int m) {
      const S rb = std::min(std::abs(v[0]) * eb[0] + std::abs(v[1]) * eb[1] + std::abs(v[2]) * eb[2], cap) + grow;
      const auto k = static_cast<std::size_t>(m);
      return centre - rb > slabs_a->hi[k] || centre + rb < slabs_a->lo[k];
    };
    const Vec3<S> p01 = r0 + r1, m01 = r0 - r1;
    if (apart(p01, tb[0] + tb[1], cap2, grow2, 0) || apart(m01, tb[0] - tb[1], cap2, grow2, 1) ||
        apart(Vec3<S>(r0 + r2), tb[0] + tb[2], cap2, grow2, 2) || apart(Vec3<S>(r0 - r2), tb[0] - tb[2], cap2, grow2, 3) ||
        apart(Vec3<S>(r1 + r2), tb[1] + tb[2], cap2, grow2, 4) || apart(Vec3<S>(r1 - r2), tb[1] - tb[2], cap2, grow2, 5) ||
        apart(Vec3<S>(p01 + r2), tb[0] + tb[1] + tb[2], cap3, grow3, 6) || apart(Vec3<S>(p01 - r2), tb[0] + tb[1] - tb[2], cap3, grow3, 7) ||
        apart(Vec3<S>(m01 + r2), tb[0] - tb[1] + tb[2], cap3, grow3, 8) || apart(Vec3<S>(m01 - r2), tb[0] - tb[1] - tb[2], cap3, grow3, 9))
      return true;
  }
  if (slabs_b) {
    // along e = sum_j c_j b_j (B's axes moved by X): B's centre at sum_j c_j (R^T tb)_j from A's,
    // its points within [lo, hi] of it; A's radius sum_i ea_i |sum_j c_j R_ij|
    const Vec3<S> q0 = R.col(0), q1 = R.col(1), q2 = R.col(2);
    const Vec3<S> s(q0.dot(tb), q1.dot(tb), q2.dot(tb));
    const S pad_a = pad * ea.sum();
    const S cap2 = cap_a * len2, cap3 = cap_a * len3;
    const S grow2 = S(2) * (pad_a + slack + spread_b), grow3 = S(3) * (pad_a + slack + spread_b);
    const auto apart = [&](const Vec3<S>& v, S centre, S cap, S grow, int m) {
      const S ra = std::min(std::abs(v[0]) * ea[0] + std::abs(v[1]) * ea[1] + std::abs(v[2]) * ea[2], cap) + grow;
      const auto k = static_cast<std::size_t>(m);
      return centre + slabs_b->lo[k] > ra || centre + slabs_b->hi[k] < -ra;
    };
    const Vec3<S> p01 = q0 + q1, m01 = q0 - q1;
    if (apart(p01, s[0] + s[1], cap2, grow2, 0) || apart(m01, s[0] - s[1], cap2, grow2, 1) ||
        apart(Vec3<S>(q0 + q2), s[0] + s[2], cap2, grow2, 2) || apart(Vec3<S>(q0 - q2), s[0] - s[2], cap2, grow2, 3) ||
        apart(Vec3<S>(q1 + q2), s[1] + s[2], cap2, grow2, 4) || apart(Vec3<S>(q1 - q2), s[1] - s[2], cap2, grow2, 5) ||
        apart(Vec3<S>(p01 + q2), s[0] + s[1] + s[2], cap3, grow3, 6) || apart(Vec3<S>(p01 - q2), s[0] + s[1] - s[2], cap3, grow3, 7) ||
        apart(Vec3<S>(m01 + q2), s[0] - s[1] + s[2], cap3, grow3, 8) || apart(Vec3<S>(m01 - q2), s[0] - s[1] - s[2], cap3, grow3, 9))
      return true;
  }
  return false;
}

}  // namespace impact
