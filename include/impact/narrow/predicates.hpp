// SPDX-License-Identifier: MIT
/// \file
/// Exact orientation predicates orient3d and orient2d.
///
/// Numerical contract: EXACT for every finite double (and float) input, over the whole range from
/// subnormal numbers to the largest double. Each predicate returns the sign (-1, 0, +1) of the
/// determinant of its floating-point inputs as if evaluated in exact real arithmetic. Three
/// stages:
///  1. a floating-point determinant with a dynamic error bound (Shewchuk's stage-A bound on the
///     permanent of the same products, plus an absolute term that covers gradual underflow of the
///     products); overflow makes the bound infinite or NaN and falls through;
///  2. when the filter cannot certify the sign, the determinant is recomputed exactly with
///     floating-point expansions (two-sum, fma two-product, expansion growth with zero
///     elimination), provided every component of the coordinate differences lies in a range where
///     no product can underflow or overflow (nonzero magnitudes in [2^-306, 2^330] for orient3d,
///     [2^-480, 2^480] for orient2d: every product is then a multiple of 2^-1074, so its rounding
///     error is representable, and every sum is below 2^1023);
///  3. otherwise (coordinates spanning subnormal to huge magnitudes, or differences that overflow)
///     an exact evaluation in fixed-size big integers: every input is an integer multiple of
///     2^e_min (the smallest exponent among them), the determinant of those integers is computed
///     exactly (at most 6,500 bits), its sign is the answer. Rare and slower (microseconds).
/// Float inputs are converted to double exactly and take the double path. Non-finite inputs are
/// outside the contract (validated meshes, poses and rays never produce them): the result is 0.
///
/// Assumption: IEEE-754 double arithmetic with round-to-nearest and gradual underflow (no
/// flush-to-zero / denormals-are-zero modes, no -ffast-math); fused multiply-add contraction is
/// harmless: it only lowers the error of the filter, and the exact stages use std::fma explicitly.
#pragma once

#include "impact/core/config.hpp"
#include "impact/core/types.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace impact {
namespace detail {
namespace expansion {

/// x + y = a + b exactly, |y| <= ulp(x) / 2.
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a;
  const double av = x - bv;
  y = (a - av) + (b - bv);
}

/// x + y = a * b exactly (no underflow assumed).
inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

/// A floating-point expansion: a sum of nonoverlapping doubles stored by increasing magnitude,
/// zero components removed. Capacity N is a compile-time bound on the number of components.
template <int N> struct Expansion {
  double c[N];
  int n = 0;

  Expansion() = default;
  /// The expansion of a - b (exact, at most two components).
  static Expansion difference(double a, double b) {
    Expansion e;
    double x, y;
    two_sum(a, -b, x, y);
    if (y != 0.0) e.c[e.n++] = y;
    if (x != 0.0) e.c[e.n++] = x;
    return e;
  }
  /// Adds the double b exactly (Shewchuk's grow-expansion with zero elimination).
  void grow(double b) {
    if (b == 0.0) return;
    double q = b;
    int m = 0;
    for (int i = 0; i < n; ++i) {
      double x, y;
      two_sum(q, c[i], x, y);
      q = x;
      if (y != 0.0) c[m++] = y;
    }
    if (q != 0.0) c[m++] = q;
    n = m;
  }
  /// Sign of the represented value: that of the most significant component.
  int sign() const { return n == 0 ? 0 : (c[n - 1] > 0.0 ? 1 : -1); }
};

/// Exact product of two expansions, accumulated into a (exact for the capacities used below).
template <int N, int A, int B> inline void add_product(Expansion<N>& acc, const Expansion<A>& x, const Expansion<B>& y, bool negate) {
  for (int i = 0; i < x.n; ++i)
    for (int j = 0; j < y.n; ++j) {
      double p, e;
      two_product(x.c[i], y.c[j], p, e);
      if (negate) p = -p, e = -e;
      acc.grow(e);
      acc.grow(p);
    }
}

/// Exact sign of det[b - a, c - a] (2D), by expansions.
inline int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
  const auto ux = Expansion<2>::difference(bx, ax), uy = Expansion<2>::difference(by, ay);
  const auto vx = Expansion<2>::difference(cx, ax), vy = Expansion<2>::difference(cy, ay);
  Expansion<16> det;
  add_product(det, ux, vy, false);
  add_product(det, uy, vx, true);
  return det.sign();
}

