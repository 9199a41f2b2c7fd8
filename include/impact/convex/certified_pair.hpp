// SPDX-License-Identifier: MIT
/// \file
/// The certified pair paths of convex_penetration: the pairs of curved and flat shapes that have
/// candidates of their own (cylinder against cylinder or cone, cone against cone, cone against box,
/// cylinder against box, cylinder or cone against hull). Each path runs the same stages:
///   1. planes that separate the shapes (one support call each: no contact);
///   2. the pair's candidates (its own file: cylinder_pair.hpp, cone_cone_pair.hpp, ...), whose
///      certificate, a positive lower bound of the depth within the tolerance of the upper bound,
///      proves the intersection and the depth without GJK (settled);
///   3. GJK until its simplex encloses the origin or a plane separates the shapes (enclose_origin;
///      cone–cone runs it before its candidates, which cost more than GJK on separated poses);
///   4. EPA from GJK's tetrahedron, seeded with the best candidate's normal and stopped early by a
///      local certificate on the pair's overlap terms (epa_from_simplex; convex/epa.hpp and
///      convex/local_certificate.hpp).
/// After stage 4, some paths
/// refine EPA's normal (refine_normal_locally, refine_on_cone_side).
/// options.max_iterations is one budget for the whole path (docs/convex-notes.md, notes 25 and 36):
/// every stage's support calls count in it (`its`, the calls so far, is handed from stage to stage
/// and reported). A stage of a fixed most (the planes, the candidates: kCandidateCalls*) runs only
/// when that most fits in what is left, else it is skipped (the candidates' absence changes no
/// guarantee: GJK and EPA decide without them); GJK and EPA stop at the bound; a refinement that
/// does not fit is skipped or cut short, EPA's normal kept and limit_reached set.
/// convex/query.hpp chooses the path per pair of types; the general pieces (GJK, EPA, settling)
/// are in convex/general_pair.hpp.
#pragma once

#include "impact/convex/closed_form.hpp"
#include "impact/convex/cone_box_pair.hpp"
#include "impact/convex/cone_box_terms.hpp"
#include "impact/convex/cone_cone_pair.hpp"
#include "impact/convex/cone_hull_pair.hpp"
#include "impact/convex/cone_hull_terms.hpp"
#include "impact/convex/convex_hull.hpp"
#include "impact/convex/cylinder_box_pair.hpp"
#include "impact/convex/cylinder_hull_pair.hpp"
#include "impact/convex/cylinder_pair.hpp"
#include "impact/convex/edge_valley.hpp"
#include "impact/convex/epa.hpp"
#include "impact/convex/general_pair.hpp"
#include "impact/convex/local_certificate.hpp"
#include "impact/convex/parallel_axes.hpp"
#include "impact/convex/query_options.hpp"
#include "impact/convex/segment_cylinder.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace impact {
namespace detail {

/// The most support calls (overlap evaluations, as CandidateBounds counts them) each pair's
/// candidates make, read off their code: the stage runs only when this many are left of the
/// bound (fits), and an IMPACT_ASSERT checks the count after each run. A candidate added to one
/// of those functions must raise its figure here.
inline constexpr int kCandidateCallsParallelAxes = 1;  // parallel_axes_contact: one overlap
inline constexpr int kCandidateCallsCylinderPair = 9;  // cylinder_pair_contact: caps 2 + 2, rulings 1, rims 2 + 2
// cylinder_cone_contact: a's caps 2, b's base 1, apex 1, rulings 2, base rim 1, a's rims 2, b's
// points 1 + 3 (cylinder_points_bound), a's points 1 + 2 (cone_points_bound), side minimum 1
inline constexpr int kCandidateCallsCylinderCone = 17;
// cone_cone_contact: bases 2, apexes 2, rulings 2, rims 2, each cone's points 1 + 2
inline constexpr int kCandidateCallsConeCone = 14;
inline constexpr int kCandidateCallsConeBox = 20;       // cone_box_contact: faces 6, corners 8, edges 6
inline constexpr int kCandidateCallsCylinderBox = 22;   // cylinder_box_contact: faces 6, caps 2, corners 8, edges 6
inline constexpr int kCandidateCallsCylinderHull = 5;   // cylinder_hull_candidates: edge 1, side vertex 1, caps 2, face 1
inline constexpr int kCandidateCallsConeHull = 4;       // cone_hull_candidates: edge 1, side vertex 1, base 1, face 1

/// Whether a stage of at most `calls` support calls fits in what `spent` left of the query's bound
/// (max_iterations is one budget for the query).
template <class S>
bool fits(const ConvexQueryOptions<S>& o, int spent, int calls) {
  return calls <= o.max_iterations - spent;
}

/// Whether a pair's candidate stage of at most `most` support calls runs after `its` calls: when it
/// fits in the bound. `cand` is reset to "no candidate" (infinite depth: EPA goes unseeded), which
/// it stays when the stage is skipped.
template <class S>
bool candidates_fit(const ConvexQueryOptions<S>& o, int its, int most, ConvexContact<S>& cand) {
  cand = ConvexContact<S>();
  cand.depth = std::numeric_limits<S>::infinity();
  return fits(o, its, most);
}

/// "No contact", after `calls` support calls.
template <class S>
ConvexContact<S> no_contact(int calls) {
  ConvexContact<S> c;
  c.iterations = calls;
  return c;
}

/// A certified candidate's answer: `calls` support calls of the stages before it added to its
/// count, and its contact settled along its normal (settle_certified_from_frame; the settling's
/// support calls are not counted, as no answer's is).
template <class S, class A, class B>
ConvexContact<S> settled(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, ConvexContact<S> c, int calls) {
  c.iterations += calls;
  settle_certified_from_frame(a, pa, b, pb, c);
  return c;
}

/// How GJK ended (enclose_origin): its simplex holds the origin; a plane separates the shapes; or
/// it hit options.max_iterations or met a degenerate simplex, and the caller runs the general
/// path from scratch.
enum class Enclosure { Enclosed, Apart, Unsure };

/// GJK on support functions of a's frame from the direction `start` (gjk_enclose of
/// convex/epa.hpp): `simplex` receives the tetrahedron, `calls` counts the support calls (those of
/// the stages before it included: they count against the bound). Nothing left of the bound: Unsure
/// without a call (the caller's general_after then answers out_of_budget).
template <class S, class SupportA, class SupportB>
Enclosure enclose_origin(const SupportA& sa, const SupportB& sb, const Vec3<S>& start, S scale, const ConvexQueryOptions<S>& o,
                         SimplexPoint<S> (&simplex)[4], int& calls) {
  if (!fits(o, calls, 1)) return Enclosure::Unsure;
  bool limit = false, failed = false;
  if (gjk_enclose(sa, sb, start, scale, o.max_iterations, simplex, calls, limit, failed)) return Enclosure::Enclosed;
  return limit || failed ? Enclosure::Unsure : Enclosure::Apart;
}

/// The general path after an Unsure enclosure that took `calls` support calls: with what is
/// left of the bound (max_iterations is one budget for the query), its calls added; nothing left:
/// out_of_budget.
template <class S, class A, class B>
ConvexContact<S> general_after(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                               const ConvexQueryOptions<S>& o, int calls) {
  ConvexQueryOptions<S> rest;
  if (!budget_left(o, calls, rest)) return out_of_budget<S>(calls);
  ConvexContact<S> c = general_penetration(a, pa, b, pb, rest);
  c.iterations += calls;
  return c;
}

/// What the paths of a (its frame) and b with their own stages share: the pair's frame, the
/// larger shape's size and the tolerance, both support functions in a's frame, the line between
/// the interior points (stage 1: separated) and stage 3 from it (enclose). Holds
/// references to the query's arguments: used within the query only.
template <class S, class A, class B>
struct PairPath {
  struct SupportA {
    const A& shape;
    Vec3<S> operator()(const Vec3<S>& d) const { return support(shape, d); }
  };
  struct SupportB {
    const PairFrame<S>& f;
    const B& shape;
    Vec3<S> operator()(const Vec3<S>& d) const { return f.support_b(shape, d); }
  };

