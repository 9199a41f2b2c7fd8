// SPDX-License-Identifier: MIT
/// \file
/// A certified shortcut for the penetration of a triangle (a) and a cylinder or cone (b), both
/// given in the shape's frame, for the common case where one point of the triangle decides it (a
/// triangle reaching into the shape through its side, a cap or its base: most mesh contacts).
/// With f(n) = h_T(n) + h_B(-n), the overlap along a unit direction n (translating the shape by
/// f(n) n separates them; the depth is min_n f(n), as for EPA in convex/epa.hpp):
///   lower  a point x of the triangle inside the shape at distance rho from its boundary has the
///          ball of radius rho about x inside the shape (the shape is the intersection of the
///          half-spaces of its caps or base and of the tangent planes of its side, each at least rho
///          from x), so for every n: h_T(n) >= n.x and h_B(-n) >= -n.x + rho, hence f(n) >= rho;
///   upper  f(n) at the direction that moves the boundary nearest x (side, cap or base) onto x.
/// Points tried: the three vertices and the triangle's point nearest the axis (the closest point
/// of the triangle's projection along the axis to the axis, lifted back onto the triangle). When
/// the best upper and lower bounds are within the tolerance the answer is certified as EPA's is
/// (depth = the upper bound, depth_gap = upper - lower); otherwise the caller runs EPA.
/// Also the pieces the cylinder–box and cone–box candidates share: inside_ball of a box, and
/// box_edge_at_azimuth (a box edge across the side of a solid of revolution).
///
/// Numerical contract: APPROXIMATE, as EPA's: depth is f(normal) computed from the supports (an
/// upper bound up to rounding), depth - depth_gap a lower bound up to the rounding of rho.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/triangle_shape.hpp"
#include "impact/narrow/closest_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace impact::detail {

/// The largest ball about a point x inside a shape: its radius rho (the distance to the nearest
/// boundary; negative when x is outside) and the unit direction that moves that boundary onto x
/// (minus its outward normal).
template <class S>
struct InsideBall {
  S rho = S(-1);
  Vec3<S> push = Vec3<S>::UnitZ();
};

template <class S>
InsideBall<S> inside_ball(const Cylinder<S>& c, const Vec3<S>& x) {
  const S rho_xy = std::sqrt(x.x() * x.x() + x.y() * x.y());
  const S side = c.radius - rho_xy, cap = c.half_length - std::abs(x.z());
  InsideBall<S> b;
  if (!(side >= S(0) && cap >= S(0))) return b;
  if (cap <= side) {
    b.rho = cap;
    b.push = Vec3<S>(S(0), S(0), x.z() >= S(0) ? S(-1) : S(1));
  } else {
    b.rho = side;
    b.push = rho_xy > S(0) ? Vec3<S>(-x.x() / rho_xy, -x.y() / rho_xy, S(0)) : Vec3<S>(-Vec3<S>::UnitX());
  }
  return b;
}

/// Cone: base disc of radius R at z = -h, apex (0, 0, h); its side's outward normal at azimuth u
/// is (2h u + R z^) / L with L = sqrt(4h^2 + R^2), the side's tangent plane at x's azimuth the
/// nearest one.
/// `L` is the cone's slant factor sqrt(4h^2 + R^2) (cone_slant), which a caller testing many
/// points computes once; a point below the base costs no square root.
template <class S>
InsideBall<S> inside_ball(const Cone<S>& c, const Vec3<S>& x, S L) {
  const S R = c.radius, h = c.half_length;
  const S base = x.z() + h;
  InsideBall<S> b;
  if (!(base >= S(0))) return b;
  const S rho_xy = std::sqrt(x.x() * x.x() + x.y() * x.y());
  const S side = (R * (h - x.z()) - S(2) * h * rho_xy) / L;
  if (!(side >= S(0))) return b;
  if (base <= side) {
    b.rho = base;
    b.push = Vec3<S>::UnitZ();
  } else {
    b.rho = side;
    const S ux = rho_xy > S(0) ? x.x() / rho_xy : S(1), uy = rho_xy > S(0) ? x.y() / rho_xy : S(0);
    b.push = Vec3<S>(-S(2) * h * ux / L, -S(2) * h * uy / L, -R / L);
  }
  return b;
}

/// The cone's slant factor sqrt(4h^2 + R^2) (its side's outward normal at azimuth u is
/// (2h u + R z^) / L).
template <class S>
S cone_slant(const Cone<S>& c) {
  return std::sqrt(S(4) * c.half_length * c.half_length + c.radius * c.radius);
}

template <class S>
InsideBall<S> inside_ball(const Cone<S>& c, const Vec3<S>& x) {
  return inside_ball(c, x, cone_slant(c));
}