/// Exact sign of det[u, v, w] (3D) for the rows u = diff[0..3), v = diff[3..6), w = diff[6..9),
/// each component an expansion of at most two components, by expansions.
inline int det3_exact(const Expansion<2>* diff) {
  const Expansion<2>* u = diff;
  const Expansion<2>* v = diff + 3;
  const Expansion<2>* w = diff + 6;
  Expansion<192> det;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    Expansion<16> minor;  // (u x v)_k = u_k1 v_k2 - u_k2 v_k1
    add_product(minor, u[k1], v[k2], false);
    add_product(minor, u[k2], v[k1], true);
    add_product(det, w[k], minor, false);
  }
  return det.sign();
}

}  // namespace expansion

namespace bigint {

/// A signed integer of up to 32 * kLimbs bits, sign and magnitude, little-endian 32-bit limbs.
/// Enough for orient3d over the whole double range: inputs are below 2^2152 once scaled to a
/// common exponent, differences below 2^2153, the determinant below 2^6462.
struct Int {
  static constexpr int kLimbs = 216;
  std::uint32_t limb[kLimbs];
  int n = 0;        ///< limbs in use (no leading zero limb); 0 is n == 0
  bool neg = false;

  int sign() const { return n == 0 ? 0 : (neg ? -1 : 1); }
  void trim() {
    while (n > 0 && limb[n - 1] == 0) --n;
    if (n == 0) neg = false;
  }
  /// m * 2^shift (|m| < 2^63, 0 <= shift < 32 * kLimbs - 64).
  static Int shifted(std::int64_t m, int shift) {
    Int r;
    r.neg = m < 0;
    const std::uint64_t a = m < 0 ? std::uint64_t(0) - std::uint64_t(m) : std::uint64_t(m);
    const int w = shift / 32, b = shift % 32;
    for (int i = 0; i < w; ++i) r.limb[i] = 0;
    const std::uint64_t lo = a << b, hi = b == 0 ? 0 : a >> (64 - b);  // a 2^b: at most 95 bits
    r.limb[w] = std::uint32_t(lo), r.limb[w + 1] = std::uint32_t(lo >> 32), r.limb[w + 2] = std::uint32_t(hi);
    r.n = w + 3;
    r.trim();
    return r;
  }
};

/// Compares magnitudes: -1, 0, +1.
inline int compare_magnitude(const Int& a, const Int& b) {
  if (a.n != b.n) return a.n < b.n ? -1 : 1;
  for (int i = a.n - 1; i >= 0; --i)
    if (a.limb[i] != b.limb[i]) return a.limb[i] < b.limb[i] ? -1 : 1;
  return 0;
}

/// a + (negate_b ? -b : b), exact.
inline Int add(const Int& a, const Int& b, bool negate_b = false) {
  const bool bneg = b.n != 0 && (b.neg != negate_b);
  Int r;
  if (a.neg == bneg || a.n == 0 || b.n == 0) {  // same signs (or a zero): add magnitudes
    const Int& big = a.n >= b.n ? a : b;
    const Int& small = a.n >= b.n ? b : a;
    std::uint64_t carry = 0;
    for (int i = 0; i < big.n; ++i) {
      const std::uint64_t s = std::uint64_t(big.limb[i]) + (i < small.n ? small.limb[i] : 0u) + carry;
      r.limb[i] = std::uint32_t(s);
      carry = s >> 32;
    }
    r.n = big.n;
    if (carry) r.limb[r.n++] = std::uint32_t(carry);
    r.neg = a.n != 0 ? a.neg : bneg;
  } else {  // opposite signs: subtract the smaller magnitude from the larger
    const int c = compare_magnitude(a, b);
    if (c == 0) return r;
    const Int& big = c > 0 ? a : b;
    const Int& small = c > 0 ? b : a;
    std::int64_t borrow = 0;
    for (int i = 0; i < big.n; ++i) {
      std::int64_t d = std::int64_t(big.limb[i]) - (i < small.n ? std::int64_t(small.limb[i]) : 0) - borrow;
      borrow = d < 0;
      if (d < 0) d += std::int64_t(1) << 32;
      r.limb[i] = std::uint32_t(d);
    }
    r.n = big.n;
    r.neg = c > 0 ? a.neg : bneg;
  }
  r.trim();
  return r;
}

/// a * b, exact (the limb counts must add up to at most kLimbs).
inline Int mul(const Int& a, const Int& b) {
  Int r;
  if (a.n == 0 || b.n == 0) return r;
  r.n = a.n + b.n;
  for (int i = 0; i < r.n; ++i) r.limb[i] = 0;
  for (int i = 0; i < a.n; ++i) {
    std::uint64_t carry = 0;
    for (int j = 0; j < b.n; ++j) {
      const std::uint64_t t = std::uint64_t(a.limb[i]) * b.limb[j] + r.limb[i + j] + carry;
      r.limb[i + j] = std::uint32_t(t);
      carry = t >> 32;
    }
    r.limb[i + b.n] = std::uint32_t(carry);
  }
  r.neg = a.neg != b.neg;
  r.trim();
  return r;
}

/// The inputs x[0..count) as integers on the common grid 2^e_min: x[i] = m_i 2^(e_i) with a 53-bit
/// integer m_i, scaled by 2^(e_i - e_min). False when an input is not finite.
inline bool to_common_grid(const double* x, int count, Int* out) {
  int e_min = 1 << 20;
  std::int64_t m[12];
  int e[12];
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(x[i])) return false;
    int ex = 0;
    const double f = std::frexp(x[i], &ex);  // x = f 2^ex, |f| in [0.5, 1) (or 0)
    m[i] = static_cast<std::int64_t>(std::ldexp(f, 53));  // exact: 53 significant bits
    e[i] = ex - 53;
    if (m[i] != 0 && e[i] < e_min) e_min = e[i];
  }
  for (int i = 0; i < count; ++i) out[i] = m[i] == 0 ? Int() : Int::shifted(m[i], e[i] - e_min);
  return true;
}