  const A& a;
  const RigidTransform<S>& pa;
  const B& b;
  const RigidTransform<S>& pb;
  const ConvexQueryOptions<S>& o;
  const PairFrame<S> f;
  const S scale, tol;
  const SupportA sa;
  const SupportB sb;
  const Vec3<S> centre_line;

  PairPath(const A& a_, const RigidTransform<S>& pa_, const B& b_, const RigidTransform<S>& pb_, const ConvexQueryOptions<S>& o_)
      : a(a_), pa(pa_), b(b_), pb(pb_), o(o_), f(pa_, pb_), scale(query_scale<S>(a_, b_)), tol(o_.relative_tolerance * scale),
        sa{a_}, sb{f, b_}, centre_line(placed_interior() - interior_point(a_)) {}
  PairPath(const PairPath&) = delete;
  PairPath& operator=(const PairPath&) = delete;

  /// b's interior point in a's frame (a box's is its centre: f.t).
  Vec3<S> placed_interior() const {
    if constexpr (std::is_same_v<B, Box<S>>) {
      return f.t;
    } else {
      return f.b_to_a(interior_point(b));
    }
  }

  /// A plane normal to the centre line separates the shapes (separated_along): most separated
  /// poses end here.
  bool separated() const { return separated_along(sa, sb, centre_line, scale); }

