// SPDX-License-Identifier: MIT
/// \file
/// Oriented bounding boxes of point sets and triangle sets: the axes are the eigenvectors of a
/// covariance matrix (Gottschalk, Lin, Manocha 1996, "OBBTree"), the extents the range of the
/// points' projections on them. Where the coordinate axes give a clearly smaller box (volume
/// below 3/4 of the covariance box's), fit_obb keeps them instead: the covariance of a box-shaped
/// set (the walls and floor of a room, an axis-aligned crate) can point its main axis along a
/// diagonal and fit a box much larger than the axis-aligned one. On env/rob (1,000 poses of
/// impact-collide-bench) this takes the boolean query from 89.5 to 66.9 node tests on average and
/// the all-pairs query from 499 to 450; on bunny/bunny from 44.9 to 40.5 and 3,686 to 3,654.
///  - TriangleArea (default for meshes): the covariance of the triangles' surfaces, each triangle
///    weighted by its area (the continuous second moment). Vertices packed densely on one side of
///    a mesh do not pull the axes towards them, as they do with the vertex covariance.
///  - Points: the covariance of the points themselves.
///
/// Contract: the returned box {center + axes h : |h_i| <= half_i} and the ball of `radius` about
/// `center` each contain every input point, exactly, for the stored (rounded) centre, axes and extents: the extents are measured after the
/// centre and axes are rounded to S, in double, and padded by a bound of what that rounding and
/// the axes' departure from orthonormality can hide. Degenerate inputs (one point, coincident,
/// collinear or coplanar points, zero-area triangles) give a finite box with some zero extents.
/// Time O(n); a 3 x 3 symmetric eigen-decomposition per box.
#pragma once

#include "impact/core/next_float.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/obb.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact {

/// How fit_obb chooses the axes.
enum class ObbFit {
  TriangleArea,  ///< points are consecutive triangle triples (a, b, c): area-weighted surface covariance
  Points         ///< covariance of the points
};

namespace detail {

/// Orthonormal, right-handed axes from the covariance C (double). Eigenvectors by decreasing
/// eigenvalue; a zero or isotropic covariance keeps the coordinate axes.
inline Eigen::Matrix3d covariance_axes(const Eigen::Matrix3d& C) {
  if (!(C.cwiseAbs().maxCoeff() > 0.0) || !all_finite(C)) return Eigen::Matrix3d::Identity();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(C);  // closed form: the axes need not be accurate, only orthonormal (re-done below)
  if (es.info() != Eigen::Success) return Eigen::Matrix3d::Identity();
  // Eigen sorts eigenvalues in increasing order: the main axis is the last column.
  Eigen::Vector3d x = es.eigenvectors().col(2), y = es.eigenvectors().col(1);
  if (!(x.norm() > 0.5)) return Eigen::Matrix3d::Identity();
  x.normalize();
  y -= x.dot(y) * x;  // Gram-Schmidt: the solver's vectors are orthonormal only to rounding
  if (!(y.norm() > 0.5)) {
    // pick any unit vector orthogonal to x
    const int k = std::abs(x.x()) < 0.6 ? 0 : (std::abs(x.y()) < 0.6 ? 1 : 2);
    y = Eigen::Vector3d::Unit(k) - x[k] * x;
  }
  y.normalize();
  Eigen::Matrix3d A;
  A.col(0) = x;
  A.col(1) = y;
  A.col(2) = x.cross(y).normalized();
  return A;
}

/// Covariance of n points about a reference point (their first), in double.
template <class S> Eigen::Matrix3d point_covariance(const Vec3<S>* pts, std::size_t n) {
  const Eigen::Vector3d ref = pts[0].template cast<double>();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[i].template cast<double>() - ref;
    sum += d;
    sq += d * d.transpose();
  }
  const double inv = 1.0 / double(n);
  const Eigen::Vector3d mean = sum * inv;
  return sq * inv - mean * mean.transpose();
}

/// Area-weighted covariance of the surfaces of n / 3 triangles (consecutive triples). The second
/// moment of a triangle (a, b, c) of area A and centroid m is A / 12 (9 m m^T + a a^T + b b^T +
/// c c^T). Returns false when the total area is zero (then the caller uses the points).
template <class S> bool triangle_covariance(const Vec3<S>* pts, std::size_t n, Eigen::Matrix3d& C) {
  const Eigen::Vector3d ref = pts[0].template cast<double>();
  double area = 0.0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i + 2 < n; i += 3) {
    const Eigen::Vector3d a = pts[i].template cast<double>() - ref, b = pts[i + 1].template cast<double>() - ref,
                          c = pts[i + 2].template cast<double>() - ref;
    const double w = 0.5 * (b - a).cross(c - a).norm();
    const Eigen::Vector3d m = (a + b + c) / 3.0;
    area += w;
    first += w * m;
    second += (w / 12.0) * (9.0 * m * m.transpose() + a * a.transpose() + b * b.transpose() + c * c.transpose());
  }
  if (!(area > 0.0)) return false;
  const Eigen::Vector3d mean = first / area;
  C = second / area - mean * mean.transpose();
  return true;
}

}  // namespace detail

