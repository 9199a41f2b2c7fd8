// SPDX-License-Identifier: MIT
// The exact referee of impact-ray-bench: which triangles a segment crosses, and which it crosses
// first, decided in exact integer arithmetic, independent of the library's ray code.
//
// It works on a mesh and segments whose coordinates are all integer multiples of one power of two
// G (the bench puts them there: the mesh's box is moved into [D, 2D] with D a power of two, then
// every coordinate is rounded to float, whose spacing in that range is G = D 2^-23; ray origins
// and directions are multiples of G too). In units of G every coordinate is an integer below 2^26,
// so every orientation determinant is exact in 128-bit integers (below 2^84), and comparing two
// crossing parameters t = n / d (cross-multiplied, below 2^170) is exact in 256 bits.
//
// The rule it applies (closed triangles, closed segments): the segment o -> e crosses triangle abc
// when o and e are not strictly on the same side of its plane, not both in it (a segment in the
// triangle's plane, like a degenerate triangle, counts as no crossing, as in the watertight test
// and in Embree), and the three orientations of the segment's line against the triangle's edges
// have no two opposite strict signs (a line through an edge or a vertex crosses). The crossing
// parameter is t = orient(o) / (orient(o) - orient(e)). A segment that starts exactly on a
// triangle (o in its plane, decided exactly, and its line through the closed triangle) is judged
// by the library's tie rule (query/ray_mesh.hpp) for every library alike: it crosses at t = 0 when
// it enters the surface through the triangle's front face (d . n < 0, n = (b - a) x (c - a) the
// wound normal: a point on a surface is on its front side), and not when it moves away from it, out
// into the front side (before, such a start always counted as a crossing at t = 0, so on a flat mesh,
// where every origin lies in the mesh's plane, the answers of the rule were counted as missed).
// Moving away, a hit at t = 0 on the start's triangle (a ray tracer's convention: the closed
// segment touches it) is accepted too (judge): neither convention counts as wrong.
// The parities that classify touches (count) take every crossing, starts included. Candidates come from the referee's own
// median-split tree over the triangles' exact integer boxes, walked with a slab test padded by a
// whole unit G, so no crossing triangle is ever left out.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <vector>

namespace impact::bench {

// GCC and Clang's 128-bit integers (__extension__: no pedantic warning)
__extension__ typedef __int128 I128;
__extension__ typedef unsigned __int128 U128;

/// A point with integer coordinates (units of G).
struct IPoint {
  std::int64_t x = 0, y = 0, z = 0;
};

/// Exact sign of det[a - d; b - d; c - d] (coordinates below 2^26 in magnitude).
inline I128 orient(const IPoint& a, const IPoint& b, const IPoint& c, const IPoint& d) {
  const std::int64_t adx = a.x - d.x, ady = a.y - d.y, adz = a.z - d.z;
  const std::int64_t bdx = b.x - d.x, bdy = b.y - d.y, bdz = b.z - d.z;
  const std::int64_t cdx = c.x - d.x, cdy = c.y - d.y, cdz = c.z - d.z;
  return I128(adx) * (bdy * cdz - bdz * cdy) + I128(ady) * (bdz * cdx - bdx * cdz) + I128(adz) * (bdx * cdy - bdy * cdx);
}

/// Exact comparison of n1 / d1 and n2 / d2 (d1, d2 > 0, all magnitudes below 2^100): -1, 0, +1.
inline int compare_fractions(I128 n1, I128 d1, I128 n2, I128 d2) {
  // n1 d2 against n2 d1 in 256 bits: split each factor into its sign and 64-bit halves
  struct U256 {
    std::uint64_t w[4] = {0, 0, 0, 0};
  };
  auto mul = [](U128 a, U128 b) {
    const std::uint64_t a0 = std::uint64_t(a), a1 = std::uint64_t(a >> 64), b0 = std::uint64_t(b), b1 = std::uint64_t(b >> 64);
    U256 r;
    const U128 p00 = (U128)a0 * b0, p01 = (U128)a0 * b1, p10 = (U128)a1 * b0,
                            p11 = (U128)a1 * b1;
    r.w[0] = std::uint64_t(p00);
    U128 mid = (p00 >> 64) + std::uint64_t(p01) + std::uint64_t(p10);
    r.w[1] = std::uint64_t(mid);
    U128 hi = (mid >> 64) + (p01 >> 64) + (p10 >> 64) + std::uint64_t(p11);
    r.w[2] = std::uint64_t(hi);
    r.w[3] = std::uint64_t((hi >> 64) + (p11 >> 64));
    return r;
  };
  auto cmp = [](const U256& a, const U256& b) {
    for (int i = 3; i >= 0; --i)
      if (a.w[i] != b.w[i]) return a.w[i] < b.w[i] ? -1 : 1;
    return 0;
  };
  const int s1 = n1 < 0 ? -1 : (n1 > 0 ? 1 : 0), s2 = n2 < 0 ? -1 : (n2 > 0 ? 1 : 0);
  if (s1 != s2) return s1 < s2 ? -1 : 1;
  if (s1 == 0) return 0;
  const auto abs = [](I128 v) { return static_cast<U128>(v < 0 ? -v : v); };
  const int c = cmp(mul(abs(n1), abs(d2)), mul(abs(n2), abs(d1)));
  return s1 > 0 ? c : -c;
}

/// The referee over one mesh (integer vertices, rows of F).
class RayReferee {
 public:
  /// A crossing: t = num / den exactly (den > 0).
  struct Crossing {
    bool hit = false;
    I128 num = 0, den = 1;
  };
  /// The first crossing of a segment: whether there is one, and its exact parameter.
  struct First {
    bool hit = false;
    I128 num = 0, den = 1;
    std::int32_t triangle = -1;  ///< one triangle crossed at that parameter
  };

