// SPDX-License-Identifier: MIT
/// \file
/// The overlap of a cone and a box as the terms of convex/local_certificate.hpp, so that the local
/// certificate stops EPA early on cone–box penetrations as it does for cylinder pairs.
///
/// In the cone's frame (base disc of radius r at z = -h, apex at +h) with the box placed by R, t
/// (half extents e), f(w) = h_A(w) + h_B(-w) with
///   h_A(w) = max(h w_z, r |P_z w| - h w_z)       (the apex or the base rim),
///   h_B(-w) = -t . w + sum_i e_i |R_i . w|        (three abs terms, R_i the box's axes),
/// so each branch of the cone gives a lower bound of f everywhere: the apex a linear term, the
/// rim a disc term about z plus a linear one (at most four terms with the box's). Where the two
/// branches tie (w normal to a side ruling) there are no terms: a body inside the cone touching
/// that ruling, as cylinder–cone uses, cost more than it saved here (callgrind over the bench's
/// cone–box poses: 4,385 instructions per query without it, 5,213 with it).
/// Numerical contract: the terms are exact expressions of the supports (rounding only).
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>

namespace impact::detail {

/// Adds the box's terms (b placed by R, t in the frame of the terms): h_B(-w) = -t . w + sum_i
/// e_i |R_i . w|.
template <class S>
void add_box_terms(const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, OverlapTerms<S>& f) {
  for (int i = 0; i < 3; ++i) f.add(Vec3<S>(R.col(i)), b.half[i], false);
  f.linear -= t;
}

/// How far cone a's (its frame) apex supports unit n beyond its base rim: h n_z minus
/// r |P_z n| - h n_z (positive: the apex, negative: the rim, 0 on a side ruling's normal).
template <class S>
S cone_branch_gap(const Cone<S>& a, const Vec3<S>& n) {
  const S nz = n.z(), apex = a.half_length * nz, rim = a.radius * std::sqrt(std::max(S(1) - nz * nz, S(0))) - a.half_length * nz;
  return apex - rim;
}

/// The branch of cone a whose support gap (cone_branch_gap) is `gap`: 1 its apex, 2 its base rim,
/// 0 when they tie within 1e-6 of the cone's size (n normal to a side ruling).
template <class S>
int cone_branch_of_gap(const Cone<S>& a, S gap) {
  if (std::abs(gap) <= S(1e-6) * (a.half_length + a.radius)) return 0;
  return gap > S(0) ? 1 : 2;
}

/// Which branch of cone a (its frame) supports unit n: 1 its apex, 2 its base rim, 0 when they tie
/// within 1e-6 of the cone's size (n normal to a side ruling).
template <class S>
int cone_branch(const Cone<S>& a, const Vec3<S>& n) {
  return cone_branch_of_gap(a, cone_branch_gap(a, n));
}

/// Adds the terms of cone a's branch `branch` (cone_branch: 1 the apex, a linear term; 2 the base
/// rim, a disc term about z plus a linear one), each a lower bound of the cone's support everywhere.
template <class S>
void add_cone_branch_terms(const Cone<S>& a, int branch, OverlapTerms<S>& f) {
  if (branch == 1) {
    f.linear.z() += a.half_length;
  } else {
    f.linear.z() -= a.half_length;
    f.add(Vec3<S>::UnitZ(), a.radius, true);
  }
  f.magnitude += a.half_length;
}

/// The overlap of cone a (its frame) and box b placed by R, t there, with the cone's branch
/// active along n (its apex or its base rim); false when they tie within 1e-6 of the cone's size
/// (n normal to a side ruling).
template <class S>
bool cone_box_terms(const Cone<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f) {
  const int branch = cone_branch(a, n);
  if (branch == 0) return false;
  f = OverlapTerms<S>();
  add_box_terms(b, R, t, f);
  add_cone_branch_terms(a, branch, f);
  return true;
}

}  // namespace impact::detail
