// SPDX-License-Identifier: MIT
/// \file
/// Separation distance and witness points of two convex sets given by their support functions:
/// the GJK algorithm (Gilbert, Johnson & Keerthi 1988) in the form of van den Bergen ("Collision
/// Detection in Interactive 3D Environments", 2003, section 4.3): the simplex's closest point to
/// the origin by signed volumes (convex/signed_volumes.hpp, Montanari et al. 2017), a relative
/// stopping test on the duality gap, and a bound on the iterations. libccd has no distance query
/// (its GJK answers only "intersecting or not"), so this one is the library's own; it needs Eigen
/// only.
///
/// Numerical contract: APPROXIMATE. On return with converged = true the reported distance d and the
/// true distance d* satisfy d - tolerance <= d* <= d (d is the length of a vector of the Minkowski
/// difference, an upper bound; the stopping test bounds the gap), and the witness points are points
/// of the two sets (convex combinations of support points) d apart. Sets closer than `tolerance`
/// may be reported as intersecting (distance 0). When rounding stalls the solver with its gap still
/// wider than 4 tolerances, it runs again from there on the same support points in a wider type
/// (float in double, double in long double) and returns that run's answer if it converges. When
/// the iteration bound is hit, or the wider run stalls too, limit_reached is set and the best upper
/// bound found so far is returned; max_iterations bounds the support calls of both runs together.
/// A boolean query (a margin, stop_within_margin) answers "apart" only on a separating plane
/// beyond the margin: a stall runs again in the wider type whatever its gap, and when that run
/// cannot decide either but the gap was within 4 tolerances, the sets count as touching.
#pragma once

#include "impact/convex/signed_volumes.hpp"
#include "impact/core/types.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

