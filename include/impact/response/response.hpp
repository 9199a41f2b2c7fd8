// SPDX-License-Identifier: MIT
/// \file
/// respond(): the velocity response of a particle at a contact, shared by every strategy
/// (backtracking and projection, particle_step.hpp).
///
/// With the relative velocity u = v - v_c (v_c the collider's velocity at the contact point)
/// split into its normal part u_n = (u . n) n and tangential part u_t = u - u_n:
///  - a separating contact (u . n >= 0) is left unchanged;
///  - otherwise u <- u_t' - epsilon u_n, where u_t' is u_t after Coulomb friction: the normal
///    velocity change is j = (1 + epsilon) |u . n|; if |u_t| <= mu j the particle sticks
///    (u_t' = 0, static friction), else u_t' = u_t (1 - mu j / |u_t|) (kinetic friction);
///  - resting contact: when |u . n| <= rest_speed and the material is not perfectly elastic,
///    epsilon is taken as 0 so that a particle settling under gravity stops bouncing instead of
///    bouncing ever lower (the usual remedy for the Zeno behaviour of restitution models).
/// Then v <- v_c + u. Exact up to rounding; with epsilon = 1 and mu = 0 it preserves |u|.
#pragma once

#include "impact/response/contact.hpp"

#include <cmath>

namespace impact {

/// Options of respond().
template <class S> struct ResponseOptions {
  /// Normal approach speeds at or below this are treated as resting contact (restitution 0) for
  /// materials with restitution < 1. 0 disables it.
  S rest_speed = S(0);
};

/// Result of respond().
template <class S> struct ResponseResult {
  Vec3<S> velocity = Vec3<S>::Zero();  ///< the new particle velocity
  S normal_impulse = S(0);             ///< normal velocity change per unit mass, >= 0
  bool approaching = false;            ///< false for separating contacts (velocity unchanged)
  bool resting = false;                ///< the contact was treated as resting (restitution 0)
  bool sticking = false;               ///< static friction removed the tangential velocity
};

/// The new velocity of a particle with velocity v at a contact with unit normal n (pointing
/// towards the particle), collider velocity vc and material m. See the file comment.
template <class S>
ResponseResult<S> respond(const Vec3<S>& v, const Vec3<S>& n, const Vec3<S>& vc, const Material<S>& m,
                          const ResponseOptions<S>& options = {}) {
  ResponseResult<S> r;
  const Vec3<S> u = v - vc;
  const S un = u.dot(n);
  if (!(un < S(0))) {
    r.velocity = v;
    return r;
  }
  r.approaching = true;
  S eps = m.restitution;
  if (eps < S(1) && -un <= options.rest_speed) {
    eps = S(0);
    r.resting = true;
  }
  const Vec3<S> ut = u - un * n;
  const S j = (S(1) + eps) * (-un);
  r.normal_impulse = j;
  Vec3<S> ut_new = ut;
  if (m.friction > S(0)) {
    const S len = ut.norm();
    const S limit = m.friction * j;
    if (len <= limit) {
      ut_new.setZero();
      r.sticking = true;
    } else {
      ut_new = ut * (S(1) - limit / len);
    }
  }
  r.velocity = vc + ut_new - eps * un * n;
  return r;
}

/// Convenience overload taking a Contact.
template <class S> ResponseResult<S> respond(const Vec3<S>& v, const Contact<S>& c, const ResponseOptions<S>& options = {}) {
  return respond(v, c.normal, c.collider_velocity, c.material, options);
}

}  // namespace impact