  RayReferee(std::vector<IPoint> v, std::vector<std::array<int, 3>> f) : v_(std::move(v)), f_(std::move(f)) {
    std::vector<std::int32_t> ids(f_.size());
    std::iota(ids.begin(), ids.end(), 0);
    if (!ids.empty()) {
      nodes_.push_back({});
      build(ids, 0, ids.size(), 0);
    }
    order_ = ids;
  }

  /// Exact crossing of segment o -> e with triangle t; `tie_rule`: a start on the triangle counts
  /// only into its front (see the file comment).
  Crossing cross(const IPoint& o, const IPoint& e, std::int32_t t, bool tie_rule = true) const {
    const auto& f = f_[static_cast<std::size_t>(t)];
    const IPoint &a = v_[static_cast<std::size_t>(f[0])], &b = v_[static_cast<std::size_t>(f[1])], &c = v_[static_cast<std::size_t>(f[2])];
    const I128 so = orient(a, b, c, o), se = orient(a, b, c, e);
    Crossing r;
    if ((so > 0 && se > 0) || (so < 0 && se < 0) || (so == 0 && se == 0)) return r;
    // from the triangle out to its front side (det[a - e; b - e; c - e] = -(e - a) . ((b - a) x
    // (c - a)) < 0 there): away from the surface, no crossing at t = 0 by the tie rule; toward the
    // back side (d . n < 0: through the front face) the crossing at t = 0 counts
    if (tie_rule && so == 0 && se < 0) return r;
    const I128 s1 = orient(o, e, a, b), s2 = orient(o, e, b, c), s3 = orient(o, e, c, a);
    if ((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0)) return r;
    r.hit = true;
    r.num = so;
    r.den = so - se;
    if (r.den < 0) r.num = -r.num, r.den = -r.den;
    return r;
  }

  /// The first crossing of segment o -> e over all triangles.
  First first(const IPoint& o, const IPoint& e) const {
    First best;
    walk(o, e, [&](std::int32_t t) {
      const Crossing c = cross(o, e, t);
      if (c.hit && (!best.hit || compare_fractions(c.num, c.den, best.num, best.den) < 0)) {
        best.hit = true;
        best.num = c.num;
        best.den = c.den;
        best.triangle = t;
      }
    });
    return best;
  }

  /// Number of triangles the segment o -> e crosses (the rule above, a start on a triangle counted
  /// whatever its side: for the parities).
  int count(const IPoint& o, const IPoint& e) const {
    int c = 0;
    walk(o, e, [&](std::int32_t t) { c += cross(o, e, t, false).hit ? 1 : 0; });
    return c;
  }

  /// Judges a method's answer `triangle` (-1: no hit) against the first crossing `ref`:
  /// 0 right, 1 missed (no hit reported, the segment crosses), 2 extra (the reported triangle is
  /// not crossed), 3 first hit skipped (crossed, but strictly after the first crossing).
  int judge(const IPoint& o, const IPoint& e, const First& ref, std::int32_t triangle) const {
    if (triangle < 0) return ref.hit ? 1 : 0;
    if (triangle >= static_cast<std::int32_t>(f_.size())) return 2;
    const Crossing c = cross(o, e, triangle);
    // A hit at t = 0 on the triangle the segment starts on, moving away from it (the only case
    // the tie rule removes), is the other convention, a ray tracer's: the closed segment touches
    // the triangle at its start. Not counted wrong, for any library.
    if (!c.hit) return cross(o, e, triangle, false).hit ? 0 : 2;
    return compare_fractions(c.num, c.den, ref.num, ref.den) > 0 ? 3 : 0;
  }

