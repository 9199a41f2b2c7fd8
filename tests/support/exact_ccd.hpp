// SPDX-License-Identifier: MIT
// An exact reference for the CCD tests, independent of the library's floating-point search.
// Inputs are integer coordinates (the test converts them to double or float by one exact power of
// two scale). F is the difference of the two closest candidates: vertex-face p - f0 - u (f1 - f0)
// - v (f2 - f0), edge-edge a0 + u (a1 - a0) - b0 - v (b1 - b0). Its values at dyadic parameters
// are integers after scaling by 2^(A+B+C), computed exactly in a 320-bit two's-complement integer.
// The search runs over the unit cube of (t, u, v) for edge-edge and of (t, w, s) for vertex-face,
// with u = w (1 - s), v = w s (the triangle as a collapsed square: w = u + v, s the position along
// the edge u + v = w). F is linear in each variable separately in both cases, so its exact range
// on a box is the hull of the 8 corner values, and a box whose corner values of one component (or
// of n . F for an integer direction n) all have one strict sign contains no contact. (In (u, v)
// the triangle is half a square: boxes across u + v = 1 had corners beyond the face, and a
// degenerate face, where F depends on u + v alone, was cut into slivers along that sum.)
// certify_no_contact subdivides until every box is excluded (a proof that there is no contact for
// t in [0, 1]) or gives up (Unknown) after a budget, at depth 60 per variable, or on reaching a
// point where F is exactly 0 (a contact). Besides the given directions, each box also tries
// integer approximations of the plane normal and of a separating direction at the box's start
// time (any integer n is valid). Bounds: |coordinate| < 2^53, depth <= 60 and |n_i| <= 2^61 keep
// every value below 2^301 (the integers have 320 bits): corner values of F stay below 2^237, each
// product with n_i below 2^298.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>
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

// One box: low end numerator and depth per variable (t, u, v or t, w, s); the interval is
// [n / 2^depth, (n + 1) / 2^depth].
struct XBox {
  std::int64_t n[3];
  int depth[3];
};

// Coordinate i of the four points at t = T/2^A, scaled by 2^A.
inline std::array<BigInt, 4> positions_at(const IntCcdQuery& q, std::int64_t T, int A, int i) {
  std::array<BigInt, 4> x;
  for (std::size_t k = 0; k < 4; ++k) {
    const std::int64_t x0 = q.points[k][std::size_t(i)], x1 = q.points[k + 4][std::size_t(i)];
    x[k] = BigInt::from(x0).shl(A) + BigInt::from(x1 - x0).mul(T);
  }
  return x;
}

// F scaled by 2^(A+B+C) at the corner (t = T/2^A, u = U/2^B, v = V/2^C), all three components.
inline std::array<BigInt, 3> corner(const IntCcdQuery& q, std::int64_t T, int A, std::int64_t U, int B, std::int64_t V, int C) {
  std::array<BigInt, 3> out;
  for (int i = 0; i < 3; ++i) {
    const auto x = positions_at(q, T, A, i);
    if (q.vertex_face) {
      const BigInt e0 = x[0] - x[1], e1 = x[2] - x[1], e2 = x[3] - x[1];
      out[std::size_t(i)] = e0.shl(B + C) - e1.shl(C).mul(U) - e2.shl(B).mul(V);
    } else {
      out[std::size_t(i)] = x[0].shl(B + C) + (x[1] - x[0]).shl(C).mul(U) - x[2].shl(B + C) - (x[3] - x[2]).shl(B).mul(V);
    }
  }
  return out;
}

// Vertex-face F scaled by 2^(A+B+C) at (t = T/2^A, w = W/2^B, s = S/2^C), that is at
// u = w (1 - s), v = w s: e0 2^(B+C) - e1 W (2^C - S) - e2 W S with e_k scaled by 2^A.
inline std::array<BigInt, 3> corner_ws(const IntCcdQuery& q, std::int64_t T, int A, std::int64_t W, int B, std::int64_t S, int C) {
  std::array<BigInt, 3> out;
  const std::int64_t rest = (std::int64_t(1) << C) - S;
  for (int i = 0; i < 3; ++i) {
    const auto x = positions_at(q, T, A, i);
    const BigInt e0 = x[0] - x[1], e1 = x[2] - x[1], e2 = x[3] - x[1];
    out[std::size_t(i)] = e0.shl(B + C) - e1.mul(W).mul(rest) - e2.mul(W).mul(S);
  }
  return out;
}

// The same vertex-face query with the face's vertices reordered so that f0, the apex of the
// collapsed square, is opposite the face's shortest edge (longest of its two ends). F then varies
// least along s; for a face with two coincident vertices it does not depend on s at all, whereas
// with the apex at one of them it would depend on the product w s (boxes along a hyperbola).
inline IntCcdQuery apex_opposite_shortest_edge(IntCcdQuery q) {
  if (!q.vertex_face) return q;
  auto len2 = [&](std::size_t a, std::size_t b) {
    long double m = 0;
    for (std::size_t e = 0; e < 8; e += 4) {
      long double l = 0;
      for (std::size_t i = 0; i < 3; ++i) {
        const long double d = (long double)q.points[a + e][i] - (long double)q.points[b + e][i];
        l += d * d;
      }
      m = std::max(m, l);
    }
    return m;
  };
  // Apex 1 (f0) faces edge 2-3, apex 2 faces 1-3, apex 3 faces 1-2 (indices into points).
  const long double l1 = len2(2, 3), l2 = len2(1, 3), l3 = len2(1, 2);
  const std::size_t apex = l1 <= l2 && l1 <= l3 ? 1 : (l2 <= l3 ? 2 : 3);
  if (apex != 1)
    for (std::size_t e = 0; e < 8; e += 4) std::swap(q.points[1 + e], q.points[apex + e]);
  return q;
}

}  // namespace detail_exact

