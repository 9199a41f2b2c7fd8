// SPDX-License-Identifier: MIT
/// \file
/// next_up and next_down: the neighbouring representable value of a float or double towards
/// +infinity or -infinity, the same value as std::nextafter(x, +/-infinity), computed on the bit
/// pattern instead of calling the C library. The outward rounding of bounding volumes calls them
/// several times per box (ccd/swept_volume.hpp), where libm's nextafter was a function call each.
///
/// For IEEE 754 binary formats the ordered values of one sign are the ordered bit patterns: a
/// positive value's successor is its pattern plus one (the largest finite one's is infinity), a
/// negative value's successor (towards zero) its pattern minus one (-denorm_min's is -0). Both
/// zeros go up to denorm_min. +infinity stays, -infinity goes up to the lowest finite value, and
/// NaN is returned as it is.
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

namespace impact {

namespace detail {
template <class T>
using FloatBits = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
}  // namespace detail

/// The smallest value of T greater than x (std::nextafter(x, +infinity)); +infinity and NaN are
/// returned unchanged.
template <class T>
inline T next_up(T x) {
  static_assert(std::is_floating_point_v<T> && std::numeric_limits<T>::is_iec559 && (sizeof(T) == 4 || sizeof(T) == 8),
                "next_up: IEEE 754 float or double");
  if (!(x < std::numeric_limits<T>::infinity())) return x;  // +infinity, NaN
  if (x == T(0)) return std::numeric_limits<T>::denorm_min();
  detail::FloatBits<T> b;
  std::memcpy(&b, &x, sizeof b);
  if (x > T(0))
    ++b;
  else
    --b;
  std::memcpy(&x, &b, sizeof b);
  return x;
}

/// The largest value of T less than x (std::nextafter(x, -infinity)); -infinity and NaN are
/// returned unchanged.
template <class T>
inline T next_down(T x) {
  return -next_up(-x);
}

}  // namespace impact
