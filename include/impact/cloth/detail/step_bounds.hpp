// SPDX-License-Identifier: MIT
/// \file
/// Stepper's proofs that a candidate stays farther than h over the step without a CCD search:
/// distance bounds (start boxes, relative motion, both ends, a fixed separating direction),
/// sampling along the step (clear hits and misses), closest points, and the path lengths that
/// keep a proof valid across passes.
/// Part of cloth_collision_step's internals (stepper.hpp); not part of the interface.
#pragma once

#include "impact/cloth/detail/hull_proofs.hpp"
#include "impact/cloth/detail/stepper.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact::detail::cloth {

/// Lower bound on the distance of the pair's primitives at x0: the gap between their start
/// boxes (in double).
template <class S>
double Stepper<S>::start_box_distance(const Prim& p) const {
  Vec3<double> lo[2], hi[2];
  const int split = p.ee ? 2 : 1;
  for (int s = 0; s < 2; ++s) lo[s] = Vec3<double>::Constant(std::numeric_limits<double>::infinity()), hi[s] = -lo[s];
  for (int k = 0; k < 4; ++k) {
    const int s = k < split ? 0 : 1;
    const Vec3<double> x = p0(p.v[k]);
    lo[s] = lo[s].cwiseMin(x), hi[s] = hi[s].cwiseMax(x);
  }
  const Vec3<double> gap = (lo[1] - hi[0]).cwiseMax(lo[0] - hi[1]).cwiseMax(0.0);
  return gap.norm();
}

/// The largest relative displacement over the step between a point of one primitive and a point
/// of the other: every point of a primitive moves by a convex combination of its vertices'
/// displacements, so the difference of the two is at most the largest vertex-pair difference.
template <class S>
double Stepper<S>::relative_motion(const Prim& p) const {
  const int split = p.ee ? 2 : 1;
  Vec3<double> d[4];
  for (int k = 0; k < 4; ++k) d[k] = p1(p.v[k]) - p0(p.v[k]);
  double m2 = 0;  // the largest squared norm: one square root (the same value, sqrt being monotone)
  for (int i = 0; i < split; ++i)
    for (int j = split; j < 4; ++j) m2 = std::max(m2, (d[i] - d[j]).squaredNorm());
  return std::sqrt(m2);
}

/// A lower bound on the pair's distance over the whole step, returned when it exceeds
/// need = h + bound_margin_ (the pair provably stays farther apart than h, so its CCD can be
/// skipped); -infinity when no bound proves that. With m the pair's relative motion
/// (relative_motion: for fixed barycentric weights the points' offset changes by t times a
/// convex combination of vertex-pair displacement differences, at most m long), the distance at
/// time t is at least d(0) - t m and at least d(1) - (1 - t) m, so at least their mean
/// (d(0) + d(1) - m) / 2 over the whole step. First the start bound alone (d(0) - m, the start
/// distance cached per candidate: a box bound, then the exact one), then both ends, then
/// separating directions on pieces of the step (split_bound). A margin covers rounding. Thread-safe per index. `known` receives m and the exact distances computed
/// (when it returns -infinity, d(0) always, d(1) unless d(0) <= need) and the directions of
/// the closest points where it computed them, for split_bound and sample_pair.
template <class S>
double Stepper<S>::separation_bound(std::size_t i, Measured& known) {
  const Prim& p = cand_[i];
  const double m = relative_motion(p), need = h_ + bound_margin_, none = -std::numeric_limits<double>::infinity();
  known = Measured();
  known.m = m;
  if (std::isnan(d0_[i])) d0_[i] = start_box_distance(p);
  if (d0_[i] > need + m) return d0_[i] - m;
  if (!d0_exact_[i]) {
    const Contact c0 = closest(p, /*start=*/true);
    d0_[i] = c0.dist;
    d0_exact_[i] = 1;
    known.n0 = c0.n, known.has_n0 = true;
    if (d0_[i] > need + m) return d0_[i] - m;
  }
  known.d0 = d0_[i];
  if (d0_[i] <= need) return none;  // nothing below can help: each bound is <= d(0)
  const Contact c1 = closest(p, /*start=*/false);
  known.d1 = c1.dist;
  known.n1 = c1.n;
  const double both = 0.5 * (d0_[i] + c1.dist - m);
  if (both > need) return both;
  // Sliding pairs (a large relative motion along the contact, as in resting contact) fail the
  // bounds above; separating directions on pieces of the step prove most of them (split_bound).
  return split_bound(p, known);
}

