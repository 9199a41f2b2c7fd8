// SPDX-License-Identifier: MIT
/// \file
/// The checks every public entry point runs on what it is given, before it reads or writes
/// anything else: finite numbers, signs, counts, and the coordinate range in which the library's
/// constructions are meaningful. Each throws impact::InvalidInput with a message naming the entry
/// point and the argument ("closest_point_on_mesh: options.max_distance must be >= 0, is -1").
/// Poses and rays have their own checks next to their types (validate_pose in
/// geometry/transform.hpp, validate_ray in geometry/ray.hpp), built on these.
///
/// Cost: a few comparisons per argument; entry points run them once per call, never per tree node
/// or per triangle.
#pragma once

#include "impact/core/config.hpp"
#include "impact/core/error.hpp"
#include "impact/core/types.hpp"

#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>

namespace impact {
namespace detail {

/// x as text for a message (shortest general form, 17 digits at most).
template <class T> std::string to_text(const T& x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

/// "where: name must ..., is value" for the message of a rejected scalar.
template <class T> std::string describe_rejected(const char* where, const char* name, const char* rule, const T& value) {
  std::ostringstream s;
  s.precision(17);
  s << where << ": " << name << " must " << rule << ", is " << value;
  return s.str();
}

}  // namespace detail

/// Throws InvalidInput("where: message") unless ok.
inline void require(bool ok, const char* where, const std::string& message) {
  if (!ok) throw InvalidInput(std::string(where) + ": " + message);
}

/// Throws InvalidInput unless x is finite (not NaN, not infinite).
template <class S, std::enable_if_t<std::is_arithmetic_v<S>, int> = 0> void validate_finite(S x, const char* where, const char* name) {
  if (!std::isfinite(x)) throw InvalidInput(detail::describe_rejected(where, name, "be finite", x));
}

/// Throws InvalidInput unless x is finite and x >= 0.
template <class S> void validate_nonnegative(S x, const char* where, const char* name) {
  if (!(x >= S(0)) || !std::isfinite(x)) throw InvalidInput(detail::describe_rejected(where, name, "be finite and >= 0", x));
}

/// Throws InvalidInput unless x is finite and x > 0.
template <class S> void validate_positive(S x, const char* where, const char* name) {
  if (!(x > S(0)) || !std::isfinite(x)) throw InvalidInput(detail::describe_rejected(where, name, "be finite and > 0", x));
}

/// Throws InvalidInput unless x >= 0 (+infinity allowed: "no limit"); NaN is rejected.
template <class S> void validate_nonnegative_or_inf(S x, const char* where, const char* name) {
  if (!(x >= S(0))) throw InvalidInput(detail::describe_rejected(where, name, "be >= 0 (or +infinity)", x));
}

/// Throws InvalidInput unless lo <= n <= hi (integer counts and sizes).
template <class I> void validate_in_range(I n, I lo, I hi, const char* where, const char* name) {
  if (n < lo || n > hi) {
    std::ostringstream r;
    r << "be in [" << lo << ", " << hi << "]";
    throw InvalidInput(detail::describe_rejected(where, name, r.str().c_str(), n));
  }
}

/// Throws InvalidInput unless every component of v is finite.
template <class Derived> void validate_finite(const Eigen::MatrixBase<Derived>& v, const char* where, const char* name) {
  if (!all_finite(v)) {
    std::ostringstream s;
    s.precision(17);
    s << where << ": " << name << " must be finite, is (" << v.transpose() << ")";
    throw InvalidInput(s.str());
  }
}

/// The magnitudes the library's constructions (distances, times of impact, ray parameters,
/// contact points, bounding volumes) are accurate for. Its predicates (narrow/predicates.hpp)
/// are exact for every finite input; its constructions compute products of up to four or five
/// coordinate differences, which must neither overflow nor underflow for the results to keep
/// their relative accuracy. Validated entry points therefore require, and throw InvalidInput
/// otherwise:
///  - every coordinate, translation, radius, extent and position at most `max` in magnitude
///    (double 2^200, about 1.6e60; float 2^28, about 2.7e8: a mesh placed by a pose stays below
///    2^29, differences below 2^30, their fourth powers below float's 2^128);
///  - every mesh whose coordinates are not all zero, and every ray direction, at least
///    `min_scale` in its largest coordinate (double 2^-200, about 6.2e-61; float 2^-28, about
///    3.7e-9): a mesh, or a ray, entirely below that scale would have its squared distances and
///    products underflow.
/// Scaling a valid input by a power of two that keeps it in the range gives the same answers
/// scaled (tests/query/test_scale_range.cpp checks it over the whole range).
template <class S> struct CoordinateRange;
template <> struct CoordinateRange<double> {
  static constexpr double max = 0x1p200;
  static constexpr double min_scale = 0x1p-200;
};
template <> struct CoordinateRange<float> {
  static constexpr float max = 0x1p28f;
  static constexpr float min_scale = 0x1p-28f;
};

/// Throws InvalidInput unless every component of v is finite and at most CoordinateRange::max in
/// magnitude.
template <class Derived> void validate_coordinates(const Eigen::MatrixBase<Derived>& v, const char* where, const char* name) {
  using S = typename Derived::Scalar;
  if (IMPACT_LIKELY(all_finite(v) && (v.size() == 0 || v.cwiseAbs().maxCoeff() <= CoordinateRange<S>::max))) return;
  validate_finite(v, where, name);
  std::ostringstream s;
  s.precision(17);
  s << where << ": " << name << " must be at most " << CoordinateRange<S>::max << " in magnitude (CoordinateRange), is ("
    << v.transpose() << ")";
  throw InvalidInput(s.str());
}

/// Throws InvalidInput unless x is finite, >= 0 and at most CoordinateRange::max (radii, extents).
template <class S> void validate_length(S x, const char* where, const char* name) {
  validate_nonnegative(x, where, name);
  if (x > CoordinateRange<S>::max) {
    std::ostringstream r;
    r << "be at most " << CoordinateRange<S>::max << " (CoordinateRange)";
    throw InvalidInput(detail::describe_rejected(where, name, r.str().c_str(), x));
  }
}

}  // namespace impact
