// SPDX-License-Identifier: MIT
/// \file
/// The proof that a vertex-face or edge-edge pair moving linearly over the step stays farther than
/// a distance `need` apart from separating directions on the pieces of a bisection of the step:
/// for each piece, the directions of the pair's closest points at its two ends against the
/// convex hull of the pair's vertex offsets there (split_direction_bound). Part of
/// cloth_collision_step's internals (step_bounds.hpp); not part of the interface.
///
/// Why it holds. Over [a, b] every vertex moves linearly, x_k(s) = ((b - s) x_k(a) + (s - a)
/// x_k(b)) / (b - a), and a point of a primitive is a convex combination of its vertices, so the
/// offset between a point of the first primitive and a point of the second at any time s in
/// [a, b] is a convex combination of the vertex offsets x_i(a) - x_j(a) and x_i(b) - x_j(b)
/// (i of the first, j of the second). A unit direction n with n . o > L for each of those offsets
/// o then gives n . y > L, hence |y| > L, for every offset y over [a, b]: the pair stays farther
/// than L apart on the interval. Proving each piece of a split of the step proves the step, with
/// the smallest piece bound as the step's bound. The hulls shrink towards the pair's own offset
/// sets as the pieces shrink, so a pair that slides a long way along its contact while its
/// distance changes little is proved by a few pieces, where a bound from the relative motion
/// alone needs samples a fraction of h apart along the whole slide.
///
/// Rounding: the pieces' end positions (1 - t) x0 + t x1 at dyadic times t (exact in double),
/// the offsets, the directions' lengths (1 up to a few ulps) and the dot products are rounded;
/// `need` must include a margin for that (a few ulps of the coordinates' magnitude), as the
/// caller's other bounds do.
#pragma once

#include "impact/core/types.hpp"

#include <algorithm>
#include <limits>

namespace impact::detail::cloth {

/// The pair's vertex offsets x_i - x_j at the interval's ends A (its start) and B (its end),
/// vertex 0 against 1-2-3 (ee false) or edge 0-1 against 2-3 (ee true), start and end offsets
/// of each vertex pair in turn; returns how many (6 or 8).
inline int pair_offsets(const Vec3<double>* A, const Vec3<double>* B, bool ee, Vec3<double>* o) {
  const int split = ee ? 2 : 1;
  int k = 0;
  for (int i = 0; i < split; ++i)
    for (int j = split; j < 4; ++j) {
      o[k++] = A[i] - A[j];
      o[k++] = B[i] - B[j];
    }
  return k;
}

/// Where a pair is at one time of the step: its distance and the unit direction from the second
/// primitive's closest point to the first's (any unit vector when the distance is 0).
struct PairSample {
  double dist = 0;
  Vec3<double> n = Vec3<double>::UnitZ();
};

/// A lower bound on the distance of the pair over the step, returned when it exceeds `need`;
/// -infinity otherwise. x0 and x1 are the four vertices' positions at the step's start and end
/// (vertex 0 against the face 1-2-3, or the edge 0-1 against the edge 2-3); m bounds how fast
/// the distance changes (the pair's relative motion: |d(s) - d(t)| <= |s - t| m; infinity
/// switches that bound off); `sample(t, X)` gives the pair's PairSample at time t from its
/// positions X there; s0 and s1 are the samples at 0 and 1. Costs at most 2^depth - 1 samples.
/// An interval [a, b] is proved by the larger of (d(a) + d(b) - (b - a) m) / 2 and, for the
/// directions n of the samples at a and b and their normalised sum, the smallest n . o over the
/// pair's vertex offsets o at a and b (the file's comment: every offset over [a, b] is a convex
/// combination of those, so its length is at least that); one that fails is halved at a new
/// sample, down to 2^-depth of the step, and the proof gives up at a sample closer than `need`.
template <class Sample>
double split_direction_bound(const Vec3<double>* x0, const Vec3<double>* x1, bool ee, double need, double m, int depth, const PairSample& s0,
                             const PairSample& s1, Sample&& sample) {
  const double none = -std::numeric_limits<double>::infinity();
  double lb = std::numeric_limits<double>::infinity();
  auto prove = [&](auto& self, double a, double b, const Vec3<double>* A, const Vec3<double>* B, const PairSample& sa, const PairSample& sb,
                   int left) -> bool {
    double best = 0.5 * (sa.dist + sb.dist - (b - a) * m);
    if (!(best > need)) {
      Vec3<double> o[8];
      const int k = pair_offsets(A, B, ee, o);
      Vec3<double> dirs[3] = {sa.n, sb.n, sa.n + sb.n};
      const double len = dirs[2].norm();
      const int nd = len > 0.5 ? 3 : 2;
      if (nd == 3) dirs[2] /= len;
      for (int q = 0; q < nd && !(best > need); ++q) {
        double l = dirs[q].dot(o[0]);
        for (int r = 1; r < k; ++r) l = std::min(l, dirs[q].dot(o[r]));
        best = std::max(best, l);
      }
    }
    if (best > need) {
      lb = std::min(lb, best);
      return true;
    }
    if (left == 0) return false;
    const double mid = 0.5 * (a + b);
    Vec3<double> M[4];
    for (int k = 0; k < 4; ++k) M[k] = (1 - mid) * x0[k] + mid * x1[k];
    const PairSample sm = sample(mid, M);
    if (!(sm.dist > need)) return false;
    return self(self, a, mid, A, M, sa, sm, left - 1) && self(self, mid, b, M, B, sm, sb, left - 1);
  };
  if (!(s0.dist > need) || !(s1.dist > need)) return none;
  return prove(prove, 0.0, 1.0, x0, x1, s0, s1, depth) ? lb : none;
}

}  // namespace impact::detail::cloth