/// A lower bound on the pair's distance over the step from the separating directions of its
/// closest points on the pieces of a bisection of the step (split_direction_bound in
/// hull_proofs.hpp, which says why it holds; down to 2^-split_depth_ of the step, each piece
/// also tried by the relative-motion bound of its two ends), for a pair that the bounds before it
/// in separation_bound could not prove: returned when it exceeds need = h + bound_margin_, else
/// -infinity. It needs the distances at both ends (`known`), farther than need; the directions
/// there are those separation_bound measured, or the start's closest points again when d(0) was
/// cached by an earlier pass. Pairs sliding far along a contact were left to sample_pair, whose
/// samples are h / 4 of relative motion apart (tens of closest points each); a few pieces of the
/// step give them a separating direction each. The rounding of the pieces' positions, of the
/// directions' lengths and of the dot products is covered by the margin in need, as for
/// sample_pair.
template <class S>
double Stepper<S>::split_bound(const Prim& p, const Measured& known) const {
  const double need = h_ + bound_margin_, none = -std::numeric_limits<double>::infinity();
  if (!(known.d0 > need) || !(known.d1 > need)) return none;
  Vec3<double> a[4], b[4];
  for (int k = 0; k < 4; ++k) a[k] = p0(p.v[k]), b[k] = p1(p.v[k]);
  auto sample = [&](double, const Vec3<double>* X) {
    const Contact c = closest_at(p, [&](int k) { return X[k]; });
    PairSample s;
    s.dist = c.dist, s.n = c.n;
    return s;
  };
  PairSample s0, s1;
  if (known.has_n0) {
    s0.dist = known.d0, s0.n = known.n0;
  } else {
    s0 = sample(0.0, a);
  }
  s1.dist = known.d1, s1.n = known.n1;
  return split_direction_bound(a, b, p.ee != 0, need, known.m, split_depth_, s0, s1, sample);
}

/// Clear hits and clear misses without the CCD's search, in every stage. A hit only gives a
/// constraint (the step's guarantee rests on the misses); a miss is proved. With m the pair's
/// relative motion (relative_motion: the distance changes by at most (t' - t) m between times t
/// and t'), the distance is sampled (exact closest points, in double) at n + 1 evenly spaced
/// times, n = ceil(4 m / h) (so it changes by at most h / 4 between samples; pairs with
/// m > (max_samples_ / 4) h = 32 h, which would need more than max_samples_ intervals, are left
/// to the search).
/// Hit: at the first sample closer than h (a contact, up to the rounding margin), the time just
/// before the distance falls to h + band_ / 2 is bisected between it and the sample before; the
/// pair was farther than 3 h / 4 before it (the samples are h / 4 apart in distance), so it had
/// not crossed, and the closest points there give the normal, as at the search's time of impact.
/// Miss: between two samples at t < t' with distances d, d' the distance is at least
/// max(d - (s - t) m, d' - (t' - s) m) >= (d + d' - (t' - t) m) / 2 at every time s; when that
/// exceeds need = h + bound_margin_ on every interval (an interval that fails it is halved, up
/// to three times, at a new sample), the smallest such bound (a lower bound on the distance over
/// the step) is `bound`. The margin covers the rounding of the samples' positions and distances
/// (computed in double from coordinates of magnitude <= scale_, as the other bounds').
/// Unknown (the search decides): everything else, and pairs closer than h at the start.
/// `known` is what separation_bound measured for the pair: its relative motion, and its
/// distances at t = 0 and t = 1 where known (NaN otherwise), which are the samples there bit for
/// bit (a sample's positions (1 - t) x0 + t x1 are x0 and x1 at those times), so they are not
/// computed again. Thread-safe.
template <class S>
typename Stepper<S>::Sampled Stepper<S>::sample_pair(const Prim& p, const Measured& known, CcdResult<S>& r, double& bound) const {
  const double m = known.m;
  static_assert(max_samples_ % 4 == 0, "the motion bound below is max_samples_ / 4 intervals of h");
  if (!(m <= (max_samples_ / 4) * h_)) return Sampled::unknown;  // so 4 m / h <= max_samples_ exactly
  const int n = std::max(2, static_cast<int>(std::ceil(4 * m / h_)));
  auto dist = [&](double t) {
    if (t == 0.0 && !std::isnan(known.d0)) return known.d0;
    if (t == 1.0 && !std::isnan(known.d1)) return known.d1;
    auto X = [&](int j) { return Vec3<double>((1 - t) * p0(p.v[j]) + t * p1(p.v[j])); };
    return closest_at(p, X).dist;
  };
  const double inside = h_ - bound_margin_, aim = h_ + 0.5 * band_, need = h_ + bound_margin_;
  double lb = std::numeric_limits<double>::infinity();
  // whether the distance stays above need on [a, b] (distances da, db there), halving up to depth times
  auto prove = [&](auto& self, double a, double b, double da, double db, int depth) -> bool {
    const double l = 0.5 * (da + db - (b - a) * m);
    if (l > need) {
      lb = std::min(lb, l);
      return true;
    }
    if (depth == 0) return false;
    const double mid = 0.5 * (a + b), dm = dist(mid);
    if (!(dm > need)) return false;
    return self(self, a, mid, da, dm, depth - 1) && self(self, mid, b, dm, db, depth - 1);
  };
  double prev = dist(0.0);
  if (prev < inside) return Sampled::unknown;  // closer than h at the start: the search decides
  // The samples computed so far (NaN: not yet). First the first sample closer than h is looked
  // for by skipping the samples the last computed one proves farther: from sample j at distance
  // d_j the distance at t_i is at least d_j - (t_i - t_j) m, so every sample i with
  // (i - j) m / n <= d_j - far is at least `far` = inside + 2 bound_margin_ away and computes
  // to at least inside (the margin covers the rounding of the samples' positions and distances,
  // as for every bound here; the factor 1 - 1e-9 the rounding of the index). The first computed
  // sample closer than `inside` is then the first of all, the one the loop below returns at:
  // the same hit, with the samples of a pair approaching head-on instead of every h / 4. When
  // there is none, the loop below runs as it would without this, on the samples computed here.
  double ds[max_samples_ + 1];
  if (n > max_samples_) return Sampled::unknown;  // (not reached: m is bounded above)
  std::fill(ds, ds + n + 1, std::numeric_limits<double>::quiet_NaN());
  ds[0] = prev;
  auto sample = [&](int k) {
    if (std::isnan(ds[k])) ds[k] = dist(double(k) / n);
    return ds[k];
  };
  const double far = inside + 2 * bound_margin_;
  int first_in = -1;
  for (int j = 0; j < n;) {
    const double dj = ds[j];
    int skip = 0;
    if (dj > far && m > 0) skip = static_cast<int>(std::min(double(n), std::floor((dj - far) / m * n * (1 - 1e-9))));
    const int k = j + std::max(skip, 0) + 1;
    if (k > n) break;
    if (sample(k) < inside) {
      first_in = k;
      break;
    }
    j = k;
  }
  bool proved = true;
  for (int k = 1; k <= n; ++k) {
    if (first_in >= 0 && k < first_in) continue;  // each farther than inside (above)
    if (first_in >= 0) prev = sample(k - 1);
    const double t = double(k) / n, d = sample(k);
    if (d < inside) {
      double lo = double(k - 1) / n, hi = t;
      if (prev > aim)
        for (int it = 0; it < 12; ++it) {
          const double mid = 0.5 * (lo + hi);
          (dist(mid) > aim ? lo : hi) = mid;
        }
      r = CcdResult<S>();
      r.hit = true;
      r.toi = static_cast<decltype(r.toi)>(lo);
      return Sampled::hit;
    }
    proved = proved && prove(prove, double(k - 1) / n, t, prev, d, 3);
    prev = d;
  }
  if (!proved) return Sampled::unknown;
  bound = lb;
  return Sampled::miss;
}

