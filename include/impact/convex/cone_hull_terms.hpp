// SPDX-License-Identifier: MIT
/// \file
/// The overlap of a cone and a convex hull as the terms of convex/local_certificate.hpp, so that
/// the local certificate stops EPA early on cone–hull penetrations (convex/certified_pair.hpp,
/// cone_hull_penetration) as it does for cylinder–hull.
///
/// In the cone's frame (base disc of radius r at z = -h, apex at +h) with the hull placed by R, t,
/// f(w) = h_A(w) + h_B(-w) with h_A(w) = max(h w_z, r |P_z w| - h w_z) (the apex or the base rim)
/// and h_B(-w) at least -w . x for every point x of the hull. So the cone's branch active along n
/// (convex/cone_box_terms.hpp) plus the hull's support feature along -n (a vertex, or an edge:
/// add_hull_feature_terms of convex/cylinder_hull_pair.hpp) is a lower bound of f everywhere, equal
/// to it near n where both are the supports. Where the cone's branches tie (n normal to a side
/// ruling) there are no terms, as for cone–box.
/// Numerical contract: the terms are exact expressions of the supports (rounding only).
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_hull_pair.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

namespace impact::detail {

/// The overlap of cone a (its frame) and hull b placed by R, t there near unit n: the cone's
/// branch active along n and the hull's feature along -n; false when the cone's branches tie.
template <class S>
bool cone_hull_terms(const Cone<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, OverlapTerms<S>& f) {
  const int branch = cone_branch(a, n);
  if (branch == 0) return false;
  f = OverlapTerms<S>();
  add_cone_branch_terms(a, branch, f);
  add_hull_feature_terms(b, R, t, n, f);
  return true;
}

}  // namespace impact::detail
