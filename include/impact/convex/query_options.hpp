// SPDX-License-Identifier: MIT
/// \file
/// The options of the convex queries (convex/query.hpp) and the check every query makes before
/// computing anything: its shapes (validate_shape), its poses (validate_pose) and these options,
/// each rejected with InvalidInput. Needs the impact::convex target (libccd).
#pragma once

#include "impact/convex/convex_hull.hpp"
#include "impact/convex/libccd_solver.hpp"
#include "impact/convex/shapes.hpp"
#include "impact/convex/triangle_shape.hpp"
#include "impact/core/config.hpp"
#include "impact/core/validate.hpp"
#include "impact/geometry/transform.hpp"

#include <algorithm>
#include <type_traits>

namespace impact {

template <class S>
struct ConvexQueryOptions {
  /// Bound on the iterations (support calls per shape) of a query; 1 .. 100000. One budget for the
  /// whole query, which the reported iterations count: every stage spends from it (a later run,
  /// retry or fallback gets what the stages before it left): the separating planes, a pair's
  /// closed-form candidates (run only when the most they can make, 1 to 22 by pair, fits in what is
  /// left; else the query goes on without them), GJK, MPR, EPA, libccd's attempts, a capsule's
  /// segment search against a cylinder or a cone, and the refinements of EPA's normal
  /// (convex/certified_pair.hpp: skipped or cut short when they do not fit). An answer the bound
  /// changed says limit_reached: its boolean is then not decided, its numbers still hold
  /// (convex/query.hpp), and its normal may be EPA's unrefined one, which is within only about the
  /// square root of the tolerance of the minimiser where the overlap is smooth (up to 3e-5 rad on
  /// the poses of docs/convex-notes.md, note 32).
  int max_iterations = 512;
  /// Tolerance of the iterative solvers relative to the larger shape's size (shape_size()); in
  /// (0, 0.1]. The default is 1e-10 for double, 1e-5 for float.
  S relative_tolerance = std::is_same_v<S, float> ? S(1e-5) : S(1e-10);
  /// Tolerance of libccd's EPA expansion relative to the larger shape's size (libccd's
  /// epa_tolerance is its square times the size squared), used with libccd_penetration; in (0, 0.1].
  /// The own EPA stops at relative_tolerance.
  S epa_relative_tolerance = std::is_same_v<S, float> ? S(1e-5) : S(1e-8);
  CcdAlgorithm boolean_algorithm = CcdAlgorithm::Mpr;     ///< libccd algorithm of general boolean tests (cylinder–cylinder has its own)
  CcdAlgorithm penetration_algorithm = CcdAlgorithm::Gjk; ///< libccd algorithm of general penetrations (GJK+EPA)
  /// General penetrations through libccd (penetration_algorithm) instead of the library's own EPA
  /// with Newton refinement (convex/epa.hpp), which is the default; libccd also answers when the
  /// own solver meets a degenerate (flat) Minkowski difference.
  bool libccd_penetration = false;
  /// Curved pairs: stop the own EPA at a gap of 1e-3 of the size and refine the normal by Newton's
  /// method (convex/epa.hpp), going on with EPA when the refinement does not verify. Off by
  /// default: on the zoo's cylinders and cones the support's edges (rulings, rims) stop it on most
  /// poses (verified on 10 of 130 cylinder–cylinder penetrations), so it cost more support calls
  /// than it saved (38.9 against 31.5 per query there), while EPA alone closes its gap to 1e-10.
  bool newton_refinement = false;
  /// Cylinder against cylinder or cone, and cone against box: stop EPA early with the local certificate of
  /// convex/local_certificate.hpp (Newton on the closed-form overlap, a certified quadratic lower
  /// bound on a cap of directions about its minimiser, EPA's polytope for the rest); off: EPA to
  /// relative_tolerance alone (the answers agree within relative_tolerance; tested).
  bool local_certificate = true;
};

namespace detail {

template <class S>
void validate_query_options(const ConvexQueryOptions<S>& o, const char* where) {
  if (IMPACT_LIKELY(o.max_iterations >= 1 && o.max_iterations <= 100000 && o.relative_tolerance > S(0) && o.relative_tolerance <= S(0.1) &&
                    o.epa_relative_tolerance > S(0) && o.epa_relative_tolerance <= S(0.1)))
    return;
  validate_in_range(o.max_iterations, 1, 100000, where, "options.max_iterations");
  if (!(o.relative_tolerance > S(0) && o.relative_tolerance <= S(0.1)))
    throw InvalidInput(describe_rejected(where, "options.relative_tolerance", "be in (0, 0.1]", o.relative_tolerance));
  if (!(o.epa_relative_tolerance > S(0) && o.epa_relative_tolerance <= S(0.1)))
    throw InvalidInput(describe_rejected(where, "options.epa_relative_tolerance", "be in (0, 0.1]", o.epa_relative_tolerance));
}

template <class S, class A, class B>
void validate_query(const A& a, const RigidTransform<S>& pa, const B& b, const RigidTransform<S>& pb, const ConvexQueryOptions<S>& o,
                    const char* where) {
  static_assert(is_supported_scalar_v<S>, "convex queries: S must be float or double");
  validate_shape(a, where);
  validate_shape(b, where);
  validate_poses(pa, pb, where, "pose_a", "pose_b");
  validate_query_options(o, where);
}

template <class S, class A, class B>
S query_scale(const A& a, const B& b) {
  return std::max(shape_size(a), shape_size(b));
}

}  // namespace detail
}  // namespace impact
