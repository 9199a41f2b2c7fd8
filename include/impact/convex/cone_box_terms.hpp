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
/// branches tie (w normal to a side ruling) they give no terms; there cone_side_box_terms puts
/// a body inside the cone along the ruling the box touches (add_cone_side_body, as
/// cone_side_hull_terms of convex/cone_hull_terms.hpp) in the branch's place, at the ruling of
/// cone_box_side_contact: for a box edge across the side, the edge and the ruling are the two
/// kinks of f whose crossing is the minimiser, so the certificate's bound there is exact.
/// Numerical contract: the terms are exact expressions of the supports (rounding only).
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/deepest_point.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

/// The ruling of cone a's side (its azimuth e, a unit vector in a's xy plane) that box b placed by
/// R, t touches near the unit direction n, and the box's point x on it: where the box's support
/// along -n is near an edge (its axis i with the least e_i |R_i . n|, the edge's ends within 0.05
/// of the size along n), the azimuth whose side normal is orthogonal to that edge (2h e . R_i =
/// -r R_i,z, the root nearest n's azimuth) and the edge's point there (box_edge_at_azimuth);
/// otherwise, or when that edge does not cross the ruling's plane, the box's deepest corner along
/// -n and its azimuth. False when that corner lies on a's axis.
template <class S>
bool cone_box_side_contact(const Cone<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n, Vec3<S>& e, Vec3<S>& x) {
  const Vec3<S> m = R.transpose() * n;
  const Vec3<S> hc[3] = {Vec3<S>(b.half.x() * R.col(0)), Vec3<S>(b.half.y() * R.col(1)), Vec3<S>(b.half.z() * R.col(2))};
  int i = 0;
  for (int j = 1; j < 3; ++j)
    if (b.half[j] * std::abs(m[j]) < b.half[i] * std::abs(m[i])) i = j;
  const S r = a.radius, h = a.half_length, size = h + r + b.half.maxCoeff();
  if (S(2) * b.half[i] * std::abs(m[i]) <= S(0.05) * size) {
    const Vec3<S> d = R.col(i);
    const S m2 = d.x() * d.x() + d.y() * d.y(), c = -r * d.z() / (S(2) * h);
    if (m2 > S(1e-12) && c * c < m2) {
      const S along = c / m2, across = std::sqrt(m2 - c * c) / m2, L = cone_slant(a);
      S ux = S(0), uy = S(0), best = -std::numeric_limits<S>::infinity();
      for (const S sign : {S(1), S(-1)}) {
        const S vx = along * d.x() - sign * across * d.y(), vy = along * d.y() + sign * across * d.x(), dot = vx * n.x() + vy * n.y();
        if (dot > best) {
          best = dot;
          ux = vx;
          uy = vy;
        }
      }
      const Vec3<S> side(S(2) * h * ux / L, S(2) * h * uy / L, r / L);
      if (box_edge_at_azimuth(R, t, hc, i, side, ux, uy, x)) {
        e = Vec3<S>(ux, uy, S(0));
        return true;
      }
    }
  }
  x = t;
  for (int j = 0; j < 3; ++j) x += m[j] > S(0) ? Vec3<S>(-hc[j]) : hc[j];
  const S q = std::sqrt(x.x() * x.x() + x.y() * x.y());
  if (!(q > S(1e-9) * size)) return false;
  e = Vec3<S>(x.x() / q, x.y() / q, S(0));
  return true;
}

/// The overlap of cone a (its frame) and box b placed by R, t there near a contact of a's side at
/// azimuth e: a body inside a along that ruling (add_cone_side_body, mirrored: a's support along
/// w) from its base rim point to the fraction `s1` of the ruling, and the box's terms; a lower
/// bound of the overlap everywhere, equal to it along the ruling's side normal when the box
/// touches the ruling within the body's span.
template <class S>
bool cone_side_box_terms(const Cone<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& e, S s1, OverlapTerms<S>& f) {
  f = OverlapTerms<S>();
  if (!add_cone_side_body(a, Mat3<S>(Mat3<S>::Identity()), Vec3<S>(Vec3<S>::Zero()), Vec3<S>(-e), f, S(0), s1)) return false;
  f.linear = -f.linear;  // add_cone_side_body gives the body's support along -w
  add_box_terms(b, R, t, f);
  return true;
}

/// The local certificate of cone a (its frame) and box b placed by R, t there on the body inside
/// a along the ruling of cone_box_side_contact near n (cone_side_box_terms, from the base rim
/// point to side_body_end of the box's point on that ruling), started at that ruling's side
/// normal. Its bound is exact only where the body touches the contact: the caller checks the true
/// overlap at its normal (certificate_holds). No certificate when there is no such ruling.
template <class S>
LocalCertificate<S> cone_box_side_certificate(const Cone<S>& a, const Box<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n) {
  Vec3<S> e, x;
  if (!cone_box_side_contact(a, b, R, t, n, e, x)) return LocalCertificate<S>();
  const S r = a.radius, h = a.half_length;
  const Vec3<S> m = Vec3<S>(S(2) * h * e.x(), S(2) * h * e.y(), r) / cone_slant(a);
  const Vec3<S> p(r * e.x(), r * e.y(), -h), d = Vec3<S>(S(0), S(0), h) - p;
  OverlapTerms<S> f;
  if (!cone_side_box_terms(a, b, R, t, e, side_body_end((x - p).dot(d) / d.dot(d)), f)) return LocalCertificate<S>();
  return local_certificate(f, m);
}

}  // namespace impact::detail