  /// GJK from the centre line, or with its first support along `first` when given (enclose_origin,
  /// `its` support calls so far, every stage's): true with `simplex` its tetrahedron about the
  /// origin; false with `answer` the query's answer when it ended there (a separating plane: no
  /// contact after its calls; unsure: the general path from scratch with what is left).
  bool enclose(SimplexPoint<S> (&simplex)[4], int& its, ConvexContact<S>& answer, const Vec3<S>* first = nullptr) const {
    switch (enclose_origin(sa, sb, first ? Vec3<S>(-*first) : Vec3<S>(-centre_line), scale, o, simplex, its)) {
      case Enclosure::Unsure: answer = general_after(a, pa, b, pb, o, its); return false;
      case Enclosure::Apart: answer = no_contact<S>(its); return false;
      case Enclosure::Enclosed: break;
    }
    return true;
  }
};

/// Whether a local certificate whose bound came through one branch of a shape (a cone's side or
/// base, a hull's vertex or edge) holds: that bound is exact only where the branch touches the
/// contact, so the true overlap at the certificate's normal (one support call of each shape) must
/// be within `tol` of its lower bound.
template <class S, class SupportA, class SupportB>
bool certificate_holds(const LocalCertificate<S>& lc, const SupportA& sa, const SupportB& sb, S tol) {
  const Vec3<S>& k = lc.normal;
  return lc.ok && k.dot(sa(k)) - k.dot(sb(Vec3<S>(-k))) - lc.lower <= tol;
}

/// EPA from GJK's tetrahedron (`calls` support calls so far, every stage's: EPA stops at the bound
/// counting them), seeded with the best candidate's normal when one has a finite depth (an upper
/// bound near the answer, and the local certificate's first start), and stopped early by `local`
/// unless options.local_certificate is off. `f` is PairFrame(pa, pb), the frame of `simplex`
/// (computed once a query). `newton_normal`, when given, is set to whether the answer's normal is
/// that of a certificate `local` gave (Newton's minimiser of the overlap's terms, the overlap along
/// it within the tolerance of the certified lower bound): no refinement after EPA moves such a
/// normal by more than rounding, so the callers skip theirs there.
template <class S, class A, class B, class Local>
ConvexContact<S> epa_from_simplex(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                  const ConvexQueryOptions<S>& o, const SimplexPoint<S> (&simplex)[4], int calls, const Local& local,
                                  const ConvexContact<S>& cand, const PairFrame<S>& f, bool* newton_normal = nullptr) {
  const Vec3<S>* seed = cand.depth < std::numeric_limits<S>::infinity() ? &cand.normal : nullptr;
  bool given = false;  // the last certificate `local` gave, in a's frame
  Vec3<S> given_normal = Vec3<S>::Zero();
  const auto recorded = [&](const Vec3<S>& n) {
    const LocalCertificate<S> lc = local(n);
    if (lc.ok) {
      given = true;
      given_normal = lc.normal;
    }
    return lc;
  };
  ConvexContact<S> g = o.local_certificate ? general_penetration(a, pa, b, pb, o, simplex, calls, recorded, seed, &f)
                                           : general_penetration(a, pa, b, pb, o, simplex, calls, NoLocalCertificate{}, seed, &f);
  if (newton_normal) {
    // EPA's normal is the certificate's (best_n = cert.normal, translated and rotated back) unless
    // a face's overlap was lower; 64 ulps allow for the rotation's rounding
    const S eps = S(64) * std::numeric_limits<S>::epsilon();
    *newton_normal = given && g.intersecting && !g.limit_reached &&
                     (Vec3<S>(pa.R.transpose() * g.normal) - given_normal).squaredNorm() <= eps * eps;
  }
  return g;
}

/// Two cylinders or cones whose axes are within a small tilt of parallel, after the general
/// penetration: when it stopped with its bracket open (a coaxial pair's least-overlap normals form
/// a circle EPA cannot close: about 515 support calls and a bracket of 7.5e-5 of the size at a tilt
/// of 1e-9 rad), the parallel-axes closed form certifies a bracket of about twice the tilt times
/// b's reach (convex/parallel_axes.hpp). The narrower of the two is kept; limit_reached stays set
/// unless it is within the tolerance. Skipped when its support call does not fit in the bound
/// (g.iterations spent; g stays flagged).
template <class S, class A, class B>
void narrow_by_parallel_axes(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                             const ConvexQueryOptions<S>& o, ConvexContact<S>& g) {
  if (!g.intersecting || !g.limit_reached || !fits(o, g.iterations, kCandidateCallsParallelAxes)) return;
  const PairFrame<S> f(pa, pb);
  ConvexContact<S> p;
  if (!parallel_axes_contact(a, b, f.R, f.t, g.depth_gap, p) || !(p.depth_gap < g.depth_gap)) return;
  settle_certified_from_frame(a, pa, b, pb, p);
  p.iterations += g.iterations;
  p.limit_reached = !(p.depth_gap <= o.relative_tolerance * query_scale<S>(a, b));
  g = p;
}

/// The options of EPA on a pair that narrow_by_parallel_axes may follow: the bound less that
/// stage's one support call, which it needs exactly when EPA stops at the bound (a coaxial pair at
/// the default bound: ParallelAxes.CoaxialTiltGetsTheClosedFormsBracket). When EPA closes its
/// bracket, the call is left to the refinements.
template <class S>
ConvexQueryOptions<S> leave_for_narrowing(const ConvexQueryOptions<S>& o) {
  ConvexQueryOptions<S> e = o;
  e.max_iterations -= kCandidateCallsParallelAxes;
  return e;
}

/// After EPA on two cylinders: EPA stops on its depth tolerance, and where f, the overlap along a
/// direction, is smooth and quadratic at its minimum, its normal is then within only about the
/// square root of that tolerance of the minimiser (4.6e-6 and 1.1e-5 rad on two of the bench's
/// 805 intersecting cylinder–cylinder poses, a cap against a rim, the depth within 1.3e-11 of the
/// size: docs/convex-notes.md, note 30). The local certificate from EPA's normal (Newton on the
/// closed-form overlap `terms`, a's frame) gives the minimiser of f on a cap about it; its normal
/// is taken when that cap holds EPA's normal and the overlap along it is no larger. EPA's lower
/// bound stays the bracket's lower end. That overlap is one support call (of each shape), counted
/// against `max_iterations` (one budget with g.iterations): when it does not fit, EPA's normal is
/// kept and g says limit_reached.
template <class S, class A, class B>
void refine_normal_locally(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, const OverlapTerms<S>& terms,
                           ConvexContact<S>& g, int max_iterations) {
  if (!g.intersecting || g.limit_reached) return;
  const Vec3<S> n0 = pa.R.transpose() * g.normal;
  const LocalCertificate<S> lc = local_certificate(terms, n0);
  if (!lc.ok || !(lc.normal.dot(n0) >= lc.cos_cap)) return;
  if (!(g.iterations < max_iterations)) {
    g.limit_reached = true;
    return;
  }
  ++g.iterations;
  keep_if_no_deeper(a, pa, b, pb, lc.normal, g);
}

/// The most evaluations of cone_side_valley_normal's search.
inline constexpr int kConeSideEvaluations = 32;

/// Where cone b's side touches the contact, the overlap f(n) = h_A(n) + h_B(-n) has a kink along
/// the circle of b's side normals (-n = m(u), u the azimuth: b's support along -n is a whole ruling,
/// its apex and its rim point tie) and its minimiser lies on that circle; EPA stops on its depth's
/// tolerance with its normal off along the circle by up to about the square root of it (1.7e-5 rad
/// on a cone-cone pose, 1.3e-5 on a capsule-cone: docs/convex-notes.md, note 32). On the circle
/// f = m . (apex - s_A(-m)) in closed form and its slope along the azimuth is m' . (apex - s_A(-m))
/// (the support point is the gradient of the support function). The search for its least value
/// within 1e-3 rad of EPA's azimuth starts there, where the minimum is near: secant steps on the
/// slope downhill (the first 1e-6 rad) until the slope turns, then regula falsi (Illinois) in that
/// bracket. It gives up at the window's edge, after 32 evaluations, or at a kink of f along the
/// circle: its first step in the bracket goes to where the ends' two supports tie, and when f there
/// is both ends' pieces (each with its end's support held) with lo's still falling and hi's rising,
/// the least value is on that kink. The search of convex/segment_cylinder.hpp over the whole
/// window, which this replaces, took 15-32 evaluations a call on the bench's poses; this about 4
/// where it finds the minimum (docs/convex-notes.md, note 35). In a's frame (b placed by R, t there; `sa` a's support
/// there), from EPA's normal n0 within 1e-3 rad of the circle; true and `n` set when the least value
/// lies inside the window with its slope within 1e-10 of the size (a local minimum of f on the
/// circle, the minimiser of f where the contact is the side's); `evaluations_out`, when given,
/// receives the evaluations of f (a support call of a each), 0 when the window was not entered.
/// The search takes at most kConeSideEvaluations evaluations, fewer when `max_evaluations` (what
/// the query's bound leaves) says so; `cut_short`, when given, is set to whether that smaller
/// bound ended the search before it decided (or left no room to start it).
template <class S, class SupportA>
bool cone_side_valley_normal(const SupportA& sa, const Cone<S>& b, const Mat3<S>& R, const Vec3<S>& t, const Vec3<S>& n0, S scale,
                             Vec3<S>& n, int* evaluations_out = nullptr, int max_evaluations = kConeSideEvaluations,
                             bool* cut_short = nullptr) {
  if (evaluations_out) *evaluations_out = 0;
  if (cut_short) *cut_short = false;
  const int most = std::min(kConeSideEvaluations, max_evaluations);
  const auto out_of_room = [&] {  // the search ended by `most` evaluations, undecided
    if (cut_short && most < kConeSideEvaluations) *cut_short = true;
    return false;
  };
  const Vec3<S> bz = R.col(2), apex = t + b.half_length * bz;
  const S len = std::sqrt(S(4) * b.half_length * b.half_length + b.radius * b.radius);
  const S ku = S(2) * b.half_length / len, kz = b.radius / len;  // m(u) = ku u + kz bz
  const Vec3<S> v = -n0, pv = v - bz.dot(v) * bz;
  const S pl = pv.norm();
  if (!(pl > S(1e-9))) return false;
  const Vec3<S> e1 = pv / pl, e2 = bz.cross(e1);
  const S window = S(1e-3);
  if (!((ku * e1 + kz * bz).dot(v) > std::cos(window))) return false;  // not near the side normals
  struct Trial {
    S x, f, g;  // azimuth from e1, f there and its slope
    Vec3<S> s;  // a's support point
  };
  const auto m_of = [&](S x) { return Vec3<S>(ku * (std::cos(x) * e1 + std::sin(x) * e2) + kz * bz); };
  const auto dm_of = [&](S x) { return Vec3<S>(ku * (std::cos(x) * e2 - std::sin(x) * e1)); };
  const auto eval = [&](S x) {
    if (evaluations_out) ++*evaluations_out;
    const S c = std::cos(x), sn = std::sin(x);
    const Vec3<S> m = ku * (c * e1 + sn * e2) + kz * bz, s = sa(Vec3<S>(-m)), gap = apex - s;
    return Trial{x, m.dot(gap), Vec3<S>(ku * (c * e2 - sn * e1)).dot(gap), s};
  };
  const S stop = std::max(S(1e-10) * scale, S(64) * std::numeric_limits<S>::epsilon() * scale);  // |df/dx|
  const auto found = [&](const Trial& e) {
    if (!(std::abs(e.x) < window)) return false;  // the least value at the window's edge: not found
    n = -m_of(e.x);
    return true;
  };
  if (most < 1) return out_of_room();
  int evaluations = 1;
  Trial lo = eval(S(0));
  if (!(lo.f > S(0))) return false;
  if (std::abs(lo.g) <= stop) return found(lo);
  // downhill from EPA's azimuth by secant steps on the slope (each at most 64 times the one
  // before; a slope that does not fall, 4 times) until it turns
  const S dir = lo.g < S(0) ? S(1) : S(-1);
  S step = S(1e-6);
  Trial hi;
  while (true) {
    if (!(std::abs(lo.x) < window)) return false;  // downhill up to the window's edge
    if (evaluations >= most) return out_of_room();
    const Trial e = eval(std::min(std::max(lo.x + dir * step, -window), window));
    ++evaluations;
    if (!(e.f > S(0))) return false;
    if (std::abs(e.g) <= stop) return found(e);
    if (dir * e.g > S(0)) {
      hi = e;
      break;
    }
    const S k = (e.g - lo.g) / (e.x - lo.x);  // the slope's rate, > 0 where f is convex
    const S next = k > S(0) ? std::abs(e.g / k) : S(4) * step;
    step = std::min(next, S(64) * step);
    lo = e;
  }
  // the slope turns between lo (downhill) and hi: regula falsi with Illinois' halving
  S glo = lo.g, ghi = hi.g;
  int side = 0;
  bool kink_tried = false;
  const S tie = S(16) * std::numeric_limits<S>::epsilon() * scale;
  while (evaluations < most) {
    const S a = std::min(lo.x, hi.x), c = std::max(lo.x, hi.x);
    if (!(c - a > S(8) * std::numeric_limits<S>::epsilon())) return false;
    S x = (lo.x * ghi - hi.x * glo) / (ghi - glo);
    if (!(x > a && x < c)) x = (lo.x + hi.x) / S(2);
    bool at_tie = false;
    const Vec3<S> d = hi.s - lo.s;
    if (!kink_tried && d.squaredNorm() > S(0)) {
      // where the ends' supports tie, m . d = 0 on the circle: ku (cos x e1 + sin x e2) . d = -kz bz . d
      kink_tried = true;
      const S al = ku * e1.dot(d), be = ku * e2.dot(d), ga = kz * bz.dot(d), r = std::hypot(al, be);
      if (r > std::abs(ga)) {
        const S psi = std::atan2(be, al), w = std::acos(-ga / r);
        for (const S y : {psi + w, psi - w}) {
          if (y > a && y < c) {
            x = y;
            at_tie = true;
            break;
          }
        }
      }
    }
    const Trial e = eval(x);
    ++evaluations;
    if (!(e.f > S(0))) return false;
    if (std::abs(e.g) <= stop) return found(e);
    if (at_tie) {
      // f there on both ends' pieces (a's support jumps from lo's to hi's: a kink of f along the
      // circle), lo's piece still falling and hi's rising: the least value is on the kink, which
      // this search does not resolve
      const Vec3<S> m = m_of(x), dm = dm_of(x);
      const Vec3<S> gap_lo = apex - lo.s, gap_hi = apex - hi.s;
      if (std::abs(e.f - m.dot(gap_lo)) <= tie && std::abs(e.f - m.dot(gap_hi)) <= tie && dir * dm.dot(gap_lo) <= S(0) &&
          dir * dm.dot(gap_hi) >= S(0))
        return false;
    }
    if (dir * e.g < S(0)) {
      lo = e;
      glo = e.g;
      if (side == -1) ghi /= S(2);
      side = -1;
    } else {
      hi = e;
      ghi = e.g;
      if (side == 1) glo /= S(2);
      side = 1;
    }
  }
  return out_of_room();
}

/// EPA's contact g of a and cone b refined on b's side (cone_side_valley_normal): the normal taken
/// where the true overlap along it is no larger; EPA's lower bound stays the bracket's lower end.
/// `mirror`: b is the first shape of the query (g's normal points from b towards a). Its support
/// calls (the search's evaluations and the overlap along the normal found) count in g.iterations
/// against `max_iterations` (one budget, budgeted_search of convex/edge_valley.hpp): the search
/// gets what is left less one for that overlap, and when that cuts it short, EPA's normal is kept
/// and g says limit_reached.
template <class S, class A>
void refine_on_cone_side(const A& a, const RigidTransform<S>& pa, const Cone<S>& b, const RigidTransform<S>& pb, ConvexContact<S>& g,
                         int max_iterations, bool mirror = false) {
  if (!g.intersecting || g.limit_reached) return;
  const PairFrame<S> f(pa, pb);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const Vec3<S> n0 = pa.R.transpose() * (mirror ? Vec3<S>(-g.normal) : g.normal);
  const S scale = query_scale<S>(a, b);
  Vec3<S> n;
  const auto search = [&](int most, int& evaluations, bool& cut_short) {
    return cone_side_valley_normal(sa, b, f.R, f.t, n0, scale, n, &evaluations, most, &cut_short);
  };
  if (!budgeted_search(g, max_iterations, search)) return;
  ConvexContact<S> r = g;
  r.normal = pa.rotate(mirror ? Vec3<S>(-n) : n);
  if (mirror) {
    settle_contact(b, pb, a, pa, r);
  } else {
    settle_contact(a, pa, b, pb, r);
  }
  if (!(r.depth <= g.depth)) return;
  r.depth_gap = std::max(r.depth - (g.depth - g.depth_gap), S(0));
  g = r;
}

/// A cylinder and a cylinder or cone: the overlap along the line between their centres (a negative
/// one separates them: no contact; 85-90 % of the bench's separated poses end here), then
/// the certified candidates of convex/cylinder_pair.hpp (caps, rulings, a ruling or a side against
/// a rim point; their certificate, a positive lower bound of the depth, proves the intersection,
/// so no GJK runs), else GJK until it encloses the origin or separates them (no contact), and EPA
/// from GJK's tetrahedron.
template <class S, class B>
ConvexContact<S> cylinder_pair_penetration(const Cylinder<S>& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb,
                                           const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b);
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  const Vec3<S> centre_b = f.b_to_a(interior_point(b));  // a's centre is its frame's origin
  // a plane normal to the line between the centres separates them (by more than rounding: a pair
  // touching within rounding goes on to GJK, which decides it)
  if (separated_along(sa, sb, centre_b, scale)) return one_plane_apart<S>();
  int its = 1;  // the plane along the centre line; each stage adds its calls (one budget)
  const S tol = o.relative_tolerance * scale;
  ConvexContact<S> c;
  if (fits(o, its, kCandidateCallsParallelAxes) && parallel_axes_contact(a, b, f.R, f.t, tol, c)) return settled(a, pa, b, pb, c, its);
  constexpr int most = std::is_same_v<B, Cone<S>> ? kCandidateCallsCylinderCone : kCandidateCallsCylinderPair;
  if (candidates_fit(o, its, most, c)) {
    bool certified;
    if constexpr (std::is_same_v<B, Cone<S>>) {
      certified = cylinder_cone_contact(a, b, f.R, f.t, tol, c);
    } else {
      certified = cylinder_pair_contact(a, b, f.R, f.t, tol, c);
    }
    IMPACT_ASSERT(c.iterations <= most);
    if (certified) return settled(a, pa, b, pb, c, its);
    its += c.iterations;
    // a candidate's direction with a negative overlap (beyond rounding) is a separating plane: no
    // contact without GJK (33 of the 145 separated poses of the bench's 2000 cylinder–cone poses
    // that the centre line leaves)
    if (c.depth < -std::numeric_limits<S>::epsilon() * S(16) * scale) return no_contact<S>(its);
  }
  SimplexPoint<S> simplex[4];
  switch (enclose_origin(sa, sb, Vec3<S>(-centre_b), scale, o, simplex, its)) {
    case Enclosure::Unsure: return general_after(a, pa, b, pb, o, its);
    case Enclosure::Apart: return no_contact<S>(its);
    case Enclosure::Enclosed: break;
  }
  // EPA from GJK's tetrahedron (its support calls counted once, in g.iterations), stopped early by
  // the local certificate of convex/local_certificate.hpp where it holds
  const auto local = [&](const Vec3<S>& n) {
    if constexpr (std::is_same_v<B, Cone<S>>) {
      // a bound through the cone's branch or a body inside it is exact only where that branch or
      // body touches the contact: accepted when the true overlap at the certified normal is within
      // the tolerance of the bound
      OverlapTerms<S> terms;
      if (cylinder_cone_terms(a, b, f.R, f.t, n, terms)) {
        const LocalCertificate<S> lc = local_certificate(terms, n);
        if (certificate_holds(lc, sa, sb, tol)) return lc;
      }
      // the cone's side (a's rim or ruling against it): the body inside b along the ruling of the
      // minimiser along b's side normals, past the contact's point of it (its overlap is exact
      // there); else no certificate (moving the body round by round to the ruling of the
      // minimiser found, up to 8 rounds, certified 9 of the 88 queries that got this far on the
      // bench's 2000 poses at 226 certificate evaluations, more than it saved)
      const LocalCertificate<S> side = cylinder_cone_side_certificate(a, b, f.R, f.t, n);
      if (certificate_holds(side, sa, sb, tol)) return side;
      return LocalCertificate<S>();
    } else {
      return local_certificate(cylinder_pair_terms(a, b, f.R, f.t), n);
    }
  };
  bool newton_normal = false;
  ConvexContact<S> g = epa_from_simplex(a, pa, b, pb, leave_for_narrowing(o), simplex, its, local, c, f, &newton_normal);
  narrow_by_parallel_axes(a, pa, b, pb, o, g);
  // a certificate's normal is the terms' minimiser already: no refinement (for two cylinders the
  // same Newton on the same terms from that normal, which stays there)
  if constexpr (std::is_same_v<B, Cylinder<S>>) {
    if (!newton_normal) refine_normal_locally(a, pa, b, pb, cylinder_pair_terms(a, b, f.R, f.t), g, o.max_iterations);
  } else if (!newton_normal) {
    OverlapTerms<S> terms;
    if (g.intersecting && cylinder_cone_terms(a, b, f.R, f.t, Vec3<S>(pa.R.transpose() * g.normal), terms)) {
      refine_normal_locally(a, pa, b, pb, terms, g, o.max_iterations);
    }
    refine_on_cone_side(a, pa, b, pb, g, o.max_iterations);
  }
  return g;
}