/// Notes the end positions' moves since the last call: a vertex whose end position changed
/// counts as moved (changed_) and its path length grows by the distance moved. Every write to
/// the end positions is seen here, whichever stage made it.
template <class S>
void Stepper<S>::note_moves() {
  ++moves_noted_;
  const std::size_t nv = sys_.w.size();
  for (std::size_t v = 0; v < nv; ++v) {
    const Eigen::Index r = Eigen::Index(v);
    if (sys_.X1.row(r) == x1_seen_.row(r)) continue;
    path_[v] += (sys_.X1.row(r).template cast<double>() - x1_seen_.row(r).template cast<double>()).norm();
    x1_seen_.row(r) = sys_.X1.row(r);
    changed_[v] = 1;
  }
}

/// The sum of the path lengths of the pair's vertices (note_moves).
template <class S>
double Stepper<S>::path_sum(const Prim& p) const {
  return path_[std::size_t(p.v[0])] + path_[std::size_t(p.v[1])] + path_[std::size_t(p.v[2])] + path_[std::size_t(p.v[3])];
}

/// Closest points of a pair at x0 (start) or x1, in double: distance, weights, unit normal.
template <class S>
typename Stepper<S>::Contact Stepper<S>::closest(const Prim& p, bool start) const {
  return closest_at(p, [&](int k) { return start ? p0(p.v[k]) : p1(p.v[k]); });
}

template <class S>
template <class Pos>
typename Stepper<S>::Contact Stepper<S>::closest_at(const Prim& p, Pos&& X) {
  Contact c;
  if (p.ee) {
    const auto r = closest_points_segment_segment(Segment<double>(X(0), X(1)), Segment<double>(X(2), X(3)));
    c.a[0] = 1 - r.s, c.a[1] = r.s, c.a[2] = -(1 - r.t), c.a[3] = -r.t;
  } else {
    const auto r = closest_point_on_triangle(X(0), Triangle<double>(X(1), X(2), X(3)));
    c.a[0] = 1, c.a[1] = -r.barycentric[0], c.a[2] = -r.barycentric[1], c.a[3] = -r.barycentric[2];
  }
  Vec3<double> d = Vec3<double>::Zero();
  for (int k = 0; k < 4; ++k) d += c.a[k] * X(k);
  c.dist = d.norm();
  if (c.dist > 0) c.n = d / c.dist;
  return c;
}

}  // namespace impact::detail::cloth
