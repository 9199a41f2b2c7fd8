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
/// ruling) a body inside the cone along that ruling takes the branch's place
/// (cone_side_hull_terms: the body of add_cone_side_body, convex/local_certificate.hpp, exact along
/// the ruling's side normals), at the ruling the hull's feature touches (cone_hull_side_azimuth).
/// Numerical contract: the terms are exact expressions of the supports (rounding only).
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_hull_pair.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

#include <cmath>

namespace impact::detail {

/// The overlap of cone a (its frame) and hull b placed by R, t there near unit n: the cone's
/// branch active along n (`branch`, as cone_branch gives it: the caller has it already) and the
/// hull's feature along -n; false when the cone's branches tie (branch 0).
template <class S>
bool cone_hull_terms(const Cone<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, int branch,
                     OverlapTerms<S>& f) {
  if (branch == 0) return false;
  f = OverlapTerms<S>();
  add_cone_branch_terms(a, branch, f);
  add_hull_feature_terms(b, R, t, n, f);
  return true;
}

/// The azimuth (a unit vector in cone a's xy plane) of the ruling of a's side that the hull's
/// support feature along -n touches: a vertex x, the azimuth of x; an edge x y, the side normal
/// n(phi) ~ (2h e, r) with n . (x - y) = 0 (the two sinusoids cross), the root nearest n's azimuth.
/// False when none.
template <class S>
bool cone_hull_side_azimuth(const Cone<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, Vec3<S>& e) {
  OverlapTerms<S> f;
  add_hull_feature_terms(b, R, t, n, f);
  const Vec3<S> x = -f.linear;  // the vertex, or the edge's midpoint
  if (f.n == 0) {
    const S m = std::sqrt(x.x() * x.x() + x.y() * x.y());
    if (!(m > S(1e-9) * b.size)) return false;
    e = Vec3<S>(x.x() / m, x.y() / m, S(0));
    return true;
  }
  const Vec3<S> d = f.axis[0];  // the edge's unit direction
  const S dd = d.x() * d.x() + d.y() * d.y();
  if (!(dd > S(1e-12))) return false;
  const S k = -a.radius * d.z() / (S(2) * a.half_length), disc = dd - k * k;
  if (!(disc >= S(0))) return false;
  const S q = std::sqrt(disc);
  const S nm = std::sqrt(n.x() * n.x() + n.y() * n.y());
  if (!(nm > S(0))) return false;
  Vec3<S> best = Vec3<S>::Zero();
  S best_dot = -S(2);
  for (int sgn = -1; sgn <= 1; sgn += 2) {
    const Vec3<S> c((k * d.x() - S(sgn) * q * d.y()) / dd, (k * d.y() + S(sgn) * q * d.x()) / dd, S(0));
    const S dot = (c.x() * n.x() + c.y() * n.y()) / nm;
    if (dot > best_dot) {
      best_dot = dot;
      best = c;
    }
  }
  e = best;
  return true;
}

/// The overlap of cone a (its frame) and hull b near a contact of a's side at azimuth e: a body
/// inside a along that ruling (add_cone_side_body, mirrored: a's support along w) from its base rim
/// point to `s1`, and the hull's feature along -n.
template <class S>
bool cone_side_hull_terms(const Cone<S>& a, const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n,
                          const Vec3<S>& e, S s1, OverlapTerms<S>& f) {
  f = OverlapTerms<S>();
  if (!add_cone_side_body(a, Mat3<S>(Mat3<S>::Identity()), Vec3<S>(Vec3<S>::Zero()), Vec3<S>(-e), f, S(0), s1)) return false;
  f.linear = -f.linear;  // add_cone_side_body gives the body's support along -w
  add_hull_feature_terms(b, R, t, n, f);
  return true;
}

}  // namespace impact::detail
