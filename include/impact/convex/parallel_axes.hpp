// SPDX-License-Identifier: MIT
/// \file
/// The penetration of two cylinders or cones whose axes are parallel (or antiparallel), in closed
/// form: coincident shapes, coaxial stacks, shapes spawned side by side with the same orientation.
/// There the least-overlap directions form whole circles or tie between the axial and the radial
/// direction, and EPA crawls along them (129 support calls and a bracket of 1e-3 of the size before
/// this shortcut), so convex/query.hpp tries this one first.
///
/// Each shape is the convex hull of discs normal to its axis: a cylinder of radius r and half length
/// h the discs (r, -h) and (r, +h), a cone its base (r, -h) and its apex (0, +h) (radius, height).
/// With parallel axes the Minkowski sum of two such discs is the disc of the summed radius at the
/// summed height about the summed centre, so the Minkowski difference M = A - B is the solid of
/// revolution about a line parallel to the axes whose meridian section is the convex hull of the
/// points (+-(r_i + r_j), z_i - s z_j), s = +-1 whether b's axis points along a's or against it.
/// The penetration depth is the distance from the origin to the boundary of M; for a solid of
/// revolution that distance is reached in the meridian half-plane through the point (rotating a
/// boundary point into it brings it no farther), so it is the distance from (rho0, t_z) (b's
/// centre in a's frame, rho0 = its distance to a's axis) to the boundary of that convex polygon:
/// the least (offset - n . p) over the polygon's edges, each edge's outward normal (n_rho, n_z)
/// giving the 3-D normal n_rho u + n_z e_z, u the radial unit vector towards b's axis (any when
/// the axes coincide).
///
/// Certified as convex/cylinder_pair.hpp's candidates are: the upper bound is f(n), the overlap of
/// the true shapes along the normal found; the lower bound is the closed form's depth minus
/// delta = |b_z - s e_z| max|x| (x over b in its frame), the most b's support can differ from that
/// of its copy with the axis exactly parallel (b is that copy rotated by the angle between the
/// axes about its centre), minus rounding. Accepted when the two are within the tolerance: exactly
/// parallel axes up to rounding (the same orientation, and any tilt below about 1e-11 rad at the
/// default tolerance); otherwise the caller goes on to its other methods, and when those stop with
/// their bracket open it calls this again with their bracket's width as the tolerance and keeps the
/// narrower bracket (convex/certified_pair.hpp, narrow_by_parallel_axes: coaxial pairs tilted by 1e-9 rad).
///
/// Numerical contract: APPROXIMATE, as EPA's: depth is f(normal) computed from the supports (an
/// upper bound up to rounding), depth - depth_gap a certified lower bound up to rounding.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// The discs (radius, height along the axis) whose convex hull is the shape (its own frame).
template <class S>
struct AxialDiscs {
  S r[2] = {S(0), S(0)};
  S z[2] = {S(0), S(0)};
  S reach2 = S(0);  ///< the squared largest distance of a point of the shape from its frame's origin
};
template <class S>
inline AxialDiscs<S> axial_discs(const Cylinder<S>& c) {
  AxialDiscs<S> d;
  d.r[0] = d.r[1] = c.radius;
  d.z[0] = -c.half_length;
  d.z[1] = c.half_length;
  d.reach2 = c.radius * c.radius + c.half_length * c.half_length;
  return d;
}
template <class S>
inline AxialDiscs<S> axial_discs(const Cone<S>& c) {
  AxialDiscs<S> d;
  d.r[0] = c.radius;
  d.z[0] = -c.half_length;
  d.z[1] = c.half_length;  // the apex: radius 0
  d.reach2 = c.radius * c.radius + c.half_length * c.half_length;
  return d;
}

