// SPDX-License-Identifier: MIT
/// \file
/// Bounding sphere of a point set by four methods, so time can be weighed against tightness
/// (impact-fit-bench measures both):
///  - AabbCenter (default): centre of the points' AABB, radius to the farthest point. Two passes.
///  - Centroid: mean of the points, radius to the farthest point. Two passes.
///  - Ritter: Ritter's (1990) two-pass growth from an approximate diameter. About 5-20 % loose.
///  - Exact: the minimal enclosing ball (Welzl 1991, iterative move-to-front form, randomised with
///    a fixed seed so results are reproducible).
/// Contract: every method returns a sphere containing every input point. The radius is always
/// recomputed as the largest distance from the final centre, padded by a few ulps, so rounding in
/// the construction (and degenerate support sets: duplicate, collinear, cospherical points) can
/// make the exact ball slightly larger than minimal, never too small.
#pragma once

#include "impact/geometry/aabb.hpp"
#include "impact/geometry/sphere.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

namespace impact {

enum class SphereFit {
  AabbCenter,  ///< centre of the bounding box (default: cheapest, within ~sqrt(3) of optimal)
  Centroid,    ///< mean of the points
  Ritter,      ///< Ritter's approximate diameter and growth
  Exact        ///< minimal enclosing ball (Welzl)
};

namespace detail {

/// Radius of the smallest sphere centred at c that holds all points, padded so that rounding in
/// later distance computations cannot put a point outside.
template <class S> S enclosing_radius(const Vec3<S>& c, const Vec3<S>* pts, std::size_t n) {
  S r2 = S(0);
  for (std::size_t i = 0; i < n; ++i) r2 = std::max(r2, (pts[i] - c).squaredNorm());
  const S r = std::sqrt(r2);
  return r * (S(1) + S(8) * std::numeric_limits<S>::epsilon()) + std::numeric_limits<S>::denorm_min();
}

template <class S> struct Ball {
  Vec3<S> c;
  S r2;  // squared radius
  bool contains(const Vec3<S>& p) const {
    // relative slack: points on the boundary (rounding) count as inside
    return (p - c).squaredNorm() <= r2 * (S(1) + S(64) * std::numeric_limits<S>::epsilon());
  }
};

template <class S> Ball<S> ball_on_2(const Vec3<S>& a, const Vec3<S>& b) {
  const Vec3<S> c = (a + b) / S(2);
  return {c, std::max((a - c).squaredNorm(), (b - c).squaredNorm())};
}

/// Smallest ball with a, b, c on its boundary (the circumcircle of the triangle); for collinear or
/// coincident points the ball on the farthest pair, which then holds the third.
template <class S> Ball<S> ball_on_3(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c) {
  const Vec3<S> ab = b - a, ac = c - a;
  const Vec3<S> n = ab.cross(ac);
  const S n2 = n.squaredNorm();
  const S scale = ab.squaredNorm() * ac.squaredNorm();
  if (!(n2 > S(1e3) * std::numeric_limits<S>::epsilon() * scale)) {
    Ball<S> best = ball_on_2(a, b);
    for (const Ball<S>& cand : {ball_on_2(a, c), ball_on_2(b, c)})
      if (cand.r2 > best.r2) best = cand;
    return best;
  }
  const Vec3<S> off = (ac.squaredNorm() * n.cross(ab) + ab.squaredNorm() * ac.cross(n)) / (S(2) * n2);
  const Vec3<S> ctr = a + off;
  return {ctr, std::max({(a - ctr).squaredNorm(), (b - ctr).squaredNorm(), (c - ctr).squaredNorm()})};
}

/// Smallest ball with a, b, c, d on its boundary (circumsphere); for (nearly) coplanar points the
/// smallest ball on three of them that holds the fourth.
template <class S> Ball<S> ball_on_4(const Vec3<S>& a, const Vec3<S>& b, const Vec3<S>& c, const Vec3<S>& d) {
  const Vec3<S> u = b - a, v = c - a, w = d - a;
  const S det = u.dot(v.cross(w));
  const S scale = u.norm() * v.norm() * w.norm();
  if (std::abs(det) > S(1e3) * std::numeric_limits<S>::epsilon() * scale) {
    const Vec3<S> off =
        (u.squaredNorm() * v.cross(w) + v.squaredNorm() * w.cross(u) + w.squaredNorm() * u.cross(v)) / (S(2) * det);
    const Vec3<S> ctr = a + off;
    const S r2 = std::max({(a - ctr).squaredNorm(), (b - ctr).squaredNorm(), (c - ctr).squaredNorm(), (d - ctr).squaredNorm()});
    return {ctr, r2};
  }
  const Vec3<S>* p[4] = {&a, &b, &c, &d};
  Ball<S> best{a, std::numeric_limits<S>::infinity()};
  for (int skip = 0; skip < 4; ++skip) {
    const Vec3<S>* q[3];
    int k = 0;
    for (int i = 0; i < 4; ++i)
      if (i != skip) q[k++] = p[i];
    Ball<S> cand = ball_on_3(*q[0], *q[1], *q[2]);
    if (cand.contains(*p[skip]) && cand.r2 < best.r2) best = cand;
  }
  if (!std::isfinite(best.r2)) {  // nothing held the fourth point: take the largest
    best = ball_on_3(a, b, c);
    for (int skip = 0; skip < 3; ++skip) {
      Ball<S> cand = ball_on_3(skip == 0 ? d : a, skip == 1 ? d : b, skip == 2 ? d : c);
      if (cand.r2 > best.r2) best = cand;
    }
  }
  return best;
}

/// Welzl's minimal ball, iterative nested form (expected linear time after a random shuffle).
template <class S> Sphere<S> minimal_ball(std::vector<Vec3<S>> p) {
  // fixed-seed shuffle (xorshift) for reproducible results
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  for (std::size_t i = p.size(); i > 1; --i) {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    std::swap(p[i - 1], p[state % i]);
  }
  const std::size_t n = p.size();
  Ball<S> B{p[0], S(0)};
  for (std::size_t i = 1; i < n; ++i) {
    if (B.contains(p[i])) continue;
    B = {p[i], S(0)};
    for (std::size_t j = 0; j < i; ++j) {
      if (B.contains(p[j])) continue;
      B = ball_on_2(p[i], p[j]);
      for (std::size_t k = 0; k < j; ++k) {
        if (B.contains(p[k])) continue;
        B = ball_on_3(p[i], p[j], p[k]);
        for (std::size_t l = 0; l < k; ++l) {
          if (B.contains(p[l])) continue;
          B = ball_on_4(p[i], p[j], p[k], p[l]);
        }
      }
    }
  }
  return {B.c, enclosing_radius(B.c, p.data(), n)};
}

template <class S> Sphere<S> ritter_sphere(const Vec3<S>* pts, std::size_t n) {
  auto farthest = [&](const Vec3<S>& from) {
    std::size_t best = 0;
    S d2 = S(-1);
    for (std::size_t i = 0; i < n; ++i) {
      const S d = (pts[i] - from).squaredNorm();
      if (d > d2) d2 = d, best = i;
    }
    return best;
  };
  const std::size_t y = farthest(pts[0]);
  const std::size_t z = farthest(pts[y]);
  Vec3<S> c = (pts[y] + pts[z]) / S(2);
  S r = (pts[z] - c).norm();
  for (std::size_t i = 0; i < n; ++i) {
    const S d = (pts[i] - c).norm();
    if (d > r) {
      const S nr = (r + d) / S(2);
      c += (pts[i] - c) * ((nr - r) / d);
      r = nr;
    }
  }
  return {c, enclosing_radius(c, pts, n)};
}

}  // namespace detail

/// Bounding sphere of n points by the chosen method. n == 0 gives an empty sphere (radius -1).
/// Time: linear for all methods (Exact: expected linear). Points must be finite.
template <class S> Sphere<S> bounding_sphere(const Vec3<S>* pts, std::size_t n, SphereFit method = SphereFit::AabbCenter) {
  if (n == 0) return {};
  switch (method) {
    case SphereFit::Centroid: {
      Vec3<S> c = Vec3<S>::Zero();
      for (std::size_t i = 0; i < n; ++i) c += pts[i];
      c /= S(n);
      return {c, detail::enclosing_radius(c, pts, n)};
    }
    case SphereFit::Ritter:
      return detail::ritter_sphere(pts, n);
    case SphereFit::Exact:
      return detail::minimal_ball(std::vector<Vec3<S>>(pts, pts + n));
    case SphereFit::AabbCenter:
    default: {
      Aabb<S> box;
      for (std::size_t i = 0; i < n; ++i) box.extend(pts[i]);
      const Vec3<S> c = box.center();
      return {c, detail::enclosing_radius(c, pts, n)};
    }
  }
}

template <class S> Sphere<S> bounding_sphere(const std::vector<Vec3<S>>& pts, SphereFit method = SphereFit::AabbCenter) {
  return bounding_sphere(pts.data(), pts.size(), method);
}

}  // namespace impact