/// Exact sign of det[b - a, c - a, d - a] for any finite doubles (0 for non-finite input), or of
/// det[b - a, c - a, d] when `d_is_direction` (d a vector, not a point). Kept out of line: its
/// 25 KB of stack should not weigh on the frames of the hot callers.
IMPACT_NOINLINE inline int orient3d(const double* a, const double* b, const double* c, const double* d, bool d_is_direction = false) {
  const double x[12] = {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], d[0], d[1], d[2]};
  Int g[12];
  if (!to_common_grid(x, 12, g)) return 0;
  Int u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k)
    u[k] = add(g[3 + k], g[k], true), v[k] = add(g[6 + k], g[k], true), w[k] = d_is_direction ? g[9 + k] : add(g[9 + k], g[k], true);
  Int det;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    const Int minor = add(mul(u[k1], v[k2]), mul(u[k2], v[k1]), true);
    det = add(det, mul(w[k], minor));
  }
  return det.sign();
}

/// Exact sign of det[b - a, c - a] (2D) for any finite doubles (0 for non-finite input).
IMPACT_NOINLINE inline int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const double x[6] = {ax, ay, bx, by, cx, cy};
  Int g[6];
  if (!to_common_grid(x, 6, g)) return 0;
  const Int ux = add(g[2], g[0], true), uy = add(g[3], g[1], true), vx = add(g[4], g[0], true), vy = add(g[5], g[1], true);
  return add(mul(ux, vy), mul(uy, vx), true).sign();
}

}  // namespace bigint

/// True when every nonzero component of the difference expansions lies in [lo, hi] in magnitude
/// (the range where the expansion stage cannot underflow or overflow; false for inf and NaN).
template <int N> inline bool components_in_range(const expansion::Expansion<N>* e, int count, double lo, double hi) {
  for (int i = 0; i < count; ++i)
    for (int j = 0; j < e[i].n; ++j) {
      const double m = std::fabs(e[i].c[j]);
      if (!(m >= lo && m <= hi)) return false;
    }
  return true;
}

