// SPDX-License-Identifier: MIT
/// \file
/// Ray and Segment. A ray is origin + s * direction for s in [0, t_max]; a particle's step from x to
/// x + v dt is the ray (x, v dt) with t_max = 1, so its hit parameter is the fraction of the step.
#pragma once

#include "impact/core/next_float.hpp"
#include "impact/core/types.hpp"
#include "impact/core/validate.hpp"

#include <cmath>
#include <limits>
#include <optional>

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

namespace detail {

/// A cast of a ray whose direction is shorter than CoordinateRange::min_scale in its largest
/// component (`dmax`): the unchecked casts take such rays (a slow particle's leg), whose squared
/// norms and products underflow (a squared norm of 0 meant "no hit" however close the surface
/// was). The ray o + s d, s in [0, t_max], is the same set of points as o + s' (2^k d), s' in
/// [0, t_max 2^-k]: `cast` runs on that ray, with 2^k bringing dmax into [min_scale,
/// 2 min_scale) (exact: a power of two) and t_max 2^-k rounded up when inexact (a t_max below
/// about 2^-148 in double, 2^-5 in float, once 2^k is near its largest), and the hit's t is
/// scaled back (exact), a hit past t_max dropped. Nothing for a zero or NaN direction.
/// `cast(const Ray<S>&)` returns a std::optional of a hit with a member `t`; the hit's other
/// members (point, normal, barycentrics) are those of the same point, left as `cast` made them.
template <class S, class Cast> auto cast_short_ray(const Ray<S>& ray, S dmax, Cast&& cast) -> decltype(cast(ray)) {
  if (!(dmax > S(0)) || !(ray.t_max >= S(0))) return std::nullopt;
  int e = 0;
  (void)std::frexp(dmax, &e);  // dmax = f 2^e, f in [1/2, 1)
  int m = 0;
  (void)std::frexp(CoordinateRange<S>::min_scale, &m);  // min_scale = 2^(m - 1)
  const int k = m - e;  // dmax 2^k = f 2^m, in [min_scale, 2 min_scale)
  Ray<S> scaled(ray.origin, Vec3<S>(std::ldexp(ray.direction[0], k), std::ldexp(ray.direction[1], k), std::ldexp(ray.direction[2], k)),
                std::ldexp(ray.t_max, -k));
  if (std::ldexp(scaled.t_max, k) < ray.t_max) scaled.t_max = next_up(scaled.t_max);
  auto hit = cast(static_cast<const Ray<S>&>(scaled));
  if (!hit) return hit;
  hit->t = std::ldexp(hit->t, k);
  if (hit->t > ray.t_max) return std::nullopt;
  return hit;
}

}  // namespace detail

/// The closed segment from p to q.
template <class S> struct Segment {
  Vec3<S> p = Vec3<S>::Zero(), q = Vec3<S>::Zero();
  Segment() = default;
  Segment(const Vec3<S>& p_, const Vec3<S>& q_) : p(p_), q(q_) {}
  Vec3<S> at(S s) const { return p + s * (q - p); }
};

}  // namespace impact