/// Box: the nearest of its six faces (the first axis on ties).
template <class S>
InsideBall<S> inside_ball(const Box<S>& b, const Vec3<S>& x) {
  InsideBall<S> out;
  for (int i = 0; i < 3; ++i) {
    const S gap = b.half[i] - std::abs(x[i]);
    if (!(gap >= S(0))) return InsideBall<S>();
    if (i == 0 || gap < out.rho) {
      out.rho = gap;
      out.push = Vec3<S>::Zero();
      out.push[i] = x[i] >= S(0) ? S(-1) : S(1);
    }
  }
  return out;
}

/// A box edge across the side of a solid of revolution about z (cylinder or cone, in its frame):
/// of the box's four edges along its axis i (the box placed by R, t, with hc[j] its axis j scaled
/// by its half extent), the one deepest along -n (its corner signs off axis i those of -R^T n),
/// and that edge's point x where it crosses the plane through z at azimuth (ux, uy) (its xy
/// projection along (ux, uy) or opposite). False when the edge is parallel to that plane or
/// crosses it beyond its ends. Used by the edge candidates of cone_box_pair.hpp and
/// cylinder_box_pair.hpp, whose normals n differ (a side normal of each at that azimuth).
template <class S>
bool box_edge_at_azimuth(const Mat3<S>& R, const Vec3<S>& t, const Vec3<S> (&hc)[3], int i, const Vec3<S>& n, S ux, S uy, Vec3<S>& x) {
  const Vec3<S> d = R.transpose() * n;
  Vec3<S> p0 = t;
  for (int j = 0; j < 3; ++j) p0 += (j == i || d[j] > S(0)) ? Vec3<S>(-hc[j]) : hc[j];
  const Vec3<S> ev = S(2) * hc[i];
  // the component of p0 + s ev along (-uy, ux) (normal to the plane) vanishes
  const S qp = -uy * p0.x() + ux * p0.y(), qe = -uy * ev.x() + ux * ev.y();
  if (!(std::abs(qe) > S(0))) return false;
  const S s = -qp / qe;
  if (!(s >= S(0) && s <= S(1))) return false;
  x = p0 + s * ev;
  return true;
}

/// The certified contact of triangle t (a) and shape b (a Cylinder or Cone), both in b's frame,
/// when a single point of t decides it within `tolerance` (see the file comment): true and `out`
/// set (normal from the triangle towards the shape, depth, depth_gap, point on the plane midway
/// between the supporting planes at the deciding point; iterations counts the support calls);
/// else false (out.iterations still counts them).
template <class S, class Shape>
bool triangle_deepest_point_contact(const TriangleShape<S>& t, const Shape& b, S tolerance, ConvexContact<S>& out) {
  const Triangle<S>& tri = t.triangle;
  Vec3<S> x[4] = {tri.a, tri.b, tri.c, tri.a};
  {  // the point of the triangle nearest the axis: its projection along z closest to the axis
    const Triangle<S> flat(Vec3<S>(tri.a.x(), tri.a.y(), S(0)), Vec3<S>(tri.b.x(), tri.b.y(), S(0)), Vec3<S>(tri.c.x(), tri.c.y(), S(0)));
    const auto q = closest_point_on_triangle(Vec3<S>(Vec3<S>::Zero()), flat);
    x[3] = q.barycentric[0] * tri.a + q.barycentric[1] * tri.b + q.barycentric[2] * tri.c;
  }
  S upper = std::numeric_limits<S>::infinity(), lower = S(0);
  Vec3<S> best_n = Vec3<S>::UnitZ(), best_x = Vec3<S>::Zero();
  int calls = 0;
  for (const Vec3<S>& p : x) {
    const InsideBall<S> ball = inside_ball(b, p);
    if (!(ball.rho >= S(0))) continue;  // outside the shape: no ball about it
    lower = std::max(lower, ball.rho);
    const Vec3<S>& n = ball.push;
    const S f = n.dot(support(t, n)) - n.dot(support(b, Vec3<S>(-n)));
    ++calls;
    if (f < upper) {
      upper = f;
      best_n = n;
      best_x = p;
    }
  }
  out.iterations = calls;
  if (!(upper - lower <= tolerance)) return false;
  out.intersecting = true;
  out.normal = best_n;
  out.depth = std::max(upper, S(0));
  out.depth_gap = std::max(upper - lower, S(0));
  // the deciding point (within the tolerance the triangle's deepest along n) onto the plane midway
  // between the two supporting planes
  const S top_a = best_n.dot(support(t, best_n)), low_b = best_n.dot(support(b, Vec3<S>(-best_n)));
  out.point = best_x + ((top_a + low_b) / S(2) - best_n.dot(best_x)) * best_n;
  return true;
}

}  // namespace impact::detail
