// SPDX-License-Identifier: MIT
/// \file
/// Material: the surface properties a collider gives to the contacts on it (restitution and
/// Coulomb friction). Each collider carries its own material; particles carry none.
#pragma once

namespace impact {

/// Surface material of a collider.
template <class S> struct Material {
  /// Restitution epsilon in [0, 1]: the normal relative velocity after a contact is -epsilon times
  /// the one before. 1 is a mirror reflection (perfectly elastic), 0 perfectly inelastic.
  S restitution = S(0.5);
  /// Coulomb friction coefficient mu >= 0: the tangential velocity change at a contact is at most
  /// mu times the normal velocity change; below that the particle sticks (static friction).
  S friction = S(0);

  static Material elastic() { return {S(1), S(0)}; }
};

}  // namespace impact
