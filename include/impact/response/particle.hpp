// SPDX-License-Identifier: MIT
/// \file
/// Particle: a point or a small ball moving under the step functions of particle_step.hpp.
#pragma once

#include "impact/core/types.hpp"

#include <cstdint>

namespace impact {

/// A particle: centre position, velocity and radius (0 for a point particle; a ball of that
/// radius otherwise, tested as a swept sphere). Units are the caller's (length, length/time).
template <class S> struct Particle {
  Vec3<S> position = Vec3<S>::Zero();
  Vec3<S> velocity = Vec3<S>::Zero();
  S radius = S(0);  ///< >= 0
  /// Cache kept by the backtracking step: a ball of centres (free_center, free_radius) known to
  /// keep this particle clear of every static backtracking collider, so that legs inside it skip
  /// the collision tests. Moving the particle anywhere is safe (a leg outside the ball is cast as
  /// usual). A negative value is a cool-down radius: no new ball is searched for within it.
  Vec3<S> free_center = Vec3<S>::Zero();
  S free_radius = S(0);
  /// The collider set and radius the ball was found for (a 64-bit digest of the colliders' poses,
  /// shapes, sides, strategies, mesh addresses and mesh revisions, and of this particle's radius):
  /// a step whose digest differs drops the ball, so adding, removing or moving colliders, editing
  /// a mesh's vertices in place (MeshBvh::set_vertices, which takes a new MeshBvh::revision) or
  /// growing the radius needs no reset. (After set_vertices the collider needs refresh(), and its
  /// distance grid and wide tree a rebuild from the edited mesh: they hold copies.) A convex shape's
  /// parameters are seen only through its scale and clearance at seven points: after editing one
  /// in place, set free_radius = 0.
  std::uint64_t free_key = 0;
};

}  // namespace impact
