// SPDX-License-Identifier: MIT
/// \file
/// Contact: what the response needs to know about one particle-collider contact, in the world
/// frame. Produced by the colliders' hit and projection queries (collider.hpp), consumed by
/// respond() (response.hpp).
#pragma once

#include "impact/core/types.hpp"
#include "impact/response/material.hpp"

namespace impact {

/// One particle-collider contact.
template <class S> struct Contact {
  /// Fraction of the tested motion at which the contact happens, in [0, 1] (1 for projection).
  S time = S(0);
  Vec3<S> point = Vec3<S>::Zero();              ///< contact point on the collider's surface
  Vec3<S> normal = Vec3<S>::UnitZ();            ///< unit, pointing from the surface to the particle's side
  Vec3<S> collider_velocity = Vec3<S>::Zero();  ///< velocity of the collider's material point at `point`
  Material<S> material;                         ///< the collider's material
  int collider = -1;                            ///< index of the collider in its ColliderSet list
};

}  // namespace impact
