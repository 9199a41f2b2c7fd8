// SPDX-License-Identifier: MIT
/// \file
/// Ray and Segment. A ray is origin + s * direction for s in [0, t_max]; a particle's step from x to
/// x + v dt is the ray (x, v dt) with t_max = 1, so its hit parameter is the fraction of the step.
#pragma once

#include "impact/core/types.hpp"

namespace impact {

template <class S> struct Ray {
  Vec3<S> origin = Vec3<S>::Zero();
  Vec3<S> direction = Vec3<S>::UnitX();  ///< need not be unit length
  S t_max = std::numeric_limits<S>::infinity();

  Ray() = default;
  Ray(const Vec3<S>& o, const Vec3<S>& d, S tmax = std::numeric_limits<S>::infinity()) : origin(o), direction(d), t_max(tmax) {}
  Vec3<S> at(S s) const { return origin + s * direction; }
};

/// The closed segment from p to q.
template <class S> struct Segment {
  Vec3<S> p = Vec3<S>::Zero(), q = Vec3<S>::Zero();
  Segment() = default;
  Segment(const Vec3<S>& p_, const Vec3<S>& q_) : p(p_), q(q_) {}
  Vec3<S> at(S s) const { return p + s * (q - p); }
};

}  // namespace impact
