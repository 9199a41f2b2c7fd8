// SPDX-License-Identifier: MIT
/// \file
/// RigidTransform: a rotation R and translation t, x -> R x + t. Used to place one mesh relative to
/// another without touching either tree: pair queries take each model's pose and work in the
/// first model's frame with the relative transform pose_a^-1 * pose_b.
#pragma once

#include "impact/core/types.hpp"
#include "impact/core/validate.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace impact {

template <class S> struct RigidTransform {
  Mat3<S> R = Mat3<S>::Identity();  ///< rotation (orthonormal, det +1)
  Vec3<S> t = Vec3<S>::Zero();      ///< translation

  RigidTransform() = default;
  RigidTransform(const Mat3<S>& rotation, const Vec3<S>& translation) : R(rotation), t(translation) {}
  /// From an Eigen isometry (its linear part must be a rotation).
  explicit RigidTransform(const Eigen::Transform<S, 3, Eigen::Isometry>& iso) : R(iso.linear()), t(iso.translation()) {}

  static RigidTransform identity() { return {}; }

  /// R p + t.
  Vec3<S> apply(const Vec3<S>& p) const { return R * p + t; }
  /// R v (directions ignore translation).
  Vec3<S> rotate(const Vec3<S>& v) const { return R * v; }
  /// The inverse transform: x -> R^T (x - t).
  RigidTransform inverse() const { return {R.transpose(), -(R.transpose() * t)}; }
  /// (this * o)(p) = this(o(p)).
  RigidTransform operator*(const RigidTransform& o) const { return {R * o.R, R * o.t + t}; }

  Eigen::Transform<S, 3, Eigen::Isometry> to_isometry() const {
    Eigen::Transform<S, 3, Eigen::Isometry> iso = Eigen::Transform<S, 3, Eigen::Isometry>::Identity();
    iso.linear() = R;
    iso.translation() = t;
    return iso;
  }
  template <class T> RigidTransform<T> cast() const { return {R.template cast<T>(), t.template cast<T>()}; }
  bool is_finite() const { return all_finite(R) && all_finite(t); }
  /// True when R is a rotation within `tol`: every entry of R^T R - I at most tol in magnitude and
  /// det R > 0 (false for NaN entries).
  /// Written out on the columns (R^T R holds their dot products, det R = c0 . (c1 x c2)): every
  /// public query checks its poses, so this is on the path of the cheapest queries.
  bool is_rigid(S tol) const {
    const Vec3<S> c0 = R.col(0), c1 = R.col(1), c2 = R.col(2);
    const auto unit = [tol](S d) { return std::abs(d - S(1)) <= tol; };
    const auto zero = [tol](S d) { return std::abs(d) <= tol; };
    return unit(c0.squaredNorm()) && unit(c1.squaredNorm()) && unit(c2.squaredNorm()) && zero(c0.dot(c1)) && zero(c0.dot(c2)) &&
           zero(c1.dot(c2)) && c0.dot(c1.cross(c2)) > S(0);
  }
};

/// The tolerance of validate_pose on R^T R - I: sqrt(epsilon) for float, 1e-6 for double (so that
/// rotations converted from float pass).
template <class S> inline S rotation_tolerance() { return std::max(std::sqrt(std::numeric_limits<S>::epsilon()), S(1e-6)); }

namespace detail {

/// Words the error of a pose that failed validate_pose's check (kept out of line, so that the
/// check itself stays small enough to inline into every query).
template <class S> [[noreturn]] void reject_pose(const RigidTransform<S>& pose, const char* where, const char* name) {
  if (!pose.is_finite()) {
    std::ostringstream s;
    s << where << ": " << name << " must be finite (R and t have a NaN or infinite entry)";
    throw InvalidInput(s.str());
  }
  validate_coordinates(pose.t, where, (std::string(name) + ".t").c_str());
  std::ostringstream s;
  s << where << ": " << name << ".R must be a rotation (R^T R = I within " << rotation_tolerance<S>() << ", det R > 0)";
  throw InvalidInput(s.str());
}

}  // namespace detail