/// Two cones: the closed form of convex/parallel_axes.hpp when their axes are parallel; else a
/// plane normal to the line between the centres (separating: no contact; most separated poses),
/// GJK until it encloses the origin or separates them (no contact), then the certified candidates
/// of convex/cone_cone_pair.hpp (bases, apexes, rims against sides, rulings), else EPA from GJK's
/// tetrahedron, seeded with the best candidate's direction and stopped early by the local
/// certificate of convex/local_certificate.hpp on the terms of each cone's branch active at EPA's
/// normal; where a branch ties (a side ruling touches the contact) on the other cone's active
/// branch and a body inside the first along the ruling where the overlap along its side normals
/// is least (cone_side_newton, cone_cone_side_terms), either cone's side; accepted when the true
/// overlap at its normal is within the tolerance of its lower bound.
template <class S>
ConvexContact<S> cone_pair_penetration(const Cone<S>& a, const RigidTransform<S>& pa, const Cone<S>& b, const RigidTransform<S>& pb,
                                       const ConvexQueryOptions<S>& o) {
  const PairPath<S, Cone<S>, Cone<S>> path(a, pa, b, pb, o);
  const PairFrame<S>& f = path.f;
  const S tol = path.tol;
  const auto& sa = path.sa;
  const auto& sb = path.sb;
  // a plane normal to the line between the centres separates them (most separated poses)
  if (path.separated()) return one_plane_apart<S>();
  int its = 1;  // the plane; each stage adds its calls (one budget)
  ConvexContact<S> cand;
  if (fits(o, its, kCandidateCallsParallelAxes) && parallel_axes_contact(a, b, f.R, f.t, tol, cand)) return settled(a, pa, b, pb, cand, its);
  SimplexPoint<S> simplex[4];
  if (!path.enclose(simplex, its, cand)) {
    narrow_by_parallel_axes(a, pa, b, pb, o, cand);  // the general path's answer (no contact: unchanged)
    return cand;
  }
  if (candidates_fit(o, its, kCandidateCallsConeCone, cand)) {
    const bool certified = cone_cone_contact(a, b, f.R, f.t, tol, cand);
    IMPACT_ASSERT(cand.iterations <= kCandidateCallsConeCone);
    if (certified) return settled(a, pa, b, pb, cand, its);
    its += cand.iterations;
  }
  const Mat3<S> Rs = f.R.transpose();
  const Vec3<S> ts = -(Rs * f.t);
  const auto local = [&](const Vec3<S>& n) {
    OverlapTerms<S> terms;
    if (cone_cone_terms(a, b, f.R, f.t, n, terms)) {
      const LocalCertificate<S> lc = local_certificate(terms, n);
      if (certificate_holds(lc, sa, sb, tol)) return lc;
    }
    // b's side against a: Newton along b's side normals, then the body inside b along that ruling
    // from its base rim point to past the contact's point of it
    Vec3<S> m = n;
    if (cone_side_newton(a, b, f.R, f.t, m) &&
        cone_cone_side_terms(a, b, f.R, f.t, m, terms, S(0), side_body_end(cone_side_contact(a, b, f.R, f.t, m)))) {
      const LocalCertificate<S> lc = local_certificate(terms, m);
      if (certificate_holds(lc, sa, sb, tol)) return lc;
    }
    // a's side against b: the same in b's frame (the overlap there is f(-R w)), mapped back
    m = -(Rs * n);
    if (cone_side_newton(b, a, Rs, ts, m) &&
        cone_cone_side_terms(b, a, Rs, ts, m, terms, S(0), side_body_end(cone_side_contact(b, a, Rs, ts, m)))) {
      LocalCertificate<S> lc = local_certificate(terms, m);
      lc.normal = -(f.R * lc.normal);
      if (certificate_holds(lc, sa, sb, tol)) return lc;
    }
    return LocalCertificate<S>();
  };
  bool newton_normal = false;
  ConvexContact<S> g = epa_from_simplex(a, pa, b, pb, leave_for_narrowing(o), simplex, its, local, cand, f, &newton_normal);
  narrow_by_parallel_axes(a, pa, b, pb, o, g);
  if (newton_normal) return g;  // a certificate's normal is the terms' minimiser already
  OverlapTerms<S> terms;
  if (g.intersecting && cone_cone_terms(a, b, f.R, f.t, Vec3<S>(pa.R.transpose() * g.normal), terms)) {
    refine_normal_locally(a, pa, b, pb, terms, g, o.max_iterations);
  }
  refine_on_cone_side(a, pa, b, pb, g, o.max_iterations);
  refine_on_cone_side(b, pb, a, pa, g, o.max_iterations, true);
  return g;
}