namespace impact {

/// Result of a distance query between two convex shapes, in world coordinates.
template <class S>
struct ConvexDistance {
  S distance = S(0);               ///< >= 0; 0 when the shapes intersect
  Vec3<S> point_a = Vec3<S>::Zero();  ///< closest point of the first shape (unspecified when intersecting)
  Vec3<S> point_b = Vec3<S>::Zero();  ///< closest point of the second shape (unspecified when intersecting)
  bool intersecting = false;       ///< the shapes touch or overlap (within the tolerance)
  int iterations = 0;              ///< support-point evaluations of each shape
  /// The iteration bound or a rounding stall stopped the solver before its tolerance: `intersecting`
  /// is then not decided (either value may be wrong); the distance is still an upper bound.
  bool limit_reached = false;
};

namespace detail {

/// A unit vector orthogonal to u (u unit).
template <class S>
inline Vec3<S> any_orthogonal(const Vec3<S>& u) {
  const Vec3<S> t = std::abs(u.x()) < S(0.6) ? Vec3<S>::UnitX() : Vec3<S>::UnitY();
  return u.cross(t).normalized();
}

/// The support point of the Minkowski difference A - B in direction d, with its two witnesses.
template <class S, class SupportA, class SupportB>
SimplexPoint<S> minkowski_support(const SupportA& support_a, const SupportB& support_b, const Vec3<S>& d) {
  SimplexPoint<S> p;
  p.a = support_a(d);
  p.b = support_b(Vec3<S>(-d));
  p.w = p.a - p.b;
  return p;
}

/// What one GJK step did with a new support point p (gjk_step).
enum class GjkStep {
  Repeated,    ///< p is already a vertex of the simplex: nothing changed
  Inside,      ///< the simplex with p holds the origin
  NoProgress,  ///< the closest point did not come nearer (rounding): the simplex is kept as it was
  Progress,    ///< p joined the simplex; v is its new closest point to the origin
  Level,       ///< p joined the simplex, whose closest point came no nearer, within the slack (gjk_step)
};

/// A simplex set aside by a Level step of gjk_step (the state before it: points, weights, closest
/// point v and |v|^2), for the distance query to return to if no later step comes nearer.
template <class S>
struct GjkSavedSimplex {
  SimplexPoint<S> s[4];
  S lambda[4] = {S(0), S(0), S(0), S(0)};
  int n = 0;
  Vec3<S> v = Vec3<S>::Zero();
  S vv = std::numeric_limits<S>::infinity();
};

/// Adds p to the simplex s[0..n) (barycentric lambda, closest point v to the origin, |v|^2 = vv)
/// and reduces it to the face closest to the origin: the step shared by the distance query and
/// EPA's enclosing simplex (epa.hpp). With `level` given, a new closest point that comes no nearer
/// than v within the rounding of the simplex (|v'|^2 <= vv + 32 eps |v| W, W the largest |w| of
/// its points) is kept (Level), and the state before the step is saved in *level when it is nearer
/// than the one saved there; without it such a step is undone (NoProgress).
template <class S>
GjkStep gjk_step(SimplexPoint<S>* s, int& n, S* lambda, Vec3<S>& v, S vv, const SimplexPoint<S>& p,
                 GjkSavedSimplex<S>* level = nullptr) {
  for (int i = 0; i < n; ++i)
    if (s[i].w == p.w) return GjkStep::Repeated;
  // s[n] is free (a reduced simplex has at most 3 points): p goes there, and s[0..n) stays as it
  // was until the step is kept
  s[n] = p;
  SimplexClosest<S> r;
  if (!sv_closest(s, n + 1, r)) {
    ++n;
    return GjkStep::Inside;
  }
  const S nvv = r.vv;
  bool keep = nvv < vv;
  if (!keep && level) {
    S w2 = p.w.squaredNorm();
    for (int i = 0; i < n; ++i) w2 = std::max(w2, s[i].w.squaredNorm());
    if (nvv <= vv + S(32) * std::numeric_limits<S>::epsilon() * std::sqrt(vv * w2)) {
      if (vv < level->vv) {
        for (int i = 0; i < n; ++i) {
          level->s[i] = s[i];
          level->lambda[i] = lambda[i];
        }
        level->n = n;
        level->v = v;
        level->vv = vv;
      }
      keep = true;
    }
  }
  if (!keep) return GjkStep::NoProgress;
  SimplexPoint<S> kept[4];
  for (int i = 0; i < r.m; ++i) kept[i] = s[r.index[i]];
  for (int i = 0; i < r.m; ++i) {
    s[i] = kept[i];
    lambda[i] = r.lambda[i];
  }
  n = r.m;
  v = r.v;
  return nvv < vv ? GjkStep::Progress : GjkStep::Level;
}

/// At most this many GJK steps per distance query may keep a simplex whose closest point came no
/// nearer (GjkStep::Level).
inline constexpr int kGjkLevelSteps = 8;

/// GJK distance between A and B given world support functions support_a(d), support_b(d) (points
/// maximising the dot product with d), a first direction (e.g. the difference of two interior
/// points, a minus b), an absolute tolerance and an iteration bound. With `margin` >= 0 it answers
/// only "distance <= margin?" and stops as soon as that is decided: intersecting is then set when
/// an upper bound of the distance is <= margin, cleared when a lower bound exceeds it (the
/// distance and points are then those bounds', not converged). With `margin` >= 0 and
/// `stop_within_margin` false it stops early only on a lower bound beyond the margin (cleared,
/// distance > margin) and otherwise converges to the tolerance as without a margin: the exact
/// distance where it is needed, the cheap answer where it is not (a round shape's core farther
/// than its radius). `plane`, when given, receives the direction v of GJK's best lower bound of the
/// distance (the separating plane {x : v . x = lower |v|} of the Minkowski difference A - B; the
/// unit normal from A towards B is -v / |v|), zero when no plane was found.
template <class S, class SupportA, class SupportB>
ConvexDistance<S> gjk_distance(const SupportA& support_a, const SupportB& support_b, Vec3<S> first, S tolerance,
                               int max_iterations, S margin = S(-1), bool stop_within_margin = true, Vec3<S>* plane = nullptr) {
  ConvexDistance<S> out;
  if (!(first.squaredNorm() > S(0))) first = Vec3<S>::UnitX();
  SimplexPoint<S> s[4];
  S lambda[4] = {S(1), S(0), S(0), S(0)};
  int n = 1;
  s[0].a = support_a(Vec3<S>(-first));
  s[0].b = support_b(first);
  s[0].w = s[0].a - s[0].b;
  out.iterations = 1;
  Vec3<S> v = s[0].w;
  const S tol2 = tolerance * tolerance;
  bool converged = false;
  S lower = S(0);       // the best lower bound of the distance so far
  Vec3<S> lower_v = Vec3<S>::Zero();  // the v that gave it
  int level_steps = 0;  // steps kept without coming nearer (gjk_step's Level)
  GjkSavedSimplex<S> level_saved;  // the nearest simplex a Level step left
  bool stalled = false;            // rounding stopped the solver with its gap still wide
  bool near_stall = false;         // ... or with its gap within 4 tolerances
  const bool boolean = margin >= S(0) && stop_within_margin;  // only "distance <= margin?" is asked
  while (out.iterations < max_iterations) {
    const S vv = v.squaredNorm();
    if (vv <= tol2 || (stop_within_margin && margin >= S(0) && vv <= margin * margin)) {  // within the tolerance (or the margin)
      out.intersecting = true;
      converged = true;
      break;
    }
    SimplexPoint<S> p;
    p.a = support_a(Vec3<S>(-v));
    p.b = support_b(v);
    p.w = p.a - p.b;
    ++out.iterations;
    // Duality gap: |v| - lower bounds |v| - distance, lower the best (v . w)/|v| so far (each the
    // distance of a plane separating the sets).
    const S vw = v.dot(p.w);
    if (margin >= S(0) && vw > S(0) && vw * vw > margin * margin * vv) {  // a separating plane beyond the margin
      converged = true;
      break;
    }
    const S len = std::sqrt(vv);
    if (vw > S(0) && vw / len > lower) {
      lower = vw / len;
      lower_v = v;
    }
    if (len - lower <= tolerance) {
      converged = true;
      break;
    }
    // A step whose closest point comes no nearer within rounding still brings a new support point
    // in: kept (a bounded number of times), since near a flat part of the Minkowski difference
    // whose support points are not its vertices (a cap of a cylinder or cone nearly parallel to
    // another flat side) v's progress is second order in the gap, below the rounding of |v|^2,
    // while the gap is first order: stopping there left it at 4e-9 of the size (cylinder caps
    // tilted by 1e-8).
    const GjkStep step = gjk_step(s, n, lambda, v, vv, p, level_steps < kGjkLevelSteps ? &level_saved : nullptr);
    if (step == GjkStep::Progress) continue;
    if (step == GjkStep::Level) {
      ++level_steps;
      continue;
    }
    // a repeated support point or no progress (rounding): v is as close as the arithmetic allows.
    // A stall whose gap |v| - lower is still wider than the tolerance is not converged: the
    // distance may be anywhere in [lower, |v|], and the result says limit_reached (fuzzing: a
    // float box and cone that overlap stalled at |v| = 1.5e-4, 5e-4 of the size, with no
    // separating plane found).
    // In the boolean mode (a margin, stopping within it) a stall decides nothing, however narrow
    // its gap: a separating plane beyond the margin would have stopped the loop above, and |v| is
    // only an upper bound of the distance, so the sets may overlap deeply (fuzzing: a float
    // cylinder and a needle cylinder overlapping by 30 tolerances stalled at |v| = 2.8
    // tolerances with no plane found, and the stall was taken for "apart"). The wider run decides.
    out.intersecting = step == GjkStep::Inside;
    near_stall = len - lower <= S(4) * tolerance;
    converged = out.intersecting || (near_stall && !boolean);
    stalled = !converged;
    break;
  }
  out.limit_reached = !converged;
  if constexpr (!std::is_same_v<S, long double>) {
    // A rounding stall with the gap still wide: the simplex was too ill-conditioned for S (a long
    // thin cone against a small float box stalled at 5e-4 of the size). The same support points are
    // exact in a wider type, so the query runs again there from v, and its answer, when it
    // converges, is this one's (distance and witnesses rounded back to S).
    // The wider run gets what is left of the bound (max_iterations is one budget for the query).
    if (stalled && out.iterations < max_iterations) {
      using W = std::conditional_t<std::is_same_v<S, float>, double, long double>;
      const auto wide_a = [&](const Vec3<W>& d) { return Vec3<W>(support_a(Vec3<S>(d.template cast<S>())).template cast<W>()); };
      const auto wide_b = [&](const Vec3<W>& d) { return Vec3<W>(support_b(Vec3<S>(d.template cast<S>())).template cast<W>()); };
      Vec3<W> wide_plane = Vec3<W>::Zero();
      const ConvexDistance<W> w = gjk_distance<W>(wide_a, wide_b, Vec3<W>(v.template cast<W>()), W(tolerance),
                                                  max_iterations - out.iterations, W(margin), stop_within_margin, &wide_plane);
      out.iterations += w.iterations;  // counted whether or not it decides
      if (!w.limit_reached) {
        if (plane) *plane = wide_plane.squaredNorm() > W(0) ? Vec3<S>(wide_plane.template cast<S>()) : lower_v;
        out.intersecting = w.intersecting;
        out.distance = S(w.distance);
        out.point_a = w.point_a.template cast<S>();
        out.point_b = w.point_b.template cast<S>();
        out.limit_reached = false;
        return out;
      }
    }
  }
  if (boolean && near_stall && !converged) {
    // no wider type decided either: the distance is at most |v| <= lower + 4 tolerances <= the
    // margin + 4 tolerances, so the sets touch within the rounding of the solver
    out.intersecting = true;
    out.limit_reached = false;
  }
  if (level_saved.vv < v.squaredNorm()) {  // Level steps came no nearer in the end: back to the nearest
    n = level_saved.n;
    for (int i = 0; i < n; ++i) {
      s[i] = level_saved.s[i];
      lambda[i] = level_saved.lambda[i];
    }
    v = level_saved.v;
  }
  Vec3<S> pa = Vec3<S>::Zero(), pb = Vec3<S>::Zero();
  for (int i = 0; i < n; ++i) {
    pa += lambda[i] * s[i].a;
    pb += lambda[i] * s[i].b;
  }
  out.point_a = pa;
  out.point_b = pb;
  out.distance = out.intersecting ? S(0) : v.norm();
  if (plane) *plane = lower_v;
  return out;
}

}  // namespace detail
}  // namespace impact