/// is_rigid(tol) of two poses at once, for the queries that check a pair of poses (every convex
/// query): in double with SSE2 each of the two lanes runs one pose's is_rigid (the same products,
/// sums and comparisons in the same order, so the same answer up to the rounding of the scalar
/// code's contraction into fused multiply-adds where a compiler does that); else the two scalar
/// checks. About half the instructions of the two checks (no shuffles: one lane a pose).
template <class S> bool both_rigid(const RigidTransform<S>& a, const RigidTransform<S>& b, S tol) {
#if defined(__SSE2__)
  if constexpr (std::is_same_v<S, double>) {
    const double* p = a.R.data();  // column-major: c0 = p[0..2], c1 = p[3..5], c2 = p[6..8]
    const double* q = b.R.data();
    const auto pair = [&](int i) { return _mm_loadh_pd(_mm_load_sd(p + i), q + i); };
    const __m128d x0 = pair(0), y0 = pair(1), z0 = pair(2), x1 = pair(3), y1 = pair(4), z1 = pair(5), x2 = pair(6), y2 = pair(7),
                  z2 = pair(8);
    const auto dot = [](__m128d ax, __m128d ay, __m128d az, __m128d bx, __m128d by, __m128d bz) {
      return _mm_add_pd(_mm_add_pd(_mm_mul_pd(ax, bx), _mm_mul_pd(ay, by)), _mm_mul_pd(az, bz));
    };
    const __m128d one = _mm_set1_pd(1.0), limit = _mm_set1_pd(tol);
    const __m128d abs_mask = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
    const auto within = [&](__m128d d) { return _mm_cmple_pd(_mm_and_pd(d, abs_mask), limit); };  // false for NaN
    __m128d ok = _mm_and_pd(within(_mm_sub_pd(dot(x0, y0, z0, x0, y0, z0), one)), within(_mm_sub_pd(dot(x1, y1, z1, x1, y1, z1), one)));
    ok = _mm_and_pd(ok, within(_mm_sub_pd(dot(x2, y2, z2, x2, y2, z2), one)));
    ok = _mm_and_pd(ok, _mm_and_pd(within(dot(x0, y0, z0, x1, y1, z1)), within(dot(x0, y0, z0, x2, y2, z2))));
    ok = _mm_and_pd(ok, within(dot(x1, y1, z1, x2, y2, z2)));
    // det R = c0 . (c1 x c2), the cross product's components as Eigen's cross forms them
    const __m128d cx = _mm_sub_pd(_mm_mul_pd(y1, z2), _mm_mul_pd(z1, y2)), cy = _mm_sub_pd(_mm_mul_pd(z1, x2), _mm_mul_pd(x1, z2)),
                  cz = _mm_sub_pd(_mm_mul_pd(x1, y2), _mm_mul_pd(y1, x2));
    ok = _mm_and_pd(ok, _mm_cmpgt_pd(dot(x0, y0, z0, cx, cy, cz), _mm_setzero_pd()));
    return _mm_movemask_pd(ok) == 3;
  }
#endif
  return a.is_rigid(tol) && b.is_rigid(tol);
}

/// Throws InvalidInput unless `pose` is a rigid transform every query can rely on: R and t finite,
/// t within CoordinateRange (core/validate.hpp), R orthonormal within rotation_tolerance<S>() (each entry of R^T R - I) and det R > 0 (a proper
/// rotation, not a reflection). A scaled or sheared R would make the queries' distances, times and
/// culling wrong without any sign of it, hence the check at every public query (about 40 flops,
/// no message built unless it fails). No NaN or infinity passes: every comparison with NaN is
/// false, an infinite t fails the range and an infinite entry of R makes its column's squared norm
/// infinite or NaN.
template <class S> inline void validate_pose(const RigidTransform<S>& pose, const char* where, const char* name = "pose") {
  constexpr S range = CoordinateRange<S>::max;
  if (IMPACT_LIKELY(std::abs(pose.t.x()) <= range && std::abs(pose.t.y()) <= range && std::abs(pose.t.z()) <= range &&
                    pose.is_rigid(rotation_tolerance<S>())))
    return;
  detail::reject_pose(pose, where, name);
}

/// validate_pose of two poses (`pose_a` named `name_a`, then `pose_b`): the same checks and
/// messages, the rotations checked together (both_rigid) in the common case where both pass.
template <class S>
inline void validate_poses(const RigidTransform<S>& pose_a, const RigidTransform<S>& pose_b, const char* where, const char* name_a,
                           const char* name_b) {
  constexpr S range = CoordinateRange<S>::max;
  const auto in_range = [](const Vec3<S>& t) { return std::abs(t.x()) <= range && std::abs(t.y()) <= range && std::abs(t.z()) <= range; };
  if (IMPACT_LIKELY(in_range(pose_a.t) && in_range(pose_b.t) && both_rigid(pose_a, pose_b, rotation_tolerance<S>()))) return;
  validate_pose(pose_a, where, name_a);  // throws where one fails (both pass where both_rigid's rounding differed)
  validate_pose(pose_b, where, name_b);
}

/// Transform that maps coordinates of frame b into frame a, given both poses in a common frame:
/// pose_a^-1 * pose_b = (Ra^T Rb, Ra^T (tb - ta)). The rotation is the same product as
/// pose_a.inverse() * pose_b's (the same bits); the translation subtracts the poses' translations
/// first, one product instead of two and no cancellation between two large products when both
/// poses are far from the origin and near each other (its error is a few ulps of |tb - ta|, not of
/// |ta| + |tb|). No temporary inverse: every mesh query computes this once, and a query decided at
/// the root pair of its trees costs only a few hundred instructions in all.
template <class S> RigidTransform<S> relative_transform(const RigidTransform<S>& pose_a, const RigidTransform<S>& pose_b) {
  const Mat3<S> at = pose_a.R.transpose();
  return {at * pose_b.R, at * (pose_b.t - pose_a.t)};
}

}  // namespace impact
