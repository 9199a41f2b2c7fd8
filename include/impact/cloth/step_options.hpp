// SPDX-License-Identifier: MIT
/// \file
/// The interface of cloth_collision_step (cloth/collision_step.hpp): the obstacles of a step
/// (rigid meshes with two poses, kinematic meshes with two vertex arrays), the options of every
/// stage, and the statistics it returns.
#pragma once

#include "impact/ccd/options.hpp"
#include "impact/core/types.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace impact {

/// A rigid obstacle: a triangle mesh in its own frame, placed by `pose0` at the start and `pose1`
/// at the end of the step. Its vertices move linearly between pose0(v) and pose1(v) (the motion
/// model of the CCD; for a rotation over a step this is the chord of the arc). Infinite mass.
/// Non-owning: the mesh must outlive the call.
template <class S>
struct RigidObstacle {
  const TriangleMesh<S>* mesh = nullptr;
  RigidTransform<S> pose0, pose1;
};

/// A kinematic (scripted, possibly deforming) obstacle: its vertices at the start (`x0`) and end
/// (`x1`) of the step and its triangles. Infinite mass. Non-owning.
template <class S>
struct KinematicObstacle {
  const Vertices<S>* x0 = nullptr;
  const Vertices<S>* x1 = nullptr;
  const Faces* faces = nullptr;
};

/// Every obstacle of a step. Obstacles are never tested against each other.
template <class S>
struct ClothObstacles {
  std::vector<RigidObstacle<S>> rigid;
  std::vector<KinematicObstacle<S>> kinematic;
};

/// How the impact zones are resolved (stage 3).
enum class ZoneMethod {
  Harmon,  ///< inelastic projection (Harmon et al. 2008): momentum kept, sliding survives
  /// Rigid impact zones (Provot 1997; Bridson 2002 section 7.4): the zone moves rigidly with
  /// its momentum and angular momentum. A zone held by infinite-mass vertices that do not move
  /// (a static obstacle, pinned vertices) rests with them (x1' = x0); one held by moving
  /// infinite-mass vertices cannot follow them rigidly and is projected like Harmon's.
  Rigid,
};

/// What to do when x0 itself has pairs closer than the thickness.
enum class StartViolation {
  Throw,   ///< InvalidInput naming the pairs (the default); nothing is modified
  Report,  ///< list them in ClothStepStats::start_violations and exclude them from the step
};

/// Options of cloth_collision_step. Lengths are in the units of the coordinates.
template <class S>
struct ClothCollisionOptions {
  /// h > 0: the guaranteed minimum separation of every tested pair over the step.
  S thickness = S(0);
  /// Stage 1: pairs within `proximity_distance` at x0 stop approaching. 0 means 2 h; otherwise it
  /// must be >= h. Also the inflation of the swept boxes (candidates within it are gathered once).
  /// The impulses are relaxed in rounds (Gauss-Seidel, cloth/detail/relax_contacts.hpp) until no
  /// pair approaches by more than `proximity_tolerance` h (> 0), at most `proximity_rounds`
  /// (>= 1; 1 is a single pass over the pairs): resting contact (a stack of sheets on a floor)
  /// is then stopped here, before the CCD stages. A deep stack needs hundreds of rounds (each
  /// carries the stop about one layer further); the default 30 leaves the rest of such a stack
  /// to the CCD impulses and their relaxation, which was cheaper overall on the layers scene
  /// (see docs/cloth-history.md); 500 relaxes shallow stacks to convergence.
  bool proximity = true;
  S proximity_distance = S(0);
  int proximity_rounds = 30;
  S proximity_tolerance = S(1e-3);
  /// Stage 2: at most `impulse_passes` passes of CCD impulses (0 skips the stage).
  /// After each pass its hits join the proximity pairs' constraints and the whole set is relaxed
  /// again for at most `impulse_relax_rounds` rounds (0: the hits' own impulses only).
  bool impulses = true;
  int impulse_passes = 3;
  int impulse_relax_rounds = 10;
  /// Coulomb friction coefficient (>= 0) of the proximity and CCD impulses.
  S friction = S(0.3);
  /// The impulses and zones aim at a separation of (1 + separation_margin) h along the collision
  /// normal at the end of the step, so that resting contact sits a little above h (>= 0).
  S separation_margin = S(0.1);
  /// Stage 3: impact zones, by `zone_method`, at most `max_zone_iterations` rounds of
  /// (CCD, merge, resolve). The projection solver stops when every constraint of a zone is met to
  /// `projection_tolerance` times h, or after `max_projection_iterations` iterations (active-set
  /// changes of the dense solver, Newton steps of the sparse one: ZoneProjectionOptions) (the
  /// zone then goes to the rigid method, then to the fail-safe).
  bool zones = true;
  ZoneMethod zone_method = ZoneMethod::Harmon;
  int max_zone_iterations = 30;
  int max_projection_iterations = 500;
  S projection_tolerance = S(1e-6);
  /// The primitive CCD's tolerance and budgets. min_separation and t_max are set by the step (h
  /// and 1); the rest is used as given by the start check, the zones and the fail-safe. The
  /// impulse passes locate hits only to within separation_margin h / 2 (a larger tolerance per
  /// query, no re-check; see docs/cloth.md): what they do with a hit needs no more.
  CcdOptions ccd{};
  /// x0 closer than h somewhere: throw (default) or report and proceed.
  StartViolation on_start_violation = StartViolation::Throw;
  /// Threads for the batch parts (CCD over the candidates; core/parallel.hpp): 1 is the serial
  /// path, <= 0 the hardware concurrency. The result does not depend on it, bit for bit.
  int threads = 1;
};

