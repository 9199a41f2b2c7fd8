// SPDX-License-Identifier: MIT
// An exact reference for the CCD tests, independent of the library's floating-point search.
// Inputs are integer coordinates (the test converts them to double or float by one exact power of
// two scale). Values of F(t, u, v) (vertex-face: p - f0 - u (f1 - f0) - v (f2 - f0); edge-edge:
// a0 + u (a1 - a0) - b0 - v (b1 - b0)) at dyadic parameters are integers after scaling by
// 2^(A+B+C), computed exactly in a 256-bit two's-complement integer. Since F is linear in each of
// t, u, v separately, its exact range on a box is the hull of the 8 corner values, so a box whose
// corner values of one component (or of n . F for an integer direction n) all have one strict sign
// contains no contact. certify_no_contact subdivides until every box is excluded (a proof that
// there is no contact for t in [0, 1]) or gives up (Unknown) after a budget or at depth 60 per
// variable. Besides the given directions, each box also tries integer approximations of the
// plane normal and of a separating direction at the box's start time (any integer n is valid). Bounds:
// |coordinate| < 2^53, depth <= 60 and |n_i| <= 2^61 keep every value below 2^301 (the integers have
// 320 bits): corner values of F stay below 2^237, each product with n_i below 2^298.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace impact::test {

__extension__ typedef unsigned __int128 U128;  // GCC/Clang extension, test-only

/// 320-bit two's-complement integer with the few operations the reference needs.
struct BigInt {
  static constexpr int kLimbs = 5;
  std::uint64_t w[kLimbs] = {0, 0, 0, 0, 0};

  static BigInt from(std::int64_t x) {
    BigInt r;
    const std::uint64_t fill = x < 0 ? ~std::uint64_t(0) : 0;
    r.w[0] = std::uint64_t(x);
    for (int i = 1; i < kLimbs; ++i) r.w[i] = fill;
    return r;
  }
  bool negative() const { return (w[kLimbs - 1] >> 63) != 0; }
  bool zero() const {
    std::uint64_t o = 0;
    for (auto x : w) o |= x;
    return o == 0;
  }
  int sign() const { return negative() ? -1 : (zero() ? 0 : 1); }
  friend BigInt operator+(const BigInt& a, const BigInt& b) {
    BigInt r;
    U128 c = 0;
    for (int i = 0; i < kLimbs; ++i) {
      c += U128(a.w[i]) + b.w[i];
      r.w[i] = std::uint64_t(c);
      c >>= 64;
    }
    return r;
  }
  BigInt operator-() const {
    BigInt r;
    for (int i = 0; i < kLimbs; ++i) r.w[i] = ~w[i];
    return r + from(1);
  }
  friend BigInt operator-(const BigInt& a, const BigInt& b) { return a + (-b); }
  /// Left shift by s bits, 0 <= s < 320 (the caller keeps values in range).
  BigInt shl(int s) const {
    BigInt r;
    const int limbs = s / 64, bits = s % 64;
    for (int i = kLimbs - 1; i >= 0; --i) {
      const int j = i - limbs;
      if (j < 0) continue;
      std::uint64_t v = w[j] << bits;
      if (bits && j > 0) v |= w[j - 1] >> (64 - bits);
      r.w[i] = v;
    }
    return r;
  }
  /// Product with a 64-bit integer. Throws when the result would not fit (never for the bounds
  /// documented above: a guard, not a code path).
  BigInt mul(std::int64_t m) const {
    const bool neg = negative() != (m < 0);
    const BigInt a = negative() ? -*this : *this;
    const std::uint64_t mm = m < 0 ? std::uint64_t(0) - std::uint64_t(m) : std::uint64_t(m);
    BigInt r;
    U128 c = 0;
    for (int i = 0; i < kLimbs; ++i) {
      c += U128(a.w[i]) * mm;
      r.w[i] = std::uint64_t(c);
      c >>= 64;
    }
    if (c != 0 || r.negative()) throw std::overflow_error("BigInt::mul overflow");
    return neg ? -r : r;
  }
  /// Nearest double (approximate; used only to choose splits).
  double approx() const {
    const BigInt a = negative() ? -*this : *this;
    double v = 0;
    for (int i = kLimbs - 1; i >= 0; --i) v = v * 18446744073709551616.0 + double(a.w[i]);
    return negative() ? -v : v;
  }
};