/// A cone (a) and a box (b): planes normal to the line between the centres and to the box's axes
/// (separating: no contact), the certified candidates of convex/cone_box_pair.hpp (a face of the
/// box against the cone's deepest point, a corner or an edge of the box through the cone's side or
/// base), else GJK from the best candidate's normal until it encloses the origin or separates them
/// (no contact), and EPA from GJK's tetrahedron, stopped early by the local certificate of
/// convex/local_certificate.hpp on the terms of convex/cone_box_terms.hpp (the cone's branch active
/// at EPA's normal; near a side ruling, a body inside the cone along the ruling the box touches).
/// A bound through one branch or body is exact only where it touches the contact, so a
/// certificate is accepted when the true overlap at its normal is within the tolerance of its
/// lower bound.
template <class S>
ConvexContact<S> cone_box_penetration(const Cone<S>& a, const RigidTransform<S>& pa, const Box<S>& b, const RigidTransform<S>& pb,
                                      const ConvexQueryOptions<S>& o) {
  const PairPath<S, Cone<S>, Box<S>> path(a, pa, b, pb, o);
  const PairFrame<S>& f = path.f;
  const S tol = path.tol;
  const auto& sa = path.sa;
  const auto& sb = path.sb;
  // a plane normal to the line between the centres separates them (most separated poses)
  if (path.separated()) return one_plane_apart<S>();
  // a plane normal to one of the box's axes (about half of the separated poses left, without GJK)
  if (cone_box_apart_along_box_axes(a, b, f.R, f.t, std::numeric_limits<S>::epsilon() * S(16) * path.scale))
    return one_plane_apart<S>();
  // the certified candidates of convex/cone_box_pair.hpp (a certified lower bound is positive, so
  // it proves the intersection: no GJK), else GJK from the best candidate's normal, when one
  // applied (its first support point, deep in D, is then a vertex of EPA's first polytope), and
  // EPA from its tetrahedron. Before GJK: on the bench's 2000 poses, instructions per query
  // 3,126 -> 2,928 (intersecting poses 13,172 -> 11,695; support calls 4,369 -> 3,631), the
  // separated poses left to GJK (80) paying for the candidates
  int its = 1;  // the planes; each stage adds its calls (one budget)
  ConvexContact<S> cand;
  if (candidates_fit(o, its, kCandidateCallsConeBox, cand)) {
    const bool certified = cone_box_contact(a, b, f.R, f.t, tol, cand);
    IMPACT_ASSERT(cand.iterations <= kCandidateCallsConeBox);
    if (certified) return settled(a, pa, b, pb, cand, its);
    its += cand.iterations;
  }
  SimplexPoint<S> simplex[4];
  ConvexContact<S> answer;
  const bool seeded = cand.depth < std::numeric_limits<S>::infinity();
  if (!path.enclose(simplex, its, answer, seeded ? &cand.normal : nullptr)) return answer;
  const auto local = [&](const Vec3<S>& n) {
    // near a side ruling (its branches within 0.02 of the size): the body inside the cone along
    // the ruling the box touches (a box edge across the side: 90 of the bench's 239 EPA poses)
    if (std::abs(cone_branch_gap(a, n)) <= S(0.02) * (a.half_length + a.radius)) {
      const LocalCertificate<S> lc = cone_box_side_certificate(a, b, f.R, f.t, n);
      if (certificate_holds(lc, sa, sb, tol)) return lc;
    }
    OverlapTerms<S> terms;
    if (cone_box_terms(a, b, f.R, f.t, n, terms)) {
      const LocalCertificate<S> lc = local_certificate(terms, n);
      if (certificate_holds(lc, sa, sb, tol)) return lc;
    }
    return LocalCertificate<S>();
  };
  bool newton_normal = false;
  ConvexContact<S> g = epa_from_simplex(a, pa, b, pb, o, simplex, its, local, cand, f, &newton_normal);
  if (!newton_normal) refine_on_cone_side(b, pb, a, pa, g, o.max_iterations, true);  // else the terms' minimiser already
  return g;
}

