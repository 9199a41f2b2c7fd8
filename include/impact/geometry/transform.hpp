// SPDX-License-Identifier: MIT
/// \file
/// RigidTransform: a rotation R and translation t, x -> R x + t. Used to place one mesh relative to
/// another without touching either tree: pair queries take each model's pose and work in the
/// first model's frame with the relative transform pose_a^-1 * pose_b.
#pragma once

#include "impact/core/types.hpp"

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
};

/// Transform that maps coordinates of frame b into frame a, given both poses in a common frame.
template <class S> RigidTransform<S> relative_transform(const RigidTransform<S>& pose_a, const RigidTransform<S>& pose_b) {
  return pose_a.inverse() * pose_b;
}

}  // namespace impact