/// A query with integer coordinates: points[k] at t = 0 and points[k + 4] at t = 1 (vertex-face:
/// p, f0, f1, f2; edge-edge: a0, a1, b0, b1), |coordinate| < 2^53.
struct IntCcdQuery {
  std::array<std::array<std::int64_t, 3>, 8> points{};
  bool vertex_face = true;
};

enum class ExactAnswer { NoContact, Unknown };

namespace detail_exact {

// One box: low end numerator and depth per variable (t, u, v); the interval is
// [n / 2^depth, (n + 1) / 2^depth].
struct XBox {
  std::int64_t n[3];
  int depth[3];
};

// F scaled by 2^(A+B+C) at the corner (t = T/2^A, u = U/2^B, v = V/2^C), all three components.
inline std::array<BigInt, 3> corner(const IntCcdQuery& q, std::int64_t T, int A, std::int64_t U, int B, std::int64_t V, int C) {
  std::array<BigInt, 3> out;
  for (int i = 0; i < 3; ++i) {
    BigInt x[4];  // point k at time t, scaled by 2^A
    for (int k = 0; k < 4; ++k) {
      const std::int64_t x0 = q.points[std::size_t(k)][std::size_t(i)], x1 = q.points[std::size_t(k) + 4][std::size_t(i)];
      x[k] = BigInt::from(x0).shl(A) + BigInt::from(x1 - x0).mul(T);
    }
    if (q.vertex_face) {
      const BigInt e0 = x[0] - x[1], e1 = x[2] - x[1], e2 = x[3] - x[1];
      out[std::size_t(i)] = e0.shl(B + C) - e1.shl(C).mul(U) - e2.shl(B).mul(V);
    } else {
      out[std::size_t(i)] = x[0].shl(B + C) + (x[1] - x[0]).shl(C).mul(U) - x[2].shl(B + C) - (x[3] - x[2]).shl(B).mul(V);
    }
  }
  return out;
}

}  // namespace detail_exact

