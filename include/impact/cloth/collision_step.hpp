// SPDX-License-Identifier: MIT
/// \file
/// cloth_collision_step: the collision step of a deforming triangle mesh (cloth, shells, any
/// number of components, open or closed) that works with any integrator, after Bridson, Fedkiw
/// and Anderson 2002 ("Robust treatment of collisions, contact and friction for cloth animation")
/// and Harmon, Vouga, Tamstorf and Grinspun 2008 ("Robust treatment of simultaneous collisions").
///
/// The integrator proposes end positions x1 for start positions x0 (velocities (x1 - x0) / dt);
/// the step corrects x1 in place into x1' such that on the linear motion x0 -> x1' no vertex-face
/// or edge-edge pair (cloth against itself, against other cloth components, against obstacles)
/// comes within the thickness h at any time. Obstacles move on their own (infinite mass): rigid
/// meshes with a start and an end pose, and kinematic meshes given by their vertices at both ends.
///
/// Stages, in order, each switchable and counted in ClothStepStats:
///  1. proximity (Bridson 2002, section 7.1): pairs closer than the proximity distance at x0 get an
///     inelastic normal impulse (they stop approaching) and Coulomb friction, relaxed in rounds
///     until no pair approaches (cloth/detail/relax_contacts.hpp), so that resting contact (a
///     stack of sheets) is settled here and not by the CCD stages;
///  2. CCD impulses (Bridson 2002, section 7.2): passes over the CCD hits with minimum separation h,
///     earliest first, each an inelastic impulse with Coulomb friction; a bounded number of passes;
///  3. impact zones: the remaining collisions are grouped into zones (merged when they share a
///     movable vertex); ZoneMethod::Harmon projects each zone's end positions onto the set where
///     every collision in it is separated along its normal, with the smallest mass-weighted change
///     (an inequality-constrained QP solved to convergence, cloth/zone_projection.hpp); it keeps the
///     zone's linear and angular momentum and lets tangential sliding survive. ZoneMethod::Rigid
///     moves each zone rigidly with its momentum and angular momentum (Provot 1997). CCD runs again
///     after each round; zones grow and merge until no collision is left or the rounds run out;
///  4. fail-safe, always on: while the conservative CCD still reports a collision, the movable
///     vertices of the colliding pairs are put back at x0 (they stay where they were, which was
///     collision-free). This ends in at most as many rounds as there are vertices.
///
/// Guarantee: on return, ClothStepStats::collision_free says that no pair of x0 -> x1' comes
/// within h: every pair that could (its primitives' envelopes overlap; the envelopes hold every
/// position of the step, and a vertex leaving its envelope makes the step gather again) was either
/// proved safe by a distance bound (e.g. its distance at x0 minus the largest difference of its
/// vertices' displacements stays above h, with a rounding margin; a bound from an earlier pass
/// counts while its margin covers the vertices' moves since) or cleared by the final
/// conservative CCD (minimum separation h, no false negatives), excluding only pairs whose every
/// vertex has infinite mass (obstacle against obstacle is never tested; pinned-only cloth pairs
/// are counted in `unresolved`, since nothing can move them). It is false only when a scripted
/// motion (pinned vertices, obstacles) itself drives into the cloth where the cloth cannot move
/// out of the way; the pairs are then listed.
///
/// Threads: stateless apart from the optional workspace; distinct calls with distinct outputs
/// and workspaces may run concurrently.
#pragma once

#include "impact/ccd/mesh_ccd.hpp"
#include "impact/ccd/options.hpp"
#include "impact/cloth/detail/step_assembly.hpp"
#include "impact/cloth/detail/step_bounds.hpp"
#include "impact/cloth/detail/step_contacts.hpp"
#include "impact/cloth/detail/step_gathering.hpp"
#include "impact/cloth/detail/step_passes.hpp"
#include "impact/cloth/detail/step_stages.hpp"
#include "impact/cloth/detail/step_zones.hpp"
#include "impact/cloth/detail/stepper.hpp"
#include "impact/cloth/detail/validate_step.hpp"
#include "impact/cloth/step_options.hpp"
#include "impact/core/error.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace impact {