 private:
  struct Node {
    std::int64_t lo[3], hi[3];
    std::int32_t first = 0, count = 0;  // leaf: range of order_; inner: first = left child (right = first + 1)
  };

  // Calls visit(t) for every triangle t whose grown box the segment o -> e may meet (a superset of
  // the triangles it crosses).
  template <class Visit> void walk(const IPoint& o, const IPoint& e, Visit&& visit) const {
    if (nodes_.empty()) return;
    const double od[3] = {double(o.x), double(o.y), double(o.z)};
    const double dd[3] = {double(e.x - o.x), double(e.y - o.y), double(e.z - o.z)};
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
      const Node& n = nodes_[static_cast<std::size_t>(stack.back())];
      stack.pop_back();
      if (!overlaps(n, od, dd)) continue;
      if (n.count > 0) {
        for (std::int32_t k = n.first; k < n.first + n.count; ++k) visit(order_[static_cast<std::size_t>(k)]);
      } else {
        stack.push_back(n.first);
        stack.push_back(n.first + 1);
      }
    }
  }

  // Builds the subtree of ids[b, e) into node `slot` (children adjacent, appended).
  void build(std::vector<std::int32_t>& ids, std::size_t b, std::size_t e, std::int32_t slot) {
    Node n;
    for (int k = 0; k < 3; ++k) n.lo[k] = INT64_MAX, n.hi[k] = INT64_MIN;
    for (std::size_t i = b; i < e; ++i)
      for (int j = 0; j < 3; ++j) {
        const IPoint& p = v_[static_cast<std::size_t>(f_[static_cast<std::size_t>(ids[i])][static_cast<std::size_t>(j)])];
        const std::int64_t c[3] = {p.x, p.y, p.z};
        for (int k = 0; k < 3; ++k) n.lo[k] = std::min(n.lo[k], c[k]), n.hi[k] = std::max(n.hi[k], c[k]);
      }
    if (e - b <= 4) {
      n.first = static_cast<std::int32_t>(b);
      n.count = static_cast<std::int32_t>(e - b);
      nodes_[static_cast<std::size_t>(slot)] = n;
      return;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (n.hi[k] - n.lo[k] > n.hi[axis] - n.lo[axis]) axis = k;
    auto key = [&](std::int32_t t) {
      std::int64_t s = 0;
      for (int j = 0; j < 3; ++j) {
        const IPoint& p = v_[static_cast<std::size_t>(f_[static_cast<std::size_t>(t)][static_cast<std::size_t>(j)])];
        s += axis == 0 ? p.x : (axis == 1 ? p.y : p.z);
      }
      return s;
    };
    const std::size_t m = b + (e - b) / 2;
    std::nth_element(ids.begin() + static_cast<std::ptrdiff_t>(b), ids.begin() + static_cast<std::ptrdiff_t>(m),
                     ids.begin() + static_cast<std::ptrdiff_t>(e), [&](std::int32_t p, std::int32_t q) { return key(p) < key(q); });
    n.first = static_cast<std::int32_t>(nodes_.size());
    nodes_[static_cast<std::size_t>(slot)] = n;
    nodes_.push_back({});
    nodes_.push_back({});
    build(ids, b, m, n.first);
    build(ids, m, e, n.first + 1);
  }

  // Conservative segment (o + s dd, s in [0, 1]) against the node's box grown by one unit.
  static bool overlaps(const Node& n, const double (&o)[3], const double (&d)[3]) {
    double s0 = 0, s1 = 1;
    for (int k = 0; k < 3; ++k) {
      const double lo = double(n.lo[k] - 1), hi = double(n.hi[k] + 1);
      if (d[k] == 0) {
        if (o[k] < lo || o[k] > hi) return false;
        continue;
      }
      double a = (lo - o[k]) / d[k], b = (hi - o[k]) / d[k];
      if (a > b) std::swap(a, b);
      s0 = std::max(s0, a - 1e-9);
      s1 = std::min(s1, b + 1e-9);
      if (s0 > s1) return false;
    }
    return true;
  }

  std::vector<IPoint> v_;
  std::vector<std::array<int, 3>> f_;
  std::vector<Node> nodes_;
  std::vector<std::int32_t> order_;
};

}  // namespace impact::bench