/// Time and counts of one stage.
struct ClothStageStats {
  double ms = 0;                ///< wall time
  std::size_t collisions = 0;   ///< pairs that needed a correction in this stage
  int passes = 0;               ///< passes (CCD rounds) run
};

/// One pair of primitives, by global vertex index. Cloth vertices are 0..n-1; the vertices of
/// obstacle k follow (rigid obstacles first, in order, then kinematic ones). Vertex-face:
/// v[0] against the triangle (v[1], v[2], v[3]); edge-edge: (v[0], v[1]) against (v[2], v[3]).
struct ClothPair {
  bool edge_edge = false;
  std::int32_t v[4] = {-1, -1, -1, -1};
};

/// Statistics of one call of cloth_collision_step.
struct ClothStepStats {
  /// Swept tree build/refit and candidate gathering; passes = gatherings (1 unless a vertex
  /// left its envelope during the step, see docs/cloth.md, the broad phase).
  ClothStageStats broad;
  /// collisions = proximity pairs that got an impulse, passes = relaxation rounds
  ClothStageStats proximity;
  ClothStageStats impulses;   ///< collisions = CCD hits handled by impulses, passes = CCD passes
  ClothStageStats zones;      ///< collisions = constraints in zones, passes = zone rounds
  ClothStageStats failsafe;   ///< collisions = hits that froze vertices, passes = its CCD rounds
  double total_ms = 0;
  std::size_t proximity_impulses = 0;  ///< impulses of the proximity stage (all rounds)
  /// The proximity stage's last round applied nothing: every pair within the proximity distance
  /// approaches by at most proximity_tolerance h (false: proximity_rounds ran out first).
  bool proximity_converged = true;
  std::size_t impulse_relax_impulses = 0;  ///< impulses of the relaxations after the CCD impulse passes
  std::size_t candidates_vf = 0, candidates_ee = 0;  ///< primitive pairs after the first gathering
  std::size_t ccd_tests = 0;                         ///< primitive CCD tests run (all stages)
  /// Candidate tests settled without a CCD search: a lower bound on the pair's distance over the
  /// step stays above h (a proof that it never comes within h): its distance at x0 minus its
  /// largest relative vertex displacement, the bound from both ends, a fixed separating direction,
  /// or its distance sampled along the step with the relative motion between samples.
  std::size_t ccd_skipped = 0;
  /// Candidate re-tests avoided after a vertex moved: the pair's proof from an earlier pass of the
  /// step (ccd_skipped) still holds, since its vertices' end positions moved by less than its
  /// lower bound's excess over h in all.
  std::size_t ccd_kept = 0;
  std::size_t zone_count = 0;                        ///< zones resolved (summed over rounds)
  std::size_t largest_zone = 0;                      ///< vertices of the largest zone
  std::size_t rigid_zones = 0;                       ///< zones resolved rigidly (method or fallback)
  /// The zones' momentum error: over the zones of finite-mass vertices only (a zone holding an
  /// obstacle or pinned vertex is legitimately pushed), the largest change of the zone's linear
  /// momentum by its resolution, |sum m (x1' - xhat)| / sum m |xhat - x0| (xhat: the end positions
  /// before the zones; 0 up to rounding for both methods), and of its angular momentum about its
  /// centre of mass c at x0, |sum m (x0 - c) x (x1' - xhat)| / sum m |x0 - c| |xhat - x0|. The
  /// angular one is not 0: Harmon's projection keeps it about the configuration where each
  /// constraint's normal is taken (the contact at the time of impact), not about x0; a rigid
  /// zone's finite rotation keeps it to first order in the rotation angle.
  double zone_momentum_error = 0, zone_angular_momentum_error = 0;
  bool failsafe_used = false;
  std::size_t frozen_vertices = 0;  ///< cloth vertices put back at x0 by the fail-safe
  /// No pair comes within h over the step (see collision_step.hpp); `unresolved` lists the pairs of
  /// scripted (infinite-mass) motion it could not fix when false.
  bool collision_free = true;
  std::vector<ClothPair> unresolved;
  /// With StartViolation::Report: the pairs closer than h at x0 (excluded from the step).
  std::vector<ClothPair> start_violations;
  /// With StartViolation::Report: the triangle pairs (cloth triangles 0..m-1, then each
  /// obstacle's, as in verify_cloth_state) that intersect at x0 with an edge of one through the
  /// other and no vertex-face or edge-edge pair within h / 2 (an intersection with a closer pair
  /// shows in start_violations). The step cannot undo them: they stay.
  std::vector<std::pair<std::int32_t, std::int32_t>> start_intersections;
  /// The start's exact intersection test was not needed: x0 (with the obstacles at their start
  /// poses) is, bit for bit, the end state of the last step in the same workspace, which started
  /// free of intersections and ended collision_free (collision_step.hpp says why that state is
  /// free of intersections). The distances at x0 are checked as always.
  bool start_intersections_known_free = false;
};

}  // namespace impact
