// SPDX-License-Identifier: MIT
/// \file
/// The boolean test of two cylinders (convex_intersect's cylinder–cylinder path in
/// convex/query.hpp), in a's frame (a's axis is z, its centre the origin; b placed by R, t), as a
/// chain of cheap tests, each of which decides only what it proves:
///   1. the overlap along the line between the centres, h_a(m) + h_b(-m) with m = t / |t|: a
///      negative one is a separating plane (no contact; 85 % of the bench's separated poses);
///   2. either centre inside the other cylinder: they intersect;
///   3. the closest points p, q of the two axis segments: when both lie strictly inside their
///      segments (the axes more than about 6 degrees from parallel, 18 in float, so that rounding
///      moves p and q by at most about 100 epsilons of the size, 10 in float), q - p is normal to both axes, so the planes
///      normal to it through p + r_a (q - p) / |q - p| and q - r_b (q - p) / |q - p| support the
///      infinite cylinders, and the finite ones intersect exactly when |q - p| <= r_a + r_b;
///      otherwise a point of both proves an intersection (q in a, p in b, their midpoint in both,
///      or the point of a's side at p's height towards q in b, or b's towards p in a), and a plane
///      normal to q - p with a negative overlap separates them;
///   4. else GJK (convex/gjk_distance.hpp) from the direction p - q, stopped as soon as it decides
///      "distance <= tolerance" either way.
/// On the bench's 2000 cylinder–cylinder poses (1,195 apart) steps 1-3 decide 1,891 (1,020 by the
/// centre line, 101 by a centre, 148 by the common normal, 519 by a point of both, 103 by the plane
/// normal to q - p); GJK runs on 109 (about 6 support calls each).
///
/// Numerical contract: EXACT up to rounding in steps 1-3 (a pair within about 100 epsilons of the
/// size of touching may go either way, as with any floating-point test: touching counts as
/// intersecting); step 4 as GJK: intersecting when the distance is within `tolerance`, apart when
/// a separating plane beyond it is found; limit_reached when the iteration bound stopped it.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/gjk_distance.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace impact::detail {

/// Whether point x (in cylinder c's frame) lies in c (boundary included).
template <class S>
inline bool point_in_cylinder(const Cylinder<S>& c, const Vec3<S>& x) {
  return std::abs(x.z()) <= c.half_length && x.x() * x.x() + x.y() * x.y() <= c.radius * c.radius;
}

/// Whether cylinders a (its frame) and b (placed by R, t there) touch or overlap, by the tests of
/// the file comment; `scale` the larger shape's size, `tolerance` GJK's (absolute), limit_reached
/// set when GJK's iteration bound decided; `gjk_run`, when given, receives GJK's answer (its
/// iterations 0 when steps 1-3 decided).
template <class S>
bool cylinder_pair_intersect(const Cylinder<S>& a, const Cylinder<S>& b, const Mat3<S>& R, const Vec3<S>& t, S scale, S tolerance,
                             int max_iterations, bool& limit_reached, ConvexDistance<S>* gjk_run = nullptr) {
  limit_reached = false;
  if (gjk_run) *gjk_run = ConvexDistance<S>{};
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return Vec3<S>(R * support(b, Vec3<S>(R.transpose() * d)) + t); };
  // 1. the line between the centres: a plane normal to it separates them by more than rounding
  if (separated_along(sa, sb, t, scale)) return false;
  // 2. a centre inside the other
  const Vec3<S> ca = -(R.transpose() * t);  // a's centre in b's frame
  if (point_in_cylinder(a, t) || point_in_cylinder(b, ca)) return true;
  // 3. the closest points p = s u of a's axis and q = t + r v of b's (u = z, v = R z)
  const Vec3<S> v = R.col(2);
  const S ha = a.half_length, hb = b.half_length;
  const S uv = v.z(), ut = t.z(), vt = v.dot(t), den = S(1) - uv * uv;
  const S skew = std::is_same_v<S, float> ? S(0.1) : S(0.01);  // rounding moves p, q by ~ eps |t| / den
  S s = S(0), r = S(0);
  if (den > skew) s = std::clamp((ut - uv * vt) / den, -ha, ha);
  r = std::clamp(uv * s - vt, -hb, hb);
  s = std::clamp(uv * r + ut, -ha, ha);
  const Vec3<S> p(S(0), S(0), s), q = t + r * v, pq = q - p;
  if (den > skew && std::abs(s) < ha && std::abs(r) < hb) {
    // both interior: q - p is normal to both axes (the lines' common normal)
    const S reach = a.radius + b.radius;
    return pq.squaredNorm() <= reach * reach;
  }
  const Vec3<S> mid = (p + q) / S(2);
  if (point_in_cylinder(a, q) || point_in_cylinder(b, Vec3<S>(R.transpose() * (p - t))) ||
      (point_in_cylinder(a, mid) && point_in_cylinder(b, Vec3<S>(R.transpose() * (mid - t)))))
    return true;
  {  // the surface points of each towards the other's axis point, at the same height
    const S ra2 = pq.x() * pq.x() + pq.y() * pq.y();
    const Vec3<S> qb = R.transpose() * (p - t);  // p - q in b's frame
    const S rb2 = qb.x() * qb.x() + qb.y() * qb.y();
    if (ra2 > S(0)) {
      const S k = a.radius / std::sqrt(ra2);
      const Vec3<S> x(k * pq.x(), k * pq.y(), s);
      if (point_in_cylinder(b, Vec3<S>(R.transpose() * (x - t)))) return true;
    }
    if (rb2 > S(0)) {
      const S k = b.radius / std::sqrt(rb2);
      const Vec3<S> y(k * qb.x(), k * qb.y(), r);
      if (point_in_cylinder(a, Vec3<S>(R * y + t))) return true;
    }
  }
  if (separated_along(sa, sb, pq, scale)) return false;  // a plane normal to q - p
  // 4. GJK from the axes' closest points, stopped as soon as it decides
  const Vec3<S> first = pq.squaredNorm() > S(0) ? Vec3<S>(-pq) : Vec3<S>(-t);
  const ConvexDistance<S> d = gjk_distance<S>(sa, sb, first, tolerance, max_iterations, tolerance);
  limit_reached = d.limit_reached;
  if (gjk_run) *gjk_run = d;
  return d.intersecting;
}

}  // namespace impact::detail