/// A cylinder (a) and a box (b): the planes of convex/cylinder_box_pair.hpp (the line between the
/// centres, the box's axes, the cylinder's axis, normal to the axis and a box edge; separating: no
/// contact), the certified candidates of convex/cylinder_box_pair.hpp (a certified lower bound is
/// positive, so it proves the intersection: no GJK; before GJK saves 4 % of the instructions on
/// the bench's poses), else GJK until it encloses the origin or separates them, and EPA from its
/// tetrahedron seeded with the best candidate's direction and stopped early by the local
/// certificate on cylinder_box_terms (the overlap's exact terms, so no check of a branch).
template <class S>
ConvexContact<S> cylinder_box_penetration(const Cylinder<S>& a, const RigidTransform<S>& pa, const Box<S>& b, const RigidTransform<S>& pb,
                                          const ConvexQueryOptions<S>& o) {
  const PairFrame<S> f(pa, pb);
  const S scale = query_scale<S>(a, b), tol = o.relative_tolerance * scale;
  const S margin = std::numeric_limits<S>::epsilon() * S(16) * scale;
  {  // a plane normal to the line between the centres separates them (most separated poses)
    const S len = f.t.norm();
    if (len > S(0) && cylinder_box_overlap(a, b, f.R, f.t, Vec3<S>(f.t / len)) < -margin) return one_plane_apart<S>();
  }
  if (cylinder_box_apart(a, b, f.R, f.t, margin)) return one_plane_apart<S>();
  int its = 1;  // the planes; each stage adds its calls (one budget)
  ConvexContact<S> cand;
  if (candidates_fit(o, its, kCandidateCallsCylinderBox, cand)) {
    const bool certified = cylinder_box_contact(a, b, f.R, f.t, tol, cand);
    IMPACT_ASSERT(cand.iterations <= kCandidateCallsCylinderBox);
    if (certified) return settled(a, pa, b, pb, cand, its);
    its += cand.iterations;
  }
  const auto sa = [&](const Vec3<S>& d) { return support(a, d); };
  const auto sb = [&](const Vec3<S>& d) { return f.support_b(b, d); };
  SimplexPoint<S> simplex[4];
  // GJK's first support along the best candidate's normal, when one applied (near the contact's
  // side of D: fewer steps to enclose the origin than from the centre line)
  const Vec3<S> start = cand.depth < std::numeric_limits<S>::infinity() ? Vec3<S>(-cand.normal) : Vec3<S>(-f.t);
  switch (enclose_origin(sa, sb, start, scale, o, simplex, its)) {
    case Enclosure::Unsure: return general_after(a, pa, b, pb, o, its);
    case Enclosure::Apart: return no_contact<S>(its);
    case Enclosure::Enclosed: break;
  }
  const OverlapTerms<S> terms = cylinder_box_terms(a, b, f.R, f.t);
  const auto local = [&](const Vec3<S>& n) { return local_certificate(terms, n); };
  return epa_from_simplex(a, pa, b, pb, o, simplex, its, local, cand, f);
}

