// SPDX-License-Identifier: MIT
// next_up and next_down (core/next_float.hpp) against std::nextafter towards +/-infinity, bit for
// bit, in float and double: both zeros, subnormals (the smallest, the largest, the step to the
// normal range), negative values, the largest finite values, infinities, NaN and random bit
// patterns.
#include "impact/core/next_float.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

template <class T>
std::uint64_t next_float_bits(T x) {
  if constexpr (sizeof(T) == 8) {
    std::uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
  } else {
    std::uint32_t b;
    std::memcpy(&b, &x, sizeof b);
    return b;
  }
}

// next_up and next_down of x have the bit pattern of std::nextafter towards +/-infinity.
template <class T>
void expect_like_nextafter(T x) {
  const T inf = std::numeric_limits<T>::infinity();
  EXPECT_EQ(next_float_bits(impact::next_up(x)), next_float_bits(std::nextafter(x, inf))) << x;
  EXPECT_EQ(next_float_bits(impact::next_down(x)), next_float_bits(std::nextafter(x, -inf))) << x;
}

template <class T>
void check_next_float() {
  using L = std::numeric_limits<T>;
  const T special[] = {T(0), -T(0), L::denorm_min(), -L::denorm_min(), T(2) * L::denorm_min(), L::min(), -L::min(),
                       L::min() - L::denorm_min(), -(L::min() - L::denorm_min()), L::min() + L::denorm_min(), T(1), -T(1),
                       T(1) - L::epsilon() / 2, T(0.1), -T(0.1), T(3.5e-3), -T(1e20), L::max(), -L::max(), L::lowest(),
                       L::infinity(), -L::infinity()};
  for (T x : special) expect_like_nextafter(x);
  // the ends of the finite range reach the infinities; the infinities their neighbours
  EXPECT_EQ(impact::next_up(L::max()), L::infinity());
  EXPECT_EQ(impact::next_down(L::lowest()), -L::infinity());
  EXPECT_EQ(impact::next_up(-L::infinity()), L::lowest());
  EXPECT_EQ(impact::next_down(L::infinity()), L::max());
  EXPECT_EQ(impact::next_up(L::infinity()), L::infinity());
  EXPECT_EQ(impact::next_down(-L::infinity()), -L::infinity());
  // from -denorm_min up is -0 (a negative zero), from zero up the smallest subnormal
  EXPECT_TRUE(std::signbit(impact::next_up(-L::denorm_min())) && impact::next_up(-L::denorm_min()) == T(0));
  EXPECT_EQ(impact::next_up(-T(0)), L::denorm_min());
  EXPECT_EQ(impact::next_down(T(0)), -L::denorm_min());
  EXPECT_TRUE(std::isnan(impact::next_up(L::quiet_NaN())));
  EXPECT_TRUE(std::isnan(impact::next_down(L::quiet_NaN())));
  // random bit patterns (every exponent, both signs; every fourth a subnormal), NaNs skipped
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    T x;
    if constexpr (sizeof(T) == 8) {
      std::uint64_t b = rng();
      if (i % 4 == 0) b &= 0x800FFFFFFFFFFFFFull;  // exponent 0
      std::memcpy(&x, &b, sizeof x);
    } else {
      auto b = static_cast<std::uint32_t>(rng());
      if (i % 4 == 0) b &= 0x807FFFFFu;
      std::memcpy(&x, &b, sizeof x);
    }
    if (!std::isnan(x)) expect_like_nextafter(x);
  }
}

TEST(NextFloat, DoubleAsNextafter) { check_next_float<double>(); }

TEST(NextFloat, FloatAsNextafter) { check_next_float<float>(); }

}  // namespace
