// SPDX-License-Identifier: MIT
/// \file
/// The options and counters of a particle step (response/particle_step.hpp): which overshooting
/// strategy, gravity, the impact budget, resting, the surface offset, the free-ball cache and the
/// threads of step_particles; and which strategy a collider uses in a step.
#pragma once

#include "impact/core/types.hpp"
#include "impact/response/collider.hpp"

#include <cstddef>

namespace impact {

/// Options of a particle step. The strategy is the system's default; a collider whose own
/// strategy is not Inherit overrides it.
template <class S> struct StepOptions {
  Strategy strategy = Strategy::Backtrack;
  Vec3<S> gravity = Vec3<S>::Zero();  ///< constant acceleration
  /// Backtracking: impacts handled per particle per step; projection: passes over the colliders.
  int max_iterations = 16;
  /// Resting threshold: rest speed = rest_speed + rest_speed_factor * |gravity| * dt.
  S rest_speed = S(0);
  S rest_speed_factor = S(2);
  /// Scale-aware surface offset in units of epsilon(S) (see the file comment).
  S offset_ulps = S(256);
  /// Absolute surface offset; used instead of offset_ulps when > 0.
  S surface_offset = S(0);
  /// Free-ball cache (Particle::free_radius) under backtracking, used when no collider moves and
  /// there is a mesh: when a leg leaves the particle's free ball, a new ball is found from lower
  /// bounds of the distance to every collider (free_ball_at): exact for planes, spheres and boxes,
  /// in O(1) from a mesh's distance grid when it has one (MeshCollider::distance_grid), else from
  /// the mesh's tree, at most free_ball_factor times the leg's length. With grids on every mesh the
  /// ball is first sought near the leg's end (around the centre of the grid cell holding it, the
  /// largest ball that cell's bound gives; it then also holds the legs that follow), else around
  /// its start; a leg is also clear of the meshes, or of the other colliders, when their
  /// balls around both of its ends (and, for grids, its midpoint) cover it. Legs inside the ball
  /// skip every collision test. Conservative (a test is skipped only when no surface is within
  /// the leg's reach); 0 disables it.
  S free_ball_factor = S(8);
  /// Threads of step_particles: <= 0 the hardware concurrency, 1 the serial loop. Particles are
  /// independent within a step, so the particles and the counters do not depend on it (bit for
  /// bit); sets of fewer than 512 particles are stepped serially.
  int threads = 0;
};

/// Counters of one or more particle steps.
struct StepStats {
  std::size_t impacts = 0;            ///< backtracking impacts handled
  std::size_t projections = 0;        ///< projections applied
  std::size_t particles_hit = 0;      ///< particle-steps with at least one impact or projection
  std::size_t budget_exhausted = 0;   ///< particle-steps that ran out of iterations
  void operator+=(const StepStats& o) {
    impacts += o.impacts;
    projections += o.projections;
    particles_hit += o.particles_hit;
    budget_exhausted += o.budget_exhausted;
  }
};

namespace detail {

/// The strategy a collider uses: its own, or the step's when its own is Inherit.
inline Strategy effective(Strategy own, Strategy system) { return own == Strategy::Inherit ? system : own; }

}  // namespace detail
}  // namespace impact