/// Workspace kept between steps of the same mesh and obstacles: the swept tree is refitted, not
/// rebuilt, when the triangles are unchanged. Optional; one per simulation, not shared between
/// threads.
template <class S>
class ClothCollisionWorkspace {
 public:
  detail::cloth::System<S> system;
};

/// The collision step. Inputs: the cloth's triangles `F` over vertices 0..n-1 (n = x0.rows());
/// `inverse_mass` (n entries, >= 0 and finite; 0 = infinite mass: pinned or scripted, such a
/// vertex is never moved); the start positions `x0` (n x 3), the candidate end positions `x1`
/// (n x 3, replaced by the corrected x1'); the obstacles; the options. Optional `workspace` to
/// refit instead of rebuilding between steps.
/// Throws InvalidInput, with nothing modified, on: sizes that do not match, out-of-range indices,
/// NaN/Inf coordinates or masses, negative masses, h <= 0 or NaN, proximity_distance in (0, h),
/// proximity_rounds < 1, proximity_tolerance <= 0, negative counts or friction; and
/// (StartViolation::Throw) an x0 that is not a valid start:
///  - two triangles intersect (cloth against itself or an obstacle; adjacent triangles may share
///    only their common vertex or edge, as in verify_cloth_state): the message names the two
///    triangles (cloth triangles 0..m-1, then each obstacle's). The start's gathering tests each
///    triangle pair it visits exactly (the library's exact predicates) when a cheap, rounding-safe
///    filter cannot rule out an edge of one passing through the other with its ends more than
///    h / 2 from the other's plane; every other intersection has a vertex-face or edge-edge pair
///    within h / 2, which the next check reports (cloth/detail/start_intersections.hpp);
///  - a tested vertex-face or edge-edge pair closer than h: the message names the first pairs.
/// With StartViolation::Report both are listed (start_intersections, start_violations) and the
/// step proceeds; it cannot undo an intersection. A start free of intersections stays free: two
/// triangles can only begin to intersect through a vertex-face or edge-edge contact, which the
/// step keeps at least h apart. So with a workspace, an x0 that is bit for bit the end state of
/// the last step (obstacles included), when that step started free of intersections and ended
/// collision_free with no start pair excluded, skips the intersection test
/// (ClothStepStats::start_intersections_known_free; cloth/detail/step_gathering.hpp, check_pierce).
/// Returns the statistics; see the file comment for the guarantee.
template <class S>
ClothStepStats cloth_collision_step(const Faces& F, const Eigen::Matrix<S, Eigen::Dynamic, 1>& inverse_mass, const Vertices<S>& x0,
                                    Vertices<S>& x1, const ClothObstacles<S>& obstacles, const ClothCollisionOptions<S>& opt,
                                    ClothCollisionWorkspace<S>* workspace = nullptr) {
  static_assert(is_supported_scalar_v<S>, "cloth_collision_step: S must be float or double");
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  detail::cloth::validate_step(F, inverse_mass, x0, x1, obstacles, opt);

  ClothCollisionWorkspace<S> local;
  detail::cloth::System<S>& sys = workspace ? workspace->system : local.system;
  ClothStepStats stats;
  detail::cloth::Stepper<S> step(sys, opt, stats);
  step.assemble(F, inverse_mass, x0, x1, obstacles);
  step.check_start();  // throws before anything is modified
  if (opt.proximity) step.proximity_stage();
  if (opt.impulses && opt.impulse_passes > 0) step.impulse_stage();
  if (opt.zones && opt.max_zone_iterations > 0) step.zone_stage();
  step.failsafe_stage();
  step.note_end();
  step.write_back(x1);
  stats.total_ms = std::chrono::duration<double, std::milli>(Clock::now() - t_start).count();
  return stats;
}

}  // namespace impact
