// SPDX-License-Identifier: MIT
/// \file
/// Ray and Segment. A ray is origin + s * direction for s in [0, t_max]; a particle's step from x to
/// x + v dt is the ray (x, v dt) with t_max = 1, so its hit parameter is the fraction of the step.
#pragma once

#include "impact/core/types.hpp"
#include "impact/core/validate.hpp"

namespace impact {

template <class S> struct Ray {
  Vec3<S> origin = Vec3<S>::Zero();
  Vec3<S> direction = Vec3<S>::UnitX();  ///< need not be unit length
  S t_max = std::numeric_limits<S>::infinity();

  Ray() = default;
  Ray(const Vec3<S>& o, const Vec3<S>& d, S tmax = std::numeric_limits<S>::infinity()) : origin(o), direction(d), t_max(tmax) {}
  Vec3<S> at(S s) const { return origin + s * direction; }
};

/// Throws InvalidInput unless `ray` is a query the ray casts can answer: origin and direction
/// finite and within CoordinateRange (core/validate.hpp), the direction's largest component at
/// least CoordinateRange::min_scale (so not zero), and t_max >= 0 (+infinity allowed; NaN
/// rejected). Run once per public query.
template <class S> void validate_ray(const Ray<S>& ray, const char* where, const char* name = "ray") {
  // the common case without building a message (the ray casts call this once per ray)
  if (IMPACT_LIKELY(all_finite(ray.origin) && all_finite(ray.direction) && ray.origin.cwiseAbs().maxCoeff() <= CoordinateRange<S>::max &&
                    ray.direction.cwiseAbs().maxCoeff() <= CoordinateRange<S>::max &&
                    ray.direction.cwiseAbs().maxCoeff() >= CoordinateRange<S>::min_scale && ray.t_max >= S(0)))
    return;
  const std::string n(name);
  validate_coordinates(ray.origin, where, (n + ".origin").c_str());
  validate_coordinates(ray.direction, where, (n + ".direction").c_str());
  require(ray.direction != Vec3<S>::Zero(), where, n + ".direction must be non-zero");
  require(ray.direction.cwiseAbs().maxCoeff() >= CoordinateRange<S>::min_scale, where,
          n + ".direction is too short: its largest component must be at least " + detail::to_text(CoordinateRange<S>::min_scale) +
              " (CoordinateRange, core/validate.hpp)");
  validate_nonnegative_or_inf(ray.t_max, where, (n + ".t_max").c_str());
}

/// The closed segment from p to q.
template <class S> struct Segment {
  Vec3<S> p = Vec3<S>::Zero(), q = Vec3<S>::Zero();
  Segment() = default;
  Segment(const Vec3<S>& p_, const Vec3<S>& q_) : p(p_), q(q_) {}
  Vec3<S> at(S s) const { return p + s * (q - p); }
};

}  // namespace impact