/// The exact stages of orient3d: expansions when their range allows, else big integers. With
/// `d_is_direction`, the exact sign of det[b - a, c - a, d] (d a vector: its row is d itself).
inline int orient3d_exact(const double* a, const double* b, const double* c, const double* d, bool d_is_direction = false) {
  expansion::Expansion<2> diff[9];
  for (int k = 0; k < 3; ++k) {
    diff[k] = expansion::Expansion<2>::difference(b[k], a[k]);
    diff[3 + k] = expansion::Expansion<2>::difference(c[k], a[k]);
    diff[6 + k] = expansion::Expansion<2>::difference(d[k], d_is_direction ? 0.0 : a[k]);
  }
  if (components_in_range(diff, 9, 0x1p-306, 0x1p330)) return expansion::det3_exact(diff);
  return bigint::orient3d(a, b, c, d, d_is_direction);
}

/// Exact sign of det[u; v; w] for x = (u, v, w) when every nonzero x_i is a normal double and all
/// nine are integer multiples of one power of two 2^lo below 2^(lo + 40) in magnitude (|lo| <= 1000):
/// then each x_i 2^-lo is an integer below 2^40, each 2x2 minor below 2^81 and the determinant
/// below 2^123, exact in 128-bit integers. Returns 2 when that does not hold (or without 128-bit
/// integers: GCC and Clang have them). The common case of a ray cast near a vertex (coordinates on
/// one grid, as meshes rounded to float are): about 200 instructions against 1,100 for the
/// expansions.
inline int det3_small_integers(const double* x) {
#if defined(__SIZEOF_INT128__)
  __extension__ typedef __int128 I128;
  int lo = 1 << 20, hi = -(1 << 20);
  for (int i = 0; i < 9; ++i) {
    if (x[i] == 0.0) continue;
    std::uint64_t bits;
    std::memcpy(&bits, x + i, sizeof bits);
    const int e = static_cast<int>((bits >> 52) & 0x7ff);
    if (e == 0 || e == 0x7ff) return 2;  // subnormal, infinite or NaN
    const std::uint64_t m = (bits & 0xfffffffffffffULL) | (std::uint64_t(1) << 52);
    const int tz = __builtin_ctzll(m);
    const int low = e - 1075 + tz;  // x_i = (m 2^-tz) 2^low, m 2^-tz odd
    lo = low < lo ? low : lo;
    hi = e - 1022 > hi ? e - 1022 : hi;  // |x_i| < 2^(e - 1022)
  }
  if (hi < lo) return 0;  // all zero
  if (hi - lo > 40 || lo < -1000 || lo > 1000) return 2;
  const std::uint64_t scale_bits = std::uint64_t(1023 - lo) << 52;
  double scale;
  std::memcpy(&scale, &scale_bits, sizeof scale);  // 2^-lo
  std::int64_t n[9];
  for (int i = 0; i < 9; ++i) n[i] = static_cast<std::int64_t>(x[i] * scale);  // exact: an integer below 2^40
  I128 det = 0;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    det += I128(n[6 + k]) * (I128(n[k1]) * n[3 + k2] - I128(n[k2]) * n[3 + k1]);
  }
  return det > 0 ? 1 : (det < 0 ? -1 : 0);
#else
  (void)x;
  return 2;
#endif
}

/// Exact sign of det[b - a, c - a, d] (d a direction, not a point), for any finite doubles:
/// det3_small_integers when the differences are exact and the values on one small grid, else
/// orient3d_exact's stages.
inline int orient3d_direction_exact(const double* a, const double* b, const double* c, const double* d) {
  double x[9];
  bool exact = true;
  for (int k = 0; k < 3; ++k) {
    double y;
    expansion::two_sum(b[k], -a[k], x[k], y);
    exact = exact && y == 0.0;
    expansion::two_sum(c[k], -a[k], x[3 + k], y);
    exact = exact && y == 0.0;
    x[6 + k] = d[k];
  }
  if (exact) {
    const int s = det3_small_integers(x);
    if (s != 2) return s;
  }
  return orient3d_exact(a, b, c, d, true);
}

