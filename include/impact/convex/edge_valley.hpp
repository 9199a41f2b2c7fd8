// SPDX-License-Identifier: MIT
/// \file
/// The normal of a contact where one shape's support is a whole straight edge, refined along the
/// edge's valley (issue 15's normal target; docs/convex-notes.md, note 34): a hull's edge against
/// a cylinder or a cone, a capsule's segment against a cylinder or a cone.
///
/// Let X be the curved shape (support s_X) and p0 p1 the other shape's edge (e its unit direction
/// from p0 to p1, in one frame), m the direction along which X's support is taken. Where the
/// edge's shape has its support along -m on the whole edge (m orthogonal to the edge), the overlap
/// has a kink across the great circle of the directions orthogonal to the edge, and when s_X(m)
/// projects onto the edge between its ends the minimiser lies on that circle: the one-sided slopes
/// off the circle, e . (s_X(m) - p0) and e . (p1 - s_X(m)), are then both >= 0. Newton on the
/// overlap's terms cannot stay on such a kink (its model's certificate from a nearby disc kink
/// jumps elsewhere: docs/convex.md, cylinder–hull's deep pose), and EPA stops on its depth
/// tolerance with its normal off along the circle by up to about the square root of it. On the
/// circle m(phi) = cos(phi) e1 + sin(phi) e2 (e1, e2 orthonormal, normal to the edge) the edge's
/// part is a constant plus -m . p for any point p of the edge, so the overlap is
/// c + m . (s_X(m) - p) and its slope m'(phi) . (s_X(m) - p) (the support point is the gradient
/// of the support function): the convex 1-D search of convex/segment_cylinder.hpp (regula falsi
/// on the slope) finds its least value within a window of 1e-3 rad about the start, as
/// cone_side_valley_normal does along a cone's side normals (convex/certified_pair.hpp).
///   a hull's edge (b) against a (cylinder, cone): X = a, m = n (the contact normal), c = 0;
///   a capsule's segment (a) against b: X = b, m = -n, c = the capsule's radius.
///
/// Numerical contract: APPROXIMATE. The refined normal is taken only where the true overlap along
/// it (one support call of each shape) is no larger than the answer's, and the answer's lower
/// bound stays the bracket's lower end, so the depth's bracket still holds. Bounded: one support
/// vertex of a hull and its neighbours (not counted, as a candidate's points are not), at most
/// kEdgeValleyEvaluations support calls of X and one overlap, all counted in the query's
/// max_iterations (one budget, docs/convex-notes.md, note 36): a search the bound cuts short keeps
/// the answer's normal and sets limit_reached.
/// Thread safety: pure functions.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/general_pair.hpp"
#include "impact/convex/query_options.hpp"
#include "impact/convex/segment_cylinder.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace impact::detail {

/// The valley search's window about its start (radians): EPA's normal is within about the square
/// root of its depth tolerance of the minimiser (1e-5 rad at 1e-10 of the size).
inline constexpr double kEdgeValleyWindow = 1e-3;

/// The most evaluations (support calls of X) of the valley search.
inline constexpr int kEdgeValleyEvaluations = 32;

/// The edge of hull b (placed by R, t in the frame of n0) whose valley holds unit n0 within
/// `window` radians: b's support vertex along -n0 and, of its neighbours (of every vertex for
/// hulls without an edge graph), the one whose edge is nearest orthogonal to n0. True with p0, p1
/// the edge's ends (n0's frame) when that angle is at most `window`.
template <class S>
bool hull_edge_near(const ConvexHull<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n0, S window, Vec3<S>& p0,
                    Vec3<S>& p1) {
  const Vec3<S> d = -(R.transpose() * n0);
  const S* p = b.vertices.data();
  const auto at = [&](int i) { return Vec3<S>(p[3 * i], p[3 * i + 1], p[3 * i + 2]); };
  const int v = support_vertex(b, d);
  const Vec3<S> pv = at(v);
  const S top = pv.dot(d);
  S best = std::sin(window);
  int u = -1;
  const auto consider = [&](int i) {
    if (i == v) return;
    const S len = (at(i) - pv).norm();
    if (!(len > S(0))) return;
    const S off = (top - at(i).dot(d)) / len;  // the sine of n0's angle off the edge's circle
    if (off <= best) {
      best = off;
      u = i;
    }
  };
  for_each_neighbor(b, v, consider);
  if (u < 0) return false;
  p0 = R * pv + t;
  p1 = R * at(u) + t;
  return true;
}