/// Tries to prove that the closed primitives never touch for t in [0, 1] (distance 0; no minimum
/// separation). `directions`: optional integer directions n (each |n_i| <= 2^61) whose n . F is
/// also used to exclude boxes, e.g. the normal of a plane of coplanar motion. NoContact is a
/// proof; Unknown means the budget (boxes) or the depth limit ran out.
inline ExactAnswer certify_no_contact(const IntCcdQuery& q, const std::vector<std::array<std::int64_t, 3>>& directions = {},
                                      std::size_t budget = 200000) {
  using detail_exact::XBox;
  std::vector<XBox> stack{XBox{{0, 0, 0}, {0, 0, 0}}};
  const int kMaxDepth = 60;
  std::size_t used = 0;
  const std::size_t nf = 5 + directions.size();
  // Values of the exclusion functions (3 components, the two box directions, the given
  // directions) at up to 16 points; nb and mb are set per box below.
  std::vector<std::array<BigInt, 16>> val(nf), clipped(nf);
  std::array<std::int64_t, 3> nb{0, 0, 0}, mb{0, 0, 0};
  auto eval_at = [&](std::int64_t T, int A, std::int64_t U, int B, std::int64_t V, int C,
                     std::vector<std::array<BigInt, 16>>& out, std::size_t slot) {
    const auto f = detail_exact::corner(q, T, A, U, B, V, C);
    for (std::size_t i = 0; i < 3; ++i) out[i][slot] = f[i];
    out[3][slot] = f[0].mul(nb[0]) + f[1].mul(nb[1]) + f[2].mul(nb[2]);
    out[4][slot] = f[0].mul(mb[0]) + f[1].mul(mb[1]) + f[2].mul(mb[2]);
    for (std::size_t j = 0; j < directions.size(); ++j)
      out[5 + j][slot] = f[0].mul(directions[j][0]) + f[1].mul(directions[j][1]) + f[2].mul(directions[j][2]);
  };
  while (!stack.empty()) {
    const XBox b = stack.back();
    stack.pop_back();
    if (++used > budget) return ExactAnswer::Unknown;
    const int A = b.depth[0], B = b.depth[1], C = b.depth[2];
    if (q.vertex_face) {
      // Outside the triangle when u_lo + v_lo > 1: U 2^C + V 2^B > 2^(B+C).
      const U128 lhs = (U128(b.n[1]) << C) + (U128(b.n[2]) << B);
      if (lhs > (U128(1) << (B + C))) continue;
    }
    // Integer approximations of two directions at the box's start time: the plane normal, and the
    // part of F at the centre of the start face orthogonal to the longest edge (for parallel
    // edges and degenerate triangles). Any integer direction gives a valid exclusion.
    nb = {0, 0, 0};
    mb = {0, 0, 0};
    {
      const long double t = std::ldexp((long double)b.n[0], -A);
      const long double uc = std::ldexp((long double)(2 * b.n[1] + 1), -B - 1),
                        vc = std::ldexp((long double)(2 * b.n[2] + 1), -C - 1);
      long double x[4][3];
      for (int k = 0; k < 4; ++k)
        for (int i = 0; i < 3; ++i) {
          const long double x0 = (long double)q.points[std::size_t(k)][std::size_t(i)];
          x[k][i] = x0 + t * ((long double)q.points[std::size_t(k) + 4][std::size_t(i)] - x0);
        }
      long double e1[3], e2[3], e3[3], nn[3], fc[3];
      for (int i = 0; i < 3; ++i) {
        if (q.vertex_face) {
          e1[i] = x[2][i] - x[1][i];
          e2[i] = x[3][i] - x[1][i];
          fc[i] = x[0][i] - x[1][i] - uc * e1[i] - vc * e2[i];
        } else {
          e1[i] = x[1][i] - x[0][i];
          e2[i] = x[3][i] - x[2][i];
          fc[i] = x[0][i] + uc * e1[i] - x[2][i] - vc * e2[i];
        }
        e3[i] = e2[i] - e1[i];
      }
      nn[0] = e1[1] * e2[2] - e1[2] * e2[1];
      nn[1] = e1[2] * e2[0] - e1[0] * e2[2];
      nn[2] = e1[0] * e2[1] - e1[1] * e2[0];
      auto sq = [](const long double* v) { return v[0] * v[0] + v[1] * v[1] + v[2] * v[2]; };
      const long double* e = sq(e1) >= sq(e2) ? e1 : e2;
      if (q.vertex_face && sq(e3) > sq(e)) e = e3;
      const long double ee = sq(e), s = ee > 0 ? (fc[0] * e[0] + fc[1] * e[1] + fc[2] * e[2]) / ee : 0;
      long double mm[3];
      for (int i = 0; i < 3; ++i) mm[i] = fc[i] - s * e[i];
      auto to_int = [](const long double* v, std::array<std::int64_t, 3>& out) {
        const long double m = std::max({std::fabs(v[0]), std::fabs(v[1]), std::fabs(v[2])});
        if (m > 0)
          for (int i = 0; i < 3; ++i) out[std::size_t(i)] = (std::int64_t)std::llround(v[i] / m * 2305843009213693952.0L);  // 2^61
      };
      to_int(nn, nb);
      to_int(mm, mb);
    }
    // Exact values of every exclusion function at the box's corners (they also guide the split).
    for (int c = 0; c < 8; ++c)
      eval_at(b.n[0] + ((c >> 2) & 1), A, b.n[1] + ((c >> 1) & 1), B, b.n[2] + (c & 1), C, val, std::size_t(c));
    // The exclusion itself looks at the box clipped to the triangle (u + v <= 1): F is linear in t
    // for fixed (u, v) and affine in (u, v) for fixed t, so its range over [t0, t1] x polygon is the
    // hull of its values at (t0 or t1, polygon vertex). Clipping matters near the edge u + v = 1:
    // there the unclipped corners lie beyond the triangle, where a contact may be (a point just past
    // the edge f1-f2 would otherwise need boxes of its distance's size all along the diagonal).
    std::size_t used_points = 8;
    const std::vector<std::array<BigInt, 16>>* excl = &val;
    if (q.vertex_face) {
      // Polygon vertices (U, depth of u, V, depth of v): the corners inside the triangle and the
      // crossings of u + v = 1 with the box's edges (strictly inside an edge).
      struct UV { std::int64_t U; int Bu; std::int64_t V; int Cv; };
      UV poly[8];
      int np = 0;
      const U128 one = U128(1) << (B + C);
      auto sum = [&](std::int64_t U, std::int64_t V) { return (U128(U) << C) + (U128(V) << B); };  // (u + v) 2^(B+C)
      const std::int64_t U0 = b.n[1], V0 = b.n[2];
      bool inside = true;
      for (int c = 0; c < 4; ++c) {
        const std::int64_t U = U0 + ((c >> 1) & 1), V = V0 + (c & 1);
        if (sum(U, V) <= one) poly[np++] = UV{U, B, V, C};
        else inside = false;
      }
      if (!inside) {
        const std::int64_t pb = std::int64_t(1) << B, pc = std::int64_t(1) << C;
        for (int e = 0; e < 2; ++e) {
          const std::int64_t V = V0 + e;  // edge v = V / 2^C: crossing at u = 1 - v
          if (sum(U0, V) < one && sum(U0 + 1, V) > one) poly[np++] = UV{pc - V, C, V, C};
          const std::int64_t U = U0 + e;  // edge u = U / 2^B: crossing at v = 1 - u
          if (sum(U, V0) < one && sum(U, V0 + 1) > one) poly[np++] = UV{U, B, pb - U, B};
        }
        for (int k = 0; k < np; ++k)
          for (int e = 0; e < 2; ++e)
            eval_at(b.n[0] + e, A, poly[k].U, poly[k].Bu, poly[k].V, poly[k].Cv, clipped, std::size_t(2 * k + e));
        used_points = std::size_t(2 * np);
        excl = &clipped;
      }
    }
    bool excluded = false;
    for (std::size_t j = 0; j < nf && !excluded; ++j) {
      bool pos = true, neg = true;
      for (std::size_t c = 0; c < used_points; ++c) {
        const int sg = (*excl)[j][c].sign();
        pos = pos && sg > 0;
        neg = neg && sg < 0;
      }
      excluded = pos || neg;
    }
    if (excluded) continue;
    // Choose the split (heuristic only): prefer a variable whose split lets a half be excluded
    // (approximately), otherwise the one along which the components vary most.
    double hv[8][8];
    const double scale = std::ldexp(1.0, -(A + B + C));
    for (std::size_t j = 0; j < nf && j < 8; ++j)
      for (int c = 0; c < 8; ++c) hv[c][j] = val[j][std::size_t(c)].approx() * scale;
    int dim = -1, best_ex = -1;
    double best_w = -1;
    for (int k = 0; k < 3; ++k) {
      if (b.depth[k] >= kMaxDepth) continue;
      const int bit = 4 >> k;
      int ex = 0;
      double wk = 0;
      for (std::size_t j = 0; j < nf && j < 8; ++j) {
        double l0 = 1e300, h0 = -1e300, l1 = 1e300, h1 = -1e300;
        for (int c = 0; c < 8; ++c) {
          if (c & bit) continue;
          const double x0 = hv[c][j], x1 = hv[c | bit][j], xm = 0.5 * (x0 + x1);
          l0 = std::min({l0, x0, xm}), h0 = std::max({h0, x0, xm});
          l1 = std::min({l1, x1, xm}), h1 = std::max({h1, x1, xm});
          if (j < 3) wk = std::max(wk, std::abs(x1 - x0));
        }
        ex = std::max(ex, int(l0 > 0 || h0 < 0) + int(l1 > 0 || h1 < 0));
      }
      if (ex > best_ex || (ex == best_ex && wk > best_w)) {
        dim = k;
        best_ex = ex;
        best_w = wk;
      }
    }
    if (dim < 0) return ExactAnswer::Unknown;
    XBox lo = b, hi = b;
    lo.n[dim] = 2 * b.n[dim];
    hi.n[dim] = 2 * b.n[dim] + 1;
    lo.depth[dim] = hi.depth[dim] = b.depth[dim] + 1;
    stack.push_back(hi);
    stack.push_back(lo);
  }
  return ExactAnswer::NoContact;
}

/// True when F(t, u, v) == 0 exactly at the dyadic point (T/2^A, U/2^B, V/2^C): a proven contact.
inline bool exact_contact_at(const IntCcdQuery& q, std::int64_t T, int A, std::int64_t U, int B, std::int64_t V, int C) {
  const auto f = detail_exact::corner(q, T, A, U, B, V, C);
  return f[0].zero() && f[1].zero() && f[2].zero();
}

}  // namespace impact::test