/// The distance from p (inside) to the boundary of the convex hull of the points (+-rho_k, z_k),
/// k < n (n <= 4), and the outward normal (n_rho, n_z) of the nearest edge; a negative distance
/// when p is outside. The hull by Andrew's monotone chain on the 2n points.
template <class S>
inline S meridian_depth(const S* rho, const S* z, int n, S p_rho, S p_z, S& n_rho, S& n_z) {
  S px[8], pz[8];
  int m = 0;
  for (int k = 0; k < n; ++k) {
    px[m] = -rho[k];
    pz[m++] = z[k];
    px[m] = rho[k];
    pz[m++] = z[k];
  }
  int order[8];
  for (int k = 0; k < m; ++k) order[k] = k;
  std::sort(order, order + m, [&](int i, int j) { return px[i] < px[j] || (px[i] == px[j] && pz[i] < pz[j]); });
  const auto cross = [&](int o, int i, int j) { return (px[i] - px[o]) * (pz[j] - pz[o]) - (pz[i] - pz[o]) * (px[j] - px[o]); };
  int hull[17];
  int h = 0;
  for (int k = 0; k < m; ++k) {  // lower chain
    while (h >= 2 && cross(hull[h - 2], hull[h - 1], order[k]) <= S(0)) --h;
    hull[h++] = order[k];
  }
  for (int k = m - 2, lo = h + 1; k >= 0; --k) {  // upper chain
    while (h >= lo && cross(hull[h - 2], hull[h - 1], order[k]) <= S(0)) --h;
    hull[h++] = order[k];
  }
  // hull[0..h-1] counter-clockwise, hull[h-1] == hull[0]
  S best = std::numeric_limits<S>::infinity();
  for (int e = 0; e + 1 < h; ++e) {
    const int i = hull[e], j = hull[e + 1];
    const S ex = px[j] - px[i], ez = pz[j] - pz[i], len = std::sqrt(ex * ex + ez * ez);
    if (!(len > S(0))) continue;
    const S nx = ez / len, nz = -ex / len;  // outward for a counter-clockwise polygon
    const S d = nx * (px[i] - p_rho) + nz * (pz[i] - p_z);
    if (d < best) {
      best = d;
      n_rho = nx;
      n_z = nz;
    }
  }
  return best;
}

/// The certified contact of a and b (cylinders or cones) with parallel or antiparallel axes, in
/// a's frame (b placed by R, t there), when the closed form of the file comment decides it within
/// `tolerance`: true and `out` set (normal from a towards b, depth, depth_gap, a point of the
/// contact for the caller to settle, iterations 1); false when the axes are too far from parallel
/// for that, or the shapes are not certainly intersecting.
template <class S, class A, class B>
bool parallel_axes_contact(const A& a, const B& b, const Mat3<S>& R, const Vec3<S>& t, S tolerance, ConvexContact<S>& out) {
  const Vec3<S> bz = R.col(2);
  const S s = bz.z() >= S(0) ? S(1) : S(-1);
  const AxialDiscs<S> da = axial_discs(a), db = axial_discs(b);
  const S tilt2 = bz.x() * bz.x() + bz.y() * bz.y() + (bz.z() - s) * (bz.z() - s);
  if (!(S(4) * tilt2 * db.reach2 <= tolerance * tolerance)) return false;  // 2 delta > tolerance: the only test most poses reach
  const S delta = std::sqrt(tilt2 * db.reach2);
  S rho[4], z[4];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      rho[2 * i + j] = da.r[i] + db.r[j];
      z[2 * i + j] = da.z[i] - s * db.z[j];
    }
  const S rho0 = std::sqrt(t.x() * t.x() + t.y() * t.y());
  S n_rho = S(0), n_z = S(1);
  const S depth0 = meridian_depth(rho, z, 4, rho0, t.z(), n_rho, n_z);
  const S size = std::sqrt(da.reach2) + std::sqrt(db.reach2) + t.norm();
  const S lower = depth0 - delta - std::numeric_limits<S>::epsilon() * S(64) * size;
  if (!(lower > S(0))) return false;
  // the radial unit vector towards b's axis; any one normal to the axes when they coincide
  const Vec3<S> u = rho0 > std::numeric_limits<S>::epsilon() * S(16) * size ? Vec3<S>(t.x() / rho0, t.y() / rho0, S(0)) : Vec3<S>(Vec3<S>::UnitX());
  const Vec3<S> n = (n_rho * u + n_z * Vec3<S>::UnitZ()).normalized();
  const Vec3<S> xa = support(a, n), xb = R * support(b, Vec3<S>(-(R.transpose() * n))) + t;
  const S upper = n.dot(xa) - n.dot(xb);
  if (!(upper - lower <= tolerance)) return false;
  out = ConvexContact<S>();
  out.intersecting = true;
  out.normal = n;
  out.depth = std::max(upper, S(0));
  out.depth_gap = std::max(upper - lower, S(0));
  out.point = (xa + xb) / S(2);
  out.iterations = 1;
  return true;
}

}  // namespace impact::detail