/// The normal of a contact g of a cylinder or cone a and hull b refined when `uncertain` (EPA
/// stopped on its depth tolerance, or a candidate certified its depth only: the normal then within
/// only about the square root of the tolerance of the minimiser) along the valley of a hull edge
/// orthogonal to it (refine_on_hull_edge, convex/edge_valley.hpp: the minimiser on the kink
/// of the edge's term, where Newton on the overlap's terms cannot stay) and, for a cone, along
/// the valley of its side normals (refine_on_cone_side), each kept where the true overlap along
/// it is no larger. (Newton on cylinder_hull_terms where the overlap is smooth,
/// tried too, changed no pose of the sweep the valley search left above 1e-8 rad: note 34.)
/// Both count their support calls in g.iterations against `max_iterations` (one budget), each
/// getting what the one before left; one cut short keeps g's normal and sets limit_reached.
template <class S, class A>
ConvexContact<S> refined_hull_normal(const A& a, const RigidTransform<S>& pa, const ConvexHull<S>& b, const RigidTransform<S>& pb,
                                     ConvexContact<S> g, bool uncertain, int max_iterations) {
  if (!uncertain) return g;
  refine_on_hull_edge(a, pa, b, pb, g, max_iterations);
  if constexpr (std::is_same_v<A, Cone<S>>) refine_on_cone_side(b, pb, a, pa, g, max_iterations, true);  // a hull vertex on a's side
  return g;
}