/// The exact stages of orient2d: expansions when their range allows, else big integers.
inline int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
  const expansion::Expansion<2> diff[4] = {expansion::Expansion<2>::difference(bx, ax), expansion::Expansion<2>::difference(by, ay),
                                           expansion::Expansion<2>::difference(cx, ax), expansion::Expansion<2>::difference(cy, ay)};
  if (components_in_range(diff, 4, 0x1p-480, 0x1p480)) return expansion::orient2d_exact(ax, ay, bx, by, cx, cy);
  return bigint::orient2d(ax, ay, bx, by, cx, cy);
}

/// Shewchuk's stage-A relative error bounds, rounded up generously (epsilon = 2^-53).
inline constexpr double orient3d_bound = (8.0 + 64.0 * 0x1p-53) * 0x1p-53;
inline constexpr double orient2d_bound = (4.0 + 32.0 * 0x1p-53) * 0x1p-53;
/// Bounds the absolute error of a product that underflows (gradual underflow: at most 2^-1075),
/// with much room: the filters add (the number of such errors, weighted by what multiplies them)
/// times this. It is 2^-1000, not a few times 2^-1075, so that the term is a normal number: a
/// subnormal product or sum costs a microcode assist (about 100 cycles on x86) at every filter
/// evaluation, which took about 12 % of a colliding mesh-mesh query. A larger bound only sends
/// more (astronomically small) determinants to the exact stage.
inline constexpr double underflow_unit = 0x1p-1000;
/// Nonzero differences at least this large make every product of three of them at least 2^-1008:
/// none rounds to zero, so a zero permanent proves a zero determinant.
inline constexpr double no_underflow_3 = 0x1p-330;
inline constexpr double no_underflow_2 = 0x1p-500;

/// True when x is 0 or |x| >= lo.
inline bool zero_or_at_least(double x, double lo) { return x == 0.0 || std::fabs(x) >= lo; }

/// Filtered sign of (d - a) . n given the rounded normal n = fl((b - a) x (c - a)) and the permanent
/// components p_k = |u_k1 v_k2| + |u_k2 v_k1|; `uv_safe` says that every component of u = b - a
/// and v = c - a is 0 or at least no_underflow_3 in magnitude. Returns 2 when the filter cannot
/// decide. The bound is Shewchuk's relative one plus the underflow term: each of the six products
/// u_i v_j may lose up to 2^-1075 to underflow, which the difference w_k multiplies, and each of
/// the three products w_k n_k as much again.
inline int orient3d_filtered(const double* a, const double* n, const double* p, const double* d, bool uv_safe) {
  const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
  const double det = wx * n[0] + wy * n[1] + wz * n[2];
  const double aw = std::fabs(wx) + std::fabs(wy) + std::fabs(wz);
  const double perm = std::fabs(wx) * p[0] + std::fabs(wy) * p[1] + std::fabs(wz) * p[2];
  const double bound = orient3d_bound * perm + underflow_unit * (aw + 2.0);
  if (det > bound) return 1;
  if (-det > bound) return -1;
  // a zero permanent proves a zero determinant when no product can have underflowed to zero
  if (perm == 0.0 && uv_safe && zero_or_at_least(wx, no_underflow_3) && zero_or_at_least(wy, no_underflow_3) &&
      zero_or_at_least(wz, no_underflow_3))
    return 0;
  return 2;
}

/// True when each of the six differences is 0 or at least no_underflow_3 in magnitude.
inline bool uv_safe(double ux, double uy, double uz, double vx, double vy, double vz) {
  return zero_or_at_least(ux, no_underflow_3) && zero_or_at_least(uy, no_underflow_3) && zero_or_at_least(uz, no_underflow_3) &&
         zero_or_at_least(vx, no_underflow_3) && zero_or_at_least(vy, no_underflow_3) && zero_or_at_least(vz, no_underflow_3);
}