/// The least of c + m . (s_X(m) - p) over the unit m orthogonal to the edge p0 p1 within
/// kEdgeValleyWindow of the start m0 (the file comment; `sx` X's support, all in one frame,
/// `scale` the query's). True and `m` set when the least value lies inside the window, is
/// positive, and s_X(m) projects onto the edge between its ends (a local minimiser of the
/// overlap on the sphere). The search takes at most kEdgeValleyEvaluations evaluations, fewer when
/// `max_evaluations` says so; `evaluations` counts them, and `cut_short` says that a smaller
/// `max_evaluations` ended the search before it decided (or left no room to start it).
template <class S, class SupportX>
bool edge_valley_normal(const SupportX& sx, const Vec3<S>& p0, const Vec3<S>& p1, const Vec3<S>& m0, S c, S scale, Vec3<S>& m,
                        int max_evaluations, int& evaluations, bool& cut_short) {
  evaluations = 0;
  cut_short = false;
  const Vec3<S> edge = p1 - p0;
  const S len = edge.norm();
  if (!(len > S(0))) return false;
  const Vec3<S> e = edge / len, mid = (p0 + p1) / S(2);
  const Vec3<S> q = m0 - e.dot(m0) * e;
  const S ql = q.norm();
  if (!(ql > S(0))) return false;
  const Vec3<S> e1 = q / ql, e2 = e.cross(e1);
  const S window = S(kEdgeValleyWindow);
  const auto eval = [&](S x) {
    SegmentSolidPoint<S> r;
    r.t = x;
    const S phi = window * (S(2) * x - S(1)), cs = std::cos(phi), sn = std::sin(phi);
    const Vec3<S> w = cs * e1 + sn * e2, dw = cs * e2 - sn * e1;
    r.p = sx(w);
    const Vec3<S> gap = r.p - mid;
    r.f = c + w.dot(gap);
    r.g = S(2) * window * dw.dot(gap);
    r.n = w;
    return r;
  };
  const S stop = S(2) * window * std::max(S(1e-10) * scale, S(64) * std::numeric_limits<S>::epsilon() * scale);
  const int most = std::min(kEdgeValleyEvaluations, max_evaluations);
  if (most < 2) {  // not even the window's two ends
    cut_short = true;
    return false;
  }
  SegmentSolidPoint<S> best;
  const SegmentSearch found = segment_solid_minimum(eval, S(0), stop, S(-1), most, best, evaluations);
  if (found != SegmentSearch::Answered) {
    cut_short = found == SegmentSearch::Bound && most < kEdgeValleyEvaluations;
    return false;
  }
  if (!(best.t > S(0) && best.t < S(1))) return false;  // the least value at the window's edge: not found
  // X's support point across the edge between its ends: the overlap rises off the circle both ways
  const S along = e.dot(best.p - p0);
  if (!(along >= S(0) && along <= len)) return false;
  m = best.n;
  return true;
}

/// Contact g (normal from a towards b) with its normal replaced by `n` (a's frame) where the true
/// overlap along it is no larger; g's lower bound stays the bracket's lower end.
template <class S, class A, class B>
void keep_if_no_deeper(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, const Vec3<S>& n,
                       ConvexContact<S>& g) {
  ConvexContact<S> r = g;
  r.normal = pa.rotate(n);
  settle_contact(a, pa, b, pb, r);
  if (!(r.depth <= g.depth)) return;
  r.depth_gap = std::max(r.depth - (g.depth - g.depth_gap), S(0));
  g = r;
}

/// A valley search refining contact g within the query's bound (one budget): `search(most,
/// evaluations, cut_short)` gets what g.iterations leaves of `max_iterations` less one for the
/// overlap along the normal it finds (keep_if_no_deeper's support call of each shape). Its
/// evaluations and that overlap count in g.iterations; a search cut short sets g.limit_reached.
/// True when the search found a normal.
template <class S, class Search>
bool budgeted_search(ConvexContact<S>& g, int max_iterations, const Search& search) {
  int evaluations = 0;
  bool cut_short = false;
  const bool found = search(max_iterations - g.iterations - 1, evaluations, cut_short);
  g.iterations += evaluations;
  if (cut_short) g.limit_reached = true;
  if (found) ++g.iterations;  // the overlap along the normal found
  return found;
}

/// A contact g of a curved shape a (cylinder or cone) and hull b (normal from a towards b)
/// refined along the valley of b's edge near orthogonal to its normal (hull_edge_near,
/// edge_valley_normal), kept where the true overlap is no larger. Nothing happens when g is not
/// intersecting, its bound was hit, or no edge of b is within kEdgeValleyWindow of orthogonal to
/// its normal. Its support calls count against `max_iterations` (budgeted_search).
template <class S, class A>
void refine_on_hull_edge(const A& a, const RigidTransform<S>& pa, const ConvexHull<S>& b, const RigidTransform<S>& pb,
                         ConvexContact<S>& g, int max_iterations) {
  if (!g.intersecting || g.limit_reached) return;
  const PairFrame<S> f(pa, pb);
  const Vec3<S> n0 = pa.R.transpose() * g.normal;
  Vec3<S> p0, p1, n;
  if (!hull_edge_near(b, f.R, f.t, n0, S(kEdgeValleyWindow), p0, p1)) return;
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const S scale = query_scale<S>(a, b);
  const auto search = [&](int most, int& evaluations, bool& cut_short) {
    return edge_valley_normal(sa, p0, p1, n0, S(0), scale, n, most, evaluations, cut_short);
  };
  if (budgeted_search(g, max_iterations, search)) keep_if_no_deeper(a, pa, b, pb, n, g);
}

/// A contact g of capsule a and a curved shape b (normal from a towards b) refined along the
/// valley of a's segment when the normal is within kEdgeValleyWindow of orthogonal to it
/// (edge_valley_normal with X = b, m = -n), kept where the true overlap is no larger. Its support
/// calls count against `max_iterations` (budgeted_search).
template <class S, class B>
void refine_on_capsule_segment(const Capsule<S>& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                               ConvexContact<S>& g, int max_iterations) {
  if (!g.intersecting || g.limit_reached) return;
  const Vec3<S> m0 = -(pa.R.transpose() * g.normal);
  if (!(std::abs(m0.z()) <= std::sin(S(kEdgeValleyWindow)))) return;
  const PairFrame<S> f(pa, pb);
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const Vec3<S> p0(S(0), S(0), -a.half_length), p1(S(0), S(0), a.half_length);
  Vec3<S> m;
  const S scale = query_scale<S>(a, b);
  const auto search = [&](int most, int& evaluations, bool& cut_short) {
    return edge_valley_normal(sb, p0, p1, m0, a.radius, scale, m, most, evaluations, cut_short);
  };
  if (budgeted_search(g, max_iterations, search)) keep_if_no_deeper(a, pa, b, pb, Vec3<S>(-m), g);
}

}  // namespace impact::detail