/// A cylinder (a) and a convex hull (b): a plane normal to the line between the centres, then the
/// candidates of convex/cylinder_hull_pair.hpp (the hull's face planes, which also separate most
/// of the separated poses left; faces, caps and edges across the side, certified by a ball inside
/// one shape; a certified lower bound is positive, so it proves the intersection: no GJK), else
/// GJK until it encloses the origin or separates them, and EPA from its tetrahedron seeded with
/// the best candidate's direction and stopped early by the local certificate on
/// cylinder_hull_terms (the hull's vertex or edge at EPA's normal) or, while EPA's best normal is
/// still a face candidate's (a rim against a hull face whose ball is cut), on the cylinder's terms
/// and a square of that face (add_hull_face_square_terms), accepted when the true overlap at its
/// normal is within the tolerance of its lower bound.
template <class S>
ConvexContact<S> cylinder_hull_penetration(const Cylinder<S>& a, const RigidTransform<S>& pa, const ConvexHull<S>& b,
                                           const RigidTransform<S>& pb, const ConvexQueryOptions<S>& o) {
  const PairPath<S, Cylinder<S>, ConvexHull<S>> path(a, pa, b, pb, o);
  const PairFrame<S>& f = path.f;
  const S tol = path.tol;
  const S margin = std::numeric_limits<S>::epsilon() * S(16) * path.scale;
  const auto& sa = path.sa;
  const auto& sb = path.sb;
  // a plane normal to the line between the centres separates them (most separated poses)
  if (path.separated()) return one_plane_apart<S>();
  int its = 1;  // the plane; each stage adds its calls (one budget)
  ConvexContact<S> cand;
  std::size_t cand_face = b.faces.size();  // the face whose candidate is the best (none: b.faces.size())
  if (candidates_fit(o, its, kCandidateCallsCylinderHull, cand)) {
    const CylinderHullVerdict verdict = cylinder_hull_candidates(a, b, f.R, f.t, margin, tol, cand, &cand_face);
    IMPACT_ASSERT(cand.iterations <= kCandidateCallsCylinderHull);
    if (verdict == CylinderHullVerdict::Apart) return one_plane_apart<S>();
    // a certified candidate's normal is the minimiser when its bound is exact (depth_gap 0)
    if (verdict == CylinderHullVerdict::Certified) {
      return refined_hull_normal(a, pa, b, pb, settled(a, pa, b, pb, cand, its), cand.depth_gap > S(0), o.max_iterations);
    }
    its += cand.iterations;
  }
  SimplexPoint<S> simplex[4];
  ConvexContact<S> answer;
  // GJK's first support along the best candidate's normal, when one applied (as cylinder–box)
  const bool seeded = cand.depth < std::numeric_limits<S>::infinity();
  if (!path.enclose(simplex, its, answer, seeded ? &cand.normal : nullptr)) return answer;
  const auto local = [&](const Vec3<S>& n) {
    if (cand_face < b.faces.size() && n == cand.normal) {  // EPA's best normal still the face candidate's
      OverlapTerms<S> terms;                              // the cylinder's terms and a square of that face
      terms.add(Vec3<S>::UnitZ(), a.radius, true);
      terms.add(Vec3<S>::UnitZ(), a.half_length, false);
      if (add_hull_face_square_terms(b, f.R, f.t, cand_face, sa(n), terms)) {
        const LocalCertificate<S> lc = local_certificate(terms, n);
        if (certificate_holds(lc, sa, sb, tol)) return lc;
      }
    }
    const LocalCertificate<S> lc = local_certificate(cylinder_hull_terms(a, b, f.R, f.t, n), n);
    if (certificate_holds(lc, sa, sb, tol)) return lc;
    return LocalCertificate<S>();
  };
  bool newton_normal = false;  // EPA's normal is a certificate's: the minimiser already
  const ConvexContact<S> g = epa_from_simplex(a, pa, b, pb, o, simplex, its, local, cand, f, &newton_normal);
  return refined_hull_normal(a, pa, b, pb, g, !newton_normal, o.max_iterations);
}

/// A cone (a) and a convex hull (b): a plane normal to the line between the centres, then the
/// candidates of convex/cone_hull_pair.hpp (the hull's face planes, also separating; faces, the
/// base, and edges and vertices across the side, each certified by a ball; a certified lower bound
/// is positive, so it proves the intersection: no GJK), else GJK (from the best candidate's
/// direction) until it encloses the origin or separates them (no contact), then EPA from GJK's
/// tetrahedron seeded with that direction and stopped early by the local certificate on
/// cone_hull_terms (the cone's branch active at EPA's normal and the hull's vertex or edge there)
/// or, near a side ruling of the cone, on cone_side_hull_terms (a body inside the cone along the
/// ruling the hull's feature touches), accepted when the true overlap at its normal is within the
/// tolerance of its lower bound.
template <class S>
ConvexContact<S> cone_hull_penetration(const Cone<S>& a, const RigidTransform<S>& pa, const ConvexHull<S>& b, const RigidTransform<S>& pb,
                                       const ConvexQueryOptions<S>& o) {
  const PairPath<S, Cone<S>, ConvexHull<S>> path(a, pa, b, pb, o);
  const PairFrame<S>& f = path.f;
  const S tol = path.tol;
  const S margin = std::numeric_limits<S>::epsilon() * S(16) * path.scale;
  const auto& sa = path.sa;
  const auto& sb = path.sb;
  if (path.separated()) return one_plane_apart<S>();
  int its = 1;  // the plane; each stage adds its calls (one budget)
  ConvexContact<S> cand;
  if (candidates_fit(o, its, kCandidateCallsConeHull, cand)) {
    const CylinderHullVerdict verdict = cone_hull_candidates(a, b, f.R, f.t, margin, tol, cand);
    IMPACT_ASSERT(cand.iterations <= kCandidateCallsConeHull);
    if (verdict == CylinderHullVerdict::Apart) return one_plane_apart<S>();
    // a certified candidate's normal is the minimiser when its bound is exact (depth_gap 0)
    if (verdict == CylinderHullVerdict::Certified) {
      return refined_hull_normal(a, pa, b, pb, settled(a, pa, b, pb, cand, its), cand.depth_gap > S(0), o.max_iterations);
    }
    its += cand.iterations;
  }
  SimplexPoint<S> simplex[4];
  ConvexContact<S> answer;
  const bool seeded = cand.depth < std::numeric_limits<S>::infinity();
  if (!path.enclose(simplex, its, answer, seeded ? &cand.normal : nullptr)) return answer;
  const auto local = [&](const Vec3<S>& n) {
    OverlapTerms<S> terms;
    const S gap = cone_branch_gap(a, n);
    if (std::abs(gap) > S(0.02) * (a.half_length + a.radius)) {
      // away from the cone's side: its active branch (a side contact's branch terms never hold)
      if (cone_hull_terms(a, b, f.R, f.t, n, cone_branch_of_gap(a, gap), terms)) {
        const LocalCertificate<S> lc = local_certificate(terms, n);
        if (certificate_holds(lc, sa, sb, tol)) return lc;
      }
      return LocalCertificate<S>();
    }
    // near the side: the body inside a along the ruling the hull's feature touches, at its side
    // normal m, from the base rim point to past the hull's contact point on that ruling
    Vec3<S> e;
    if (!cone_hull_side_azimuth(a, b, f.R, f.t, n, e)) return LocalCertificate<S>();
    const Vec3<S> m = Vec3<S>(S(2) * a.half_length * e.x(), S(2) * a.half_length * e.y(), a.radius).normalized();
    const Vec3<S> x = sb(Vec3<S>(-m));
    const Vec3<S> p(a.radius * e.x(), a.radius * e.y(), -a.half_length), d = Vec3<S>(S(0), S(0), a.half_length) - p;
    if (cone_side_hull_terms(a, b, f.R, f.t, m, e, side_body_end((x - p).dot(d) / d.dot(d)), terms)) {
      const LocalCertificate<S> lc = local_certificate(terms, m);
      if (certificate_holds(lc, sa, sb, tol)) return lc;
    }
    return LocalCertificate<S>();
  };
  bool newton_normal = false;  // EPA's normal is a certificate's: the minimiser already
  const ConvexContact<S> g = epa_from_simplex(a, pa, b, pb, o, simplex, its, local, cand, f, &newton_normal);
  return refined_hull_normal(a, pa, b, pb, g, !newton_normal, o.max_iterations);
}

}  // namespace detail
}  // namespace impact