inline int orient3d_double(const double* a, const double* b, const double* c, const double* d) {
  const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
  const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
  const double n[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
  const double p[3] = {std::fabs(uy * vz) + std::fabs(uz * vy), std::fabs(uz * vx) + std::fabs(ux * vz),
                       std::fabs(ux * vy) + std::fabs(uy * vx)};
  const int s = orient3d_filtered(a, n, p, d, uv_safe(ux, uy, uz, vx, vy, vz));
  return s != 2 ? s : orient3d_exact(a, b, c, d);
}

inline int orient2d_double(double ax, double ay, double bx, double by, double cx, double cy) {
  const double ux = bx - ax, uy = by - ay, vx = cx - ax, vy = cy - ay;
  const double l = ux * vy, r = uy * vx;
  const double det = l - r;
  // two products, each may lose up to 2^-1075 to underflow
  const double bound = orient2d_bound * (std::fabs(l) + std::fabs(r)) + underflow_unit;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  if (l == 0.0 && r == 0.0 && zero_or_at_least(ux, no_underflow_2) && zero_or_at_least(uy, no_underflow_2) &&
      zero_or_at_least(vx, no_underflow_2) && zero_or_at_least(vy, no_underflow_2))
    return 0;
  return orient2d_exact(ax, ay, bx, by, cx, cy);
}

}  // namespace detail

/// Exact sign of det[b - a, c - a, d - a] = (d - a) . ((b - a) x (c - a)): +1 when d lies on the side
/// of the plane through a, b, c towards which the normal (b - a) x (c - a) points (a, b, c appear
/// counter-clockwise seen from d), -1 on the other side, 0 when the four points are coplanar
/// (exactly). Note the sign convention is the opposite of Shewchuk's orient3d.
template <class S> inline int orient3d(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c, const Vec3<S>& d) {
  static_assert(is_supported_scalar_v<S>, "orient3d: float or double");
  const double pa[3] = {double(a.x()), double(a.y()), double(a.z())}, pb[3] = {double(b.x()), double(b.y()), double(b.z())};
  const double pc[3] = {double(c.x()), double(c.y()), double(c.z())}, pd[3] = {double(d.x()), double(d.y()), double(d.z())};
  return detail::orient3d_double(pa, pb, pc, pd);
}

/// Exact sign of det[b - a, c - a] = (b - a) x (c - a): +1 when a, b, c turn counter-clockwise,
/// -1 clockwise, 0 when collinear (exactly).
template <class S> inline int orient2d(const Vec2<S>& a, const Vec2<S>& b, const Vec2<S>& c) {
  static_assert(is_supported_scalar_v<S>, "orient2d: float or double");
  return detail::orient2d_double(double(a.x()), double(a.y()), double(b.x()), double(b.y()), double(c.x()), double(c.y()));
}

/// A triangle's supporting plane prepared for many exact orient3d queries against the same a, b, c
/// (the normal and the filter's permanent terms are computed once). Same contract as orient3d.
struct OrientPlane {
  double a[3], b[3], c[3];
  double n[3];  ///< fl((b - a) x (c - a))
  double p[3];  ///< permanent terms of the normal for the error bound
  bool safe = true;  ///< every component of b - a and c - a is 0 or at least detail::no_underflow_3

  OrientPlane() = default;
  template <class S> OrientPlane(const Vec3<S>& pa, const Vec3<S>& pb, const Vec3<S>& pc) {
    for (int k = 0; k < 3; ++k) a[k] = double(pa[k]), b[k] = double(pb[k]), c[k] = double(pc[k]);
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    n[0] = uy * vz - uz * vy, n[1] = uz * vx - ux * vz, n[2] = ux * vy - uy * vx;
    p[0] = std::fabs(uy * vz) + std::fabs(uz * vy), p[1] = std::fabs(uz * vx) + std::fabs(ux * vz);
    p[2] = std::fabs(ux * vy) + std::fabs(uy * vx);
    safe = detail::uv_safe(ux, uy, uz, vx, vy, vz);
  }
  /// Exact orient3d(a, b, c, d).
  int orient(const double* d) const {
    const int s = detail::orient3d_filtered(a, n, p, d, safe);
    return s != 2 ? s : detail::orient3d_exact(a, b, c, d);
  }
  template <class S> int orient(const Vec3<S>& d) const {
    const double pd[3] = {double(d.x()), double(d.y()), double(d.z())};
    return orient(pd);
  }
};

}  // namespace impact