namespace detail {
/// fit_obb_with_axes once the range [lo, hi] of the points' projections A^T (p - ref) on the axes
/// is known (ref: the first point; n > 0).
template <class S>
Obb<S> fit_obb_in_range(const Vec3<S>* pts, std::size_t n, const Mat3<S>& axes, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Obb<S> box;
  box.axes = axes;
  const Eigen::Matrix3d A = axes.template cast<double>();
  const Eigen::Vector3d ref = pts[0].template cast<double>();
  box.center = (ref + A * ((lo + hi) * 0.5)).template cast<S>();
  // Extents measured from the stored centre along the stored axes.
  const Eigen::Vector3d c = box.center.template cast<double>();
  Eigen::Vector3d ext = Eigen::Vector3d::Zero();
  double reach = 0.0, r2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[i].template cast<double>() - c;
    ext = ext.cwiseMax((A.transpose() * d).cwiseAbs());
    reach = std::max(reach, d.cwiseAbs().maxCoeff());
    r2 = std::max(r2, d.squaredNorm());
  }
  // The box is {c + A h}: a point p has h = A^-1 (p - c), which differs from the computed A^T (p -
  // c) by at most |A^T A - I| |p - c| (the axes are orthonormal to a few ulps of S) plus the
  // double rounding of the projection (a few ulps of double of |p - c| and of the coordinates).
  // The last term also covers the rounding of the centre to S: c is read back from the stored S
  // centre, but GCC 12's vectoriser can fold a double -> float -> double round trip (seen at -O2
  // on x86-64: the unrounded double was used), so the bound does not rely on that read.
  const double orth = (A.transpose() * A - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double eps_d = std::numeric_limits<double>::epsilon();
  const double eps_s = static_cast<double>(std::numeric_limits<S>::epsilon());
  const double pad = (3.0 * orth + 16.0 * eps_d) * 3.0 * reach + (eps_s + 16.0 * eps_d) * c.cwiseAbs().maxCoeff() +
                     std::numeric_limits<double>::denorm_min();
  const auto round_up = [](double e) {
    S s = static_cast<S>(e);
    if (double(s) < e) s = next_up(s);
    return s;
  };
  for (int k = 0; k < 3; ++k) box.half[k] = round_up(ext[k] + pad);
  // The ball about the stored centre: |p - c| is within a few ulps of double of the computed
  // sqrt(r2) (each d exact to 1 ulp of |d|, the sum of squares and the root to a few more), and c
  // may be the unrounded double centre (see above): the distance to the stored one differs by at
  // most the centre's rounding, sqrt(3) ulps of S of its largest coordinate.
  box.radius = round_up(std::sqrt(r2) * (1.0 + 8.0 * eps_d) + 2.0 * (eps_s + 16.0 * eps_d) * c.cwiseAbs().maxCoeff() +
                        std::numeric_limits<double>::denorm_min());
  return box;
}
}  // namespace detail

/// The box with the given axes (columns, orthonormal to rounding) that holds the n points, its
/// centre in the middle of the points' projections. Contains every point exactly (see the file
/// comment). n == 0 gives an empty box (negative extents).
template <class S> Obb<S> fit_obb_with_axes(const Vec3<S>* pts, std::size_t n, const Mat3<S>& axes) {
  if (n == 0) {
    Obb<S> box;
    box.axes = axes;
    box.half = Vec3<S>::Constant(S(-1));
    return box;
  }
  const Eigen::Matrix3d A = axes.template cast<double>();
  const Eigen::Vector3d ref = pts[0].template cast<double>();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d h = A.transpose() * (pts[i].template cast<double>() - ref);
    lo = lo.cwiseMin(h);
    hi = hi.cwiseMax(h);
  }
  return detail::fit_obb_in_range(pts, n, axes, lo, hi);
}

/// Oriented bounding box of n points (see ObbFit for how the axes are chosen; TriangleArea reads
/// the points as consecutive triangle triples and falls back to the points' covariance when n is
/// not a multiple of 3 or the triangles have no area; the coordinate axes replace them when their
/// box has under 3/4 of the volume, see the file comment). Contains every point exactly. O(n).
template <class S> Obb<S> fit_obb(const Vec3<S>* pts, std::size_t n, ObbFit method = ObbFit::TriangleArea) {
  if (n == 0) return fit_obb_with_axes<S>(pts, 0, Mat3<S>::Identity());
  Eigen::Matrix3d C;
  if (method != ObbFit::TriangleArea || n % 3 != 0 || !detail::triangle_covariance(pts, n, C)) C = detail::point_covariance(pts, n);
  const Mat3<S> axes = detail::covariance_axes(C).template cast<S>();
  // the points' ranges on the covariance axes and on the coordinate axes, in one pass
  const Eigen::Matrix3d A = axes.template cast<double>();
  const Eigen::Vector3d ref = pts[0].template cast<double>();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo, lo_c = lo, hi_c = hi;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = pts[i].template cast<double>() - ref;
    const Eigen::Vector3d h = A.transpose() * d;
    lo = lo.cwiseMin(h);
    hi = hi.cwiseMax(h);
    lo_c = lo_c.cwiseMin(d);
    hi_c = hi_c.cwiseMax(d);
  }
  if ((hi_c - lo_c).prod() < 0.75 * (hi - lo).prod()) return detail::fit_obb_in_range<S>(pts, n, Mat3<S>::Identity(), lo_c, hi_c);
  return detail::fit_obb_in_range(pts, n, axes, lo, hi);
}

/// The eight corners of a box, computed in S (rounded): callers that need containment pad for it.
template <class S> void obb_corners(const Obb<S>& b, Vec3<S> (&out)[8]) {
  for (int k = 0; k < 8; ++k) {
    Vec3<S> h((k & 1) ? b.half[0] : -b.half[0], (k & 2) ? b.half[1] : -b.half[1], (k & 4) ? b.half[2] : -b.half[2]);
    out[k] = b.center + b.axes * h;
  }
}

}  // namespace impact
