// SPDX-License-Identifier: MIT
/// \file
/// Double-double numbers (an unevaluated sum hi + lo of two doubles, |lo| <= ulp(hi) / 2) with the
/// few operations the CCD re-check needs: +, -, * and comparisons. They carry about 106 bits, so
/// the re-check can separate near misses that double rounding (53 bits) cannot.
///
/// Error model, used by the error bounds of detail/inclusion.hpp: with u = 2^-53, every operation
/// below returns the exact result of its (double-double) operands times (1 + delta) with
/// |delta| <= 7 u^2 < 2^-103, as long as nothing underflows or overflows:
///  - sum:  the accurate double-word addition, error <= 3 u^2 (Joldes, Muller and Popescu, "Tight
///    and rigorous error bounds for basic building blocks of double-word arithmetic", ACM TOMS 2017,
///    algorithm 6);
///  - product by a double: error <= 2 u^2 (ibid., algorithm 9); product of two double-words:
///    error <= 7 u^2 (ibid., algorithm 10);
///  - negation and products by powers of two are exact.
/// The building blocks two_sum and two_prod are exact; two_prod uses a fused multiply-add when the
/// target has a fast one and Dekker's splitting otherwise (exact too, for |a|, |b| < 2^996).
/// Contraction of a * b + c into a fused multiply-add only removes roundings and keeps the bounds;
/// the splitting, which contraction would break, is only used when the target has no FMA.
#pragma once

#include <cmath>

namespace impact::detail {

/// a + b = s + e exactly (Knuth's branch-free TwoSum).
inline void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bb = s - a;
  e = (a - (s - bb)) + (b - bb);
}

/// a + b = s + e exactly, provided |a| >= |b| or a == 0 (Dekker's FastTwoSum).
inline void fast_two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  e = b - (s - a);
}

/// a * b = p + e exactly (barring underflow).
inline void two_prod(double a, double b, double& p, double& e) {
  p = a * b;
#ifdef FP_FAST_FMA
  e = std::fma(a, b, -p);
#else
  constexpr double kSplit = 134217729.0;  // 2^27 + 1
  const double ca = kSplit * a, cb = kSplit * b;
  const double ah = ca - (ca - a), al = a - ah;
  const double bh = cb - (cb - b), bl = b - bh;
  e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
#endif
}

/// A double-double number hi + lo.
struct DoubleDouble {
  double hi = 0.0, lo = 0.0;

  DoubleDouble() = default;
  constexpr DoubleDouble(double x) : hi(x), lo(0.0) {}  // NOLINT: implicit on purpose, exact
  constexpr DoubleDouble(double h, double l) : hi(h), lo(l) {}

  /// The exact difference a - b of two doubles.
  static DoubleDouble difference(double a, double b) {
    DoubleDouble r;
    two_sum(a, -b, r.hi, r.lo);
    return r;
  }

  /// Nearest double (hi already is, since |lo| <= ulp(hi) / 2).
  double approx() const { return hi; }

  DoubleDouble operator-() const { return {-hi, -lo}; }

  friend DoubleDouble operator+(const DoubleDouble& x, const DoubleDouble& y) {
    double sh, sl, th, tl;
    two_sum(x.hi, y.hi, sh, sl);
    two_sum(x.lo, y.lo, th, tl);
    const double c = sl + th;
    double vh, vl;
    fast_two_sum(sh, c, vh, vl);
    const double w = tl + vl;
    DoubleDouble z;
    fast_two_sum(vh, w, z.hi, z.lo);
    return z;
  }
  friend DoubleDouble operator-(const DoubleDouble& x, const DoubleDouble& y) { return x + (-y); }

  friend DoubleDouble operator*(const DoubleDouble& x, double y) {
    double ch, cl1;
    two_prod(x.hi, y, ch, cl1);
    const double cl3 = x.lo * y + cl1;
    DoubleDouble z;
    fast_two_sum(ch, cl3, z.hi, z.lo);
    return z;
  }
  friend DoubleDouble operator*(double y, const DoubleDouble& x) { return x * y; }
  friend DoubleDouble operator*(const DoubleDouble& x, const DoubleDouble& y) {
    double ch, cl1;
    two_prod(x.hi, y.hi, ch, cl1);
    const double tl1 = x.hi * y.lo, tl2 = x.lo * y.hi;
    const double cl2 = tl1 + tl2;
    const double cl3 = cl1 + cl2;
    DoubleDouble z;
    fast_two_sum(ch, cl3, z.hi, z.lo);
    return z;
  }

  // Comparisons of normalised values: the sign and order are decided by hi, then lo.
  friend bool operator<(const DoubleDouble& x, const DoubleDouble& y) { return x.hi < y.hi || (x.hi == y.hi && x.lo < y.lo); }
  friend bool operator>(const DoubleDouble& x, const DoubleDouble& y) { return y < x; }
  friend bool operator<=(const DoubleDouble& x, const DoubleDouble& y) { return !(y < x); }
  friend bool operator>=(const DoubleDouble& x, const DoubleDouble& y) { return !(x < y); }
};

inline DoubleDouble abs(const DoubleDouble& x) { return x.hi < 0.0 || (x.hi == 0.0 && x.lo < 0.0) ? -x : x; }

}  // namespace impact::detail
