// SPDX-License-Identifier: MIT
/// \file
/// Where a backtracking particle stands after a hit (response/particle_step.hpp): the surface
/// offset it is backed off by, how far beyond a leg's end the cast reaches, and the check that
/// rounding the backed-off point cannot put it across the hit's tangent plane.
///
/// The offset is scale-aware: offset_ulps * epsilon(S) * (|x|_inf + collider scale + |chord|_inf)
/// unless StepOptions::surface_offset gives it absolutely: 256 ulps is about 3e-5 of the scene's
/// size in float and 6e-14 in double, well above the rounding of a hit point and well below any
/// physical length.
#pragma once

#include "impact/core/types.hpp"
#include "impact/response/particle_step_options.hpp"

#include <algorithm>
#include <limits>

namespace impact {
namespace detail {

/// The surface offset of a hit at x of a collider of the given scale, by a leg of chord d (see the
/// file comment).
template <class S> inline S surface_offset(const StepOptions<S>& o, const Vec3<S>& x, S scale, const Vec3<S>& d) {
  if (o.surface_offset > S(0)) return o.surface_offset;
  return o.offset_ulps * std::numeric_limits<S>::epsilon() * (x.cwiseAbs().maxCoeff() + scale + d.cwiseAbs().maxCoeff()) +
         std::numeric_limits<S>::min();
}

/// How far beyond a leg's end the cast reaches (see step_particle_in): `reach`, the surface offset
/// (surface_offset's formula) and at least 8 ulps of m = |end|_inf + the colliders' largest scale
/// + |chord|_inf; and the cast's t_max, 1 + reach / |chord|_inf (at least `reach` beyond the end;
/// 1 for a zero chord).
template <class S> struct EndReach {
  S reach = S(0);
  S t_max = S(1);
};
template <class S> inline EndReach<S> end_reach(const StepOptions<S>& o, const Vec3<S>& end, const Vec3<S>& chord, S scale) {
  const S eps = std::numeric_limits<S>::epsilon();
  const S c_max = chord.cwiseAbs().maxCoeff();
  const S m = end.cwiseAbs().maxCoeff() + scale + c_max;
  EndReach<S> r;
  r.reach = o.surface_offset > S(0) ? std::max(o.surface_offset, S(8) * eps * m)
                                    : std::max(o.offset_ulps, S(8)) * eps * m + std::numeric_limits<S>::min();
  if (c_max > S(0)) r.t_max = S(1) + r.reach / c_max;
  return r;
}

/// Whether the backed-off point x + s c of a hit leg (0 < s < 1), once rounded, provably stays on
/// the particle's side of the hit's tangent plane when it was `delta` from it: each rounded
/// component is off by at most u (|s c_k| + |x_k + s c_k|) <= u (|x|_inf + 3 |c|_inf) (u = eps / 2,
/// two roundings), so the point moves by at most eps (|x|_inf + 3 |c|_inf) (sqrt(3) u < eps); at
/// least twice that leaves it delta / 2 or more from the plane. The scale-aware offset (256 eps
/// (|hit|_inf + scale + |c|_inf), with |x|_inf <= |hit|_inf + |c|_inf) always passes; only an
/// absolute StepOptions::surface_offset below the coordinates' rounding can fail it.
template <class S> inline bool backoff_rounding_clear(S delta, const Vec3<S>& x, const Vec3<S>& c) {
  return delta >= S(2) * std::numeric_limits<S>::epsilon() * (x.cwiseAbs().maxCoeff() + S(3) * c.cwiseAbs().maxCoeff());
}

}  // namespace detail
}  // namespace impact
