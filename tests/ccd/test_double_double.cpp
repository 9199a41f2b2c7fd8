// SPDX-License-Identifier: MIT
// The double-double arithmetic of the CCD re-check against exact integer arithmetic: two_sum and
// two_prod are exact, and +, - and * stay within the relative error 2^-103 that the re-check's
// error bounds assume (detail/double_double.hpp). Operands are integers (a 53-bit head times 2^60
// plus a tail below half its ulp), so every value is an exact integer held in a 320-bit BigInt.
#include "impact/ccd/detail/double_double.hpp"
#include "support/exact_ccd.hpp"
#include "support/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

namespace {

using impact::detail::DoubleDouble;
using impact::test::BigInt;

/// An integer-valued double as a BigInt (exact).
BigInt big(double x) {
  int e = 0;
  const double m = std::frexp(x, &e);  // x = m 2^e, 0.5 <= |m| < 1
  const auto mant = static_cast<std::int64_t>(std::ldexp(m, 53));
  e -= 53;
  if (e >= 0) return BigInt::from(mant).shl(e);
  EXPECT_EQ(mant % (std::int64_t(1) << -e), 0) << "not an integer: " << x;
  return BigInt::from(mant / (std::int64_t(1) << -e));
}
BigInt big(const DoubleDouble& x) { return big(x.hi) + big(x.lo); }

/// A random double-double: head m 2^60 (m of 53 bits), tail of at most 59 bits, random signs.
DoubleDouble random_dd(impact::test::Rng& rng) {
  const auto head = std::int64_t((rng.raw() >> 11) | (std::uint64_t(1) << 52));
  const auto tail = std::int64_t(rng.raw() >> (5 + rng.index(40)));  // below 2^59
  DoubleDouble x(std::ldexp(double(head), 60) * (rng.index(2) ? 1 : -1), double(tail) * (rng.index(2) ? 1 : -1));
  EXPECT_EQ(x.hi + x.lo, x.hi);  // normalised: the tail is below half an ulp of the head
  return x;
}

/// |computed - exact| <= 2^-103 |exact|, checked exactly.
void expect_within_bound(const DoubleDouble& z, const BigInt& exact) {
  const BigInt diff = big(z) - exact;
  const double rough = std::abs(diff.approx()), scale = std::abs(exact.approx());
  ASSERT_LE(rough, std::ldexp(scale, -100)) << "far off";  // keeps the shift below in range
  const BigInt a = diff.negative() ? -diff : diff, b = exact.negative() ? -exact : exact;
  EXPECT_GE((b - a.shl(103)).sign(), 0) << "error above 2^-103 relative";
}

TEST(DoubleDouble, TwoSumAndTwoProdAreExact) {
  impact::test::Rng rng(7);
  for (int i = 0; i < 20000; ++i) {
    const double a = std::ldexp(double(rng.raw() >> 11), int(rng.index(60))) * (rng.index(2) ? 1 : -1);
    const double b = std::ldexp(double(rng.raw() >> 11), int(rng.index(60))) * (rng.index(2) ? 1 : -1);
    double s, e;
    impact::detail::two_sum(a, b, s, e);
    EXPECT_TRUE((big(s) + big(e) - big(a) - big(b)).zero());
    const double x = double(rng.raw() >> 11), y = double(rng.raw() >> 11) * (rng.index(2) ? 1 : -1);
    impact::detail::two_prod(x, y, s, e);
    EXPECT_TRUE((big(s) + big(e) - big(x).mul(std::int64_t(y))).zero());
  }
}

TEST(DoubleDouble, OperationsWithinTheErrorBound) {
  impact::test::Rng rng(8);
  for (int i = 0; i < 20000; ++i) {
    const DoubleDouble x = random_dd(rng), y = random_dd(rng);
    const BigInt X = big(x), Y = big(y);
    expect_within_bound(x + y, X + Y);
    expect_within_bound(x - y, X - Y);
    // x * y = x (yh + yl) with yh = m 2^60, yl = integer tail
    const auto yh = static_cast<std::int64_t>(std::ldexp(y.hi, -60)), yl = static_cast<std::int64_t>(y.lo);
    expect_within_bound(x * y, X.mul(yh).shl(60) + X.mul(yl));
    const double d = std::ldexp(double(rng.raw() >> 11), int(rng.index(8))) * (rng.index(2) ? 1 : -1);
    const auto di = static_cast<std::int64_t>(d);
    if (double(di) == d) expect_within_bound(x * d, X.mul(di));
  }
}

TEST(DoubleDouble, ExactCases) {
  const DoubleDouble d = DoubleDouble::difference(1.0, std::ldexp(1.0, -80));  // 1 - 2^-80 exactly
  EXPECT_EQ(d.hi, 1.0);
  EXPECT_EQ(d.lo, -std::ldexp(1.0, -80));
  EXPECT_TRUE(d < DoubleDouble(1.0));
  EXPECT_TRUE(DoubleDouble(0.0) < d);
  EXPECT_EQ(abs(-d).lo, d.lo);
  const DoubleDouble z = d - DoubleDouble(1.0);
  EXPECT_EQ(z.hi, -std::ldexp(1.0, -80));
  EXPECT_EQ(z.lo, 0.0);
}

}  // namespace