/// Tries to prove that the closed primitives never touch for t in [0, 1] (distance 0; no minimum
/// separation). `directions`: optional integer directions n (each |n_i| <= 2^61) whose n . F is
/// also used to exclude boxes, e.g. the normal of a plane of coplanar motion. NoContact is a
/// proof; Unknown means the budget (boxes) or the depth limit ran out, or a contact was found.
inline ExactAnswer certify_no_contact(const IntCcdQuery& query, const std::vector<std::array<std::int64_t, 3>>& directions = {},
                                      std::size_t budget = 200000) {
  using detail_exact::XBox;
  const IntCcdQuery q = detail_exact::apex_opposite_shortest_edge(query);
  std::vector<XBox> stack{XBox{{0, 0, 0}, {0, 0, 0}}};
  const int kMaxDepth = 60;
  std::size_t used = 0;
  const std::size_t nf = 5 + directions.size();
  // Values of the exclusion functions (3 components, the two box directions, the given
  // directions) at a box's 8 corners; nb and mb are set per box below.
  std::vector<std::array<BigInt, 8>> val(nf);
  std::array<std::int64_t, 3> nb{0, 0, 0}, mb{0, 0, 0};
  // Corner `slot` of a box at (t, second, third variable) = (T/2^A, X/2^B, Y/2^C).
  auto eval_at = [&](std::int64_t T, int A, std::int64_t X, int B, std::int64_t Y, int C, std::size_t slot) {
    const auto f = q.vertex_face ? detail_exact::corner_ws(q, T, A, X, B, Y, C) : detail_exact::corner(q, T, A, X, B, Y, C);
    for (std::size_t i = 0; i < 3; ++i) val[i][slot] = f[i];
    val[3][slot] = f[0].mul(nb[0]) + f[1].mul(nb[1]) + f[2].mul(nb[2]);
    val[4][slot] = f[0].mul(mb[0]) + f[1].mul(mb[1]) + f[2].mul(mb[2]);
    for (std::size_t j = 0; j < directions.size(); ++j)
      val[5 + j][slot] = f[0].mul(directions[j][0]) + f[1].mul(directions[j][1]) + f[2].mul(directions[j][2]);
  };
  while (!stack.empty()) {
    const XBox b = stack.back();
    stack.pop_back();
    if (++used > budget) return ExactAnswer::Unknown;
    const int A = b.depth[0], B = b.depth[1], C = b.depth[2];
    // Integer approximations of two directions at the box's start time: the plane normal, and the
    // part of F at the centre of the start face orthogonal to the longest edge (for parallel
    // edges and degenerate triangles). Any integer direction gives a valid exclusion.
    nb = {0, 0, 0};
    mb = {0, 0, 0};
    {
      const long double t = std::ldexp((long double)b.n[0], -A);
      const long double c1 = std::ldexp((long double)(2 * b.n[1] + 1), -B - 1),
                        c2 = std::ldexp((long double)(2 * b.n[2] + 1), -C - 1);
      const long double uc = q.vertex_face ? c1 * (1 - c2) : c1, vc = q.vertex_face ? c1 * c2 : c2;
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
    // Exact values of every exclusion function at the box's corners.
    for (int c = 0; c < 8; ++c)
      eval_at(b.n[0] + ((c >> 2) & 1), A, b.n[1] + ((c >> 1) & 1), B, b.n[2] + (c & 1), C, std::size_t(c));
    // A point of the domain where F is exactly 0 is a contact: nothing left to prove.
    for (std::size_t c = 0; c < 8; ++c)
      if (val[0][c].zero() && val[1][c].zero() && val[2][c].zero()) return ExactAnswer::Unknown;
    bool excluded = false;
    for (std::size_t j = 0; j < nf && !excluded; ++j) {
      bool pos = true, neg = true;
      for (std::size_t c = 0; c < 8; ++c) {
        const int sg = val[j][c].sign();
        pos = pos && sg > 0;
        neg = neg && sg < 0;
      }
      excluded = pos || neg;
    }
    if (excluded) continue;
    // Choose the split (heuristic only): prefer a variable whose split lets a half be excluded
    // (approximately), otherwise the one along which the functional nearest to excluding the box
    // varies most (the least share of its range on the minority side of 0; the components when
    // none qualifies). Splitting where the components vary most instead cut degenerate faces
    // (F depends on u + v alone) into ~10^5 slivers along u + v where one split in t settled them.
    double hv[8][8];
    const double scale = std::ldexp(1.0, -(A + B + C));
    for (std::size_t j = 0; j < nf && j < 8; ++j)
      for (int c = 0; c < 8; ++c) hv[c][j] = val[j][std::size_t(c)].approx() * scale;
    std::size_t jstar = nf;  // none
    {
      double best_frac = 2;
      for (std::size_t j = 0; j < nf && j < 8; ++j) {
        double l = 1e300, h = -1e300;
        for (int c = 0; c < 8; ++c) l = std::min(l, hv[c][j]), h = std::max(h, hv[c][j]);
        const double frac = h > l ? std::min(-l, h) / (h - l) : 2;
        if (frac < best_frac) best_frac = frac, jstar = j;
      }
    }
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
          if (jstar < nf ? j == jstar : j < 3) wk = std::max(wk, std::abs(x1 - x0));
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
